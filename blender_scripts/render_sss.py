"""Render a .blend with screen-space SSS, headless, from a checkout.

    blender -b SCENE.blend --python-exit-code 1 --python blender_scripts/render_sss.py -- \
        --output OUT.exr [--frames A-B] [--samples N] \
        [--method NAME (one of the library's: sss --help lists them)] \
        [--resolution WxH] [--radius-scale F]

Per frame: renders with material SSS switched off (restored afterwards),
and writes OUT (#### is replaced by the frame number; without #### and with
several frames, _NNNN is appended) as a multilayer EXR holding every pass
plus the SSS layer (SSS.Combined, SSS.DiffLight), with the scene
description JSON beside it (OUT_scene.json). Uses the add-on from this
checkout and build/libsss.so (run make first); nothing needs installing.
"""
import argparse
import os
import shutil
import sys
import time

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "addon"))
sys.path.insert(0, HERE)

from script_cli import run_main, script_argv  # noqa: E402
from separable_sss import native  # noqa: E402


def parse_args():
    argv = script_argv()
    p = argparse.ArgumentParser(prog="render_sss.py")
    p.add_argument("--output", required=True)
    p.add_argument("--frames", help="A-B or A (default: the current frame)")
    p.add_argument("--samples", type=int)
    p.add_argument("--method", choices=[name for name, _ in
                                        native.methods()])
    p.add_argument("--resolution", help="WxH")
    p.add_argument("--radius-scale", type=float)
    args = p.parse_args(argv)
    if args.frames:
        a, _, b = args.frames.partition("-")
        args.frames = range(int(a), int(b or a) + 1)
    if args.resolution:
        w, _, h = args.resolution.partition("x")
        args.resolution = (int(w), int(h))
    return args


def frame_output(pattern, frame, many):
    if "#" in pattern:
        n = pattern.count("#")
        return pattern.replace("#" * n, f"{frame:0{n}d}")
    if many:
        root, ext = os.path.splitext(pattern)
        return f"{root}_{frame:04d}{ext}"
    return pattern


def main():
    args = parse_args()
    import separable_sss
    from separable_sss import pipeline
    separable_sss.register()

    scene = bpy.context.scene
    # Render settings given on the command line apply to this run only
    # (the .blend is never saved).
    if args.samples:
        scene.cycles.samples = args.samples
    if args.resolution:
        scene.render.resolution_x, scene.render.resolution_y = \
            args.resolution
        scene.render.resolution_percentage = 100
    if args.method:
        scene.sss.method = args.method.upper().replace("-", "_")
    if args.radius_scale is not None:
        scene.sss.radius_scale = args.radius_scale

    frames = list(args.frames or [scene.frame_current])
    failed = 0
    for frame in frames:
        scene.frame_set(frame)
        out = os.path.abspath(frame_output(args.output, frame,
                                           len(frames) > 1))
        os.makedirs(os.path.dirname(out), exist_ok=True)
        t0 = time.monotonic()
        try:
            job = pipeline.prepare_render(bpy.context)
            render_s = time.monotonic() - t0
            job.output_exr = out
            pipeline.scatter(job)
            root = os.path.splitext(out)[0]
            shutil.copyfile(job.scene_json, root + "_scene.json")
            print(f"render_sss: frame {frame}: {out} (render {render_s:.2f} "
                  f"s, {pipeline.timings_text(job)}; {job.summary})",
                  flush=True)
        except pipeline.SSSError as e:
            failed += 1
            print(f"render_sss: frame {frame}: error: {e}", file=sys.stderr,
                  flush=True)
    separable_sss.unregister()
    if failed:
        sys.exit(1)


run_main(main)
