"""A render farm task's Blender half: renders a chunk of frames with
material SSS off and writes, per frame, the passes (a multilayer EXR) and
the scene description beside them, for the `sss` command to scatter on the
worker. The farm templates (farm/openjd/sss_job.yaml, farm/flamenco/sss.js)
run it in `blender -b SHOT.blend` through a short --python-expr that imports
the add-on from a checkout or from the installed add-on or extension:

    ... -- --passes DIR/NAME_####.exr --frames 1-3,7 [--done OUT_####.exr]
           [--samples N] [--method NAME]

A frame is skipped when its passes exist (they are written to a temporary
name and renamed, so an existing file is whole) or when its --done output
exists (already scattered): a re-queued task renders only what is missing.
A frame that fails is reported and the others are still rendered; the
exit status is then 1.
"""
import argparse
import os
import shutil
import sys
import tempfile
import time

import bpy

from . import native, pipeline
from .errors import SSSError


def parse_frames(text):
    """"1-3,7" -> [1, 2, 3, 7] (the frame lists OpenJD's chunks and
    Flamenco's frameChunker give)."""
    frames = []
    for part in text.replace(" ", "").split(","):
        a, sep, b = part.partition("-")
        try:
            lo, hi = int(a), int(b) if sep else int(a)
        except ValueError:
            raise SystemExit(f"farm: bad --frames '{text}': expected "
                             "A, A-B or a comma-separated list") from None
        if hi < lo:
            raise SystemExit(f"farm: bad --frames '{text}': {hi} < {lo}")
        frames.extend(range(lo, hi + 1))
    return frames


def frame_path(pattern, frame):
    n = pattern.count("#")
    if n == 0:
        raise SystemExit(f"farm: '{pattern}' needs #### for the frame "
                         "number")
    return pattern.replace("#" * n, f"{frame:0{n}d}")


def scene_json_for(passes):
    """The scene description written beside a frame's passes."""
    return os.path.splitext(passes)[0] + "_scene.json"


def parse_args(argv):
    p = argparse.ArgumentParser(prog="separable_sss.farm")
    p.add_argument("--passes", required=True,
                   help="the passes per frame, with #### (DIR/NAME_####.exr)")
    p.add_argument("--frames", required=True, help="1-3,7")
    p.add_argument("--done", help="the scattered output per frame, with "
                   "####: a frame whose output exists is not rendered")
    p.add_argument("--samples", type=int)
    p.add_argument("--method", choices=[n for n, _ in native.methods()])
    args = p.parse_args(argv)
    args.frames = parse_frames(args.frames)
    return args


def _move(src, dst):
    """Renames src to dst, through a temporary beside dst when they lie on
    different file systems: dst appears whole or not at all."""
    try:
        os.replace(src, dst)
    except OSError:
        tmp = dst + ".tmp"
        shutil.copyfile(src, tmp)
        os.replace(tmp, dst)
        os.remove(src)


def render_frame(context, frame, passes):
    """Renders one frame's passes into `passes`, its description beside."""
    scene = context.scene
    scene.frame_set(frame)
    t0 = time.monotonic()
    job = pipeline.prepare_render(context)
    # The description first: existing passes mean a complete frame.
    _move(job.scene_json, scene_json_for(passes))
    _move(job.input_exr, passes)
    return f"{passes} (render {time.monotonic() - t0:.2f} s; {job.summary})"


def main(argv=None):
    if argv is None:
        argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv \
            else []
    args = parse_args(argv)
    package = sys.modules[__package__]
    registered = hasattr(bpy.types.Scene, "sss")
    if not registered:
        package.register()
    # Which add-on and library this worker runs, for the task's log.
    print(f"farm: add-on {__package__} ({os.path.dirname(__file__)}), "
          f"library {native.loaded_path()}", flush=True)
    scene = bpy.context.scene
    # Settings given on the command line apply to this run only (the .blend
    # is never saved).
    if args.samples:
        scene.cycles.samples = args.samples
    if args.method:
        scene.sss.method = args.method.upper().replace("-", "_")

    first = os.path.abspath(frame_path(args.passes, args.frames[0]))
    os.makedirs(os.path.dirname(first), exist_ok=True)
    # The add-on's own working files go to a private folder beside the
    # passes (same file system: the final rename is atomic), never to a
    # folder that another task on this machine also uses.
    work = tempfile.mkdtemp(prefix=".sss-work-", dir=os.path.dirname(first))
    saved_dir = scene.sss.output_dir
    scene.sss.output_dir = work
    failed = 0
    try:
        for frame in args.frames:
            passes = os.path.abspath(frame_path(args.passes, frame))
            done = args.done and frame_path(args.done, frame)
            if os.path.exists(passes) or (done and os.path.exists(done)):
                print(f"farm: frame {frame}: "
                      f"{passes if os.path.exists(passes) else done} exists, "
                      "skipped", flush=True)
                continue
            os.makedirs(os.path.dirname(passes), exist_ok=True)
            try:
                print(f"farm: frame {frame}: "
                      f"{render_frame(bpy.context, frame, passes)}",
                      flush=True)
            except (SSSError, OSError) as e:
                failed += 1
                print(f"farm: frame {frame}: error: {e}", file=sys.stderr,
                      flush=True)
    finally:
        scene.sss.output_dir = saved_dir
        shutil.rmtree(work, ignore_errors=True)
        if not registered:
            package.unregister()
    if failed:
        print(f"farm: {failed} of {len(args.frames)} frame(s) failed",
              file=sys.stderr, flush=True)
        sys.exit(1)
