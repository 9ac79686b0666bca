"""What Screen-space SSS adds to a render: one frame of a scene rendered
as F12 and `blender -b -f` render it (bpy.ops.render.render on the main
thread, write_still), timed inside Blender, with the scene's switch on or
off. Run by bench/run_bench.py:

    blender -b SCENE.blend --python-exit-code 1 --python bench/blender_f12.py -- \
        --sss on|off|plain --size 1920 1080 --samples 64 --out DIR

plain: the switch off and the materials' own SSS switched off, with the
passes the library reads: the render Screen-space SSS itself runs, so
`on` minus `plain` is what the add-on adds (the library, its files, the
back-light layer).

Uses the add-on from this checkout and $SSS_LIB. Prints
`f12_seconds=S layer=yes|no` (layer: whether the back-light view layer
was rendered)."""
import argparse
import os
import sys
import time

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "addon"))
sys.path.insert(0, os.path.join(HERE, "..", "blender_scripts"))

from script_cli import run_main, script_argv  # noqa: E402
import separable_sss  # noqa: E402
from separable_sss import pipeline, transmission  # noqa: E402
from separable_sss.switch_off import switched_off  # noqa: E402


def main():
    p = argparse.ArgumentParser(prog="blender_f12.py")
    p.add_argument("--sss", choices=("on", "off", "plain"), required=True)
    p.add_argument("--size", type=int, nargs=2, default=(1920, 1080))
    p.add_argument("--samples", type=int, default=64)
    p.add_argument("--out", required=True)
    args = p.parse_args(script_argv())
    separable_sss.register()
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = args.size
    scene.render.resolution_percentage = 100
    scene.cycles.samples = args.samples
    scene.render.image_settings.file_format = "PNG"
    scene.render.filepath = os.path.join(args.out, f"f12_{args.sss}")
    scene.sss.enabled = args.sss == "on"
    analysis = pipeline.analyse(scene)
    layer, _why = transmission.wanted(scene, analysis)
    t0 = time.perf_counter()
    if args.sss == "plain":
        with switched_off(scene, analysis, backlight=False):
            bpy.ops.render.render(write_still=True)
    else:
        bpy.ops.render.render(write_still=True)
    seconds = time.perf_counter() - t0
    print(f"f12_seconds={seconds:.3f} layer="
          f"{'yes' if layer and args.sss == 'on' else 'no'}", flush=True)


run_main(main)
