"""A live re-tune, as an artist meets it: a scene rendered once with Render
with SSS, then the first scattering material's Subsurface Scale (3.x:
Subsurface) changed and Apply SSS to Last Render run, five times, each
timed inside Blender (the operator's whole call: the scene described
again, the kept passes scattered, the pixels pushed into the compositor's
image). Run by bench/run_bench.py:

    blender -b SCENE.blend --python-exit-code 1 --python bench/blender_retune.py -- \
        --size 1920 1080 --samples 1 --out DIR [--repeat 5]

Uses the add-on from this checkout and $SSS_LIB. Prints
`retune_seconds=MEDIAN scatter_seconds=MEDIAN render_seconds=S
size=WxH` (scatter: the library's part of each re-tune)."""
import argparse
import os
import statistics
import sys
import time

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "addon"))
sys.path.insert(0, os.path.join(HERE, "..", "blender_scripts"))

from script_cli import run_main, script_argv  # noqa: E402
import separable_sss  # noqa: E402
from separable_sss import blender_compat as compat  # noqa: E402
from separable_sss import live, pipeline  # noqa: E402


def main():
    p = argparse.ArgumentParser(prog="blender_retune.py")
    p.add_argument("--size", type=int, nargs=2, default=(1920, 1080))
    p.add_argument("--samples", type=int, default=1)
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--out", required=True)
    args = p.parse_args(script_argv())
    separable_sss.register()
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = args.size
    scene.render.resolution_percentage = 100
    scene.cycles.samples = args.samples
    scene.sss.output_dir = args.out
    t0 = time.perf_counter()
    if bpy.ops.sss.render() != {'FINISHED'}:
        raise RuntimeError("Render with SSS failed")
    render = time.perf_counter() - t0
    sock = compat.radius_factor_input(pipeline.analyse(scene).materials[0].node)
    base = sock.default_value
    totals, scatters = [], []
    for i in range(args.repeat):
        sock.default_value = base * (1.5 + 0.25 * i)
        t0 = time.perf_counter()
        if bpy.ops.sss.apply() != {'FINISHED'}:
            raise RuntimeError("Apply SSS to Last Render failed")
        totals.append(time.perf_counter() - t0)
        scatters.append(live.kept(scene).timings["scatter"])
    print(f"retune_seconds={statistics.median(totals):.4f} "
          f"scatter_seconds={statistics.median(scatters):.4f} "
          f"render_seconds={render:.2f} size={args.size[0]}x{args.size[1]}",
          flush=True)


run_main(main)
