"""Measure the speed/accuracy trade of libsss against Cycles' random-walk
SSS and EEVEE's own SSS, on one .blend, headless.

    blender -b --python-exit-code 1 --python blender_scripts/compare.py -- \\
        --scene SCENE.blend --out DIR [--quick] [--no-eevee] [--no-denoise]
        [--resolution WxH] [--rw-samples 16,64,256,1024]
        [--samples 16,64,256] [--eevee-samples 64] [--name NAME]

Renders, all in this one run (so every time is measured on the same
machine under the same load):
- Cycles with the materials' random-walk SSS at each --rw-samples count;
  the highest count is the reference: two renders of half as many samples
  with two other seeds, averaged, so that its own noise is measured and
  taken out of every error (rmse_c, compare_metrics.py);
- Cycles with material SSS switched off (the add-on's switched_off) at each
  --samples count, then each method the library accepts (enumerated at run
  time: a method the library answers SSS_ERR_UNSUPPORTED is skipped with a
  message) on those passes, through the add-on's native binding;
- OIDN (Blender's compositor Denoise node, with the render's albedo and
  normal) on the random walk, on SSS off and on the default method at each
  of their sample counts ("+oidn" rows; skipped where the node does not
  denoise: a Blender built without OpenImageDenoise);
- EEVEE with its own SSS, and EEVEE with SSS off plus each method. EEVEE
  3.4 has no Material Index pass: each scattering material gets a value AOV
  output ("SSSCovN", 1 on that material) for the render; the pixel's index
  is the material with the largest coverage if that is >= 0.5, written into
  the pass file as IndexMA, beside EEVEE's Depth, Diffuse Light/Colour,
  Specular Light/Colour, Emission and Environment (which the library reads
  as DiffDir, DiffCol, GlossDir, GlossCol, Emit, Env). EEVEE needs an
  OpenGL context: without $DISPLAY the script re-runs itself under
  xvfb-run, and skips EEVEE with a message where there is none.

Writes into DIR: sheet.png (contact sheet: one crop and one exposure for
every image, each labelled, with its error heat-map against the reference
below it), results.csv and results.md (one row per image: scene, renderer,
method, samples, render and post-process seconds, RMSE and relative MAE
over the scattering pixels at full and at quarter resolution, SSIM, max
error; metrics in compare_metrics.py), plot.png (error against total time,
log axes, one line per method) and summary.txt (also in results.md): per
sample count, the error reduction of the best and of the default method
against the no-SSS render at the same samples (also both denoised), and
the random-walk sample count reaching the same error, with both times,
and up to what wall time ours + OIDN is ahead of the denoised random walk
(compare_metrics.equal_time: the walk's curve interpolated in log time);
time.png (that trade: error at quarter resolution against wall time,
render + post-process + OIDN, the walk's curve and ours').

The .blend is opened, never saved; the add-on restores what it switches
off. --quick: 160x120, random walk 16/64/256 (reference 256), our methods
on 16 and 64 samples, EEVEE 16 samples.
"""
import argparse
import os
import shutil
import subprocess
import sys
import time
import traceback

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
# (compare_runs puts the add-on on sys.path)
from compare_runs import (ROOT, Bench, denoise_rows,  # noqa: E402
                          library_methods, log, open_scene, run_eevee,
                          run_rw, run_sss_off)
import separable_sss  # noqa: E402
from separable_sss import blender_compat as compat  # noqa: E402
from separable_sss import description, native, pipeline  # noqa: E402

from compare_figures import contact_sheet, plot, time_plot  # noqa: E402
from compare_report import score, summarise, write_tables  # noqa: E402
import mesh_check  # noqa: E402
from script_cli import run_main, script_argv  # noqa: E402


def parse_args():
    argv = script_argv()
    p = argparse.ArgumentParser(prog="compare.py")
    p.add_argument("--scene", required=True, help=".blend to compare on")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--quick", action="store_true")
    p.add_argument("--name", help="scene name in the tables (default: the "
                   "file's name)")
    p.add_argument("--resolution", help="WxH (default 320x240; quick "
                   "160x120)")
    p.add_argument("--rw-samples", help="random-walk sample counts, the "
                   "highest is the reference (default 16,64,256,1024)")
    p.add_argument("--samples", help="sample counts of the SSS-off renders "
                   "(default 16,64,256)")
    p.add_argument("--eevee-samples", type=int)
    p.add_argument("--no-eevee", action="store_true")
    p.add_argument("--no-denoise", action="store_true",
                   help="no OIDN rows (the random walk, SSS off and the "
                   "default method, each denoised)")
    args = p.parse_args(argv)
    q = args.quick

    def ints(text, default):
        return sorted({int(x) for x in (text or default).split(",")})
    args.rw_samples = ints(args.rw_samples, "16,64,256" if q else
                           "16,64,256,1024")
    args.samples = ints(args.samples, "16,64" if q else "16,64,256")
    if len(args.rw_samples) < 2:
        p.error("--rw-samples needs at least two counts")
    args.eevee_samples = args.eevee_samples or (16 if q else 64)
    w, _, h = (args.resolution or ("160x120" if q else "320x240")) \
        .partition("x")
    args.resolution = (int(w), int(h))
    args.scene = os.path.abspath(args.scene)
    args.out = os.path.abspath(args.out)
    args.name = args.name or os.path.splitext(os.path.basename(
        args.scene))[0]
    return args


def maybe_reexec_with_display(args):
    """EEVEE renders need an X display even in background mode."""
    if args.no_eevee or os.environ.get("DISPLAY") or \
            os.environ.get("SSS_COMPARE_XVFB"):
        return
    xvfb = shutil.which("xvfb-run")
    if not xvfb:
        log("no $DISPLAY and no xvfb-run: EEVEE is skipped")
        args.no_eevee = True
        return
    env = dict(os.environ, SSS_COMPARE_XVFB="1")
    cmd = [xvfb, "-a", "-s", "-screen 0 640x480x24",
           compat.blender_command()] + sys.argv[1:]
    log("no $DISPLAY: running again under xvfb-run for EEVEE")
    sys.stdout.flush()
    sys.exit(subprocess.call(cmd, env=env))


# ------------------------------------------------------------------ main

def main():
    args = parse_args()
    maybe_reexec_with_display(args)
    os.environ.setdefault("SSS_LIB", os.path.join(ROOT, "build",
                                                  "libsss.so"))
    separable_sss.register()
    log(f"{args.name}: libsss {native.version()}, {args.resolution[0]}x"
        f"{args.resolution[1]}, random walk {args.rw_samples}, SSS off "
        f"{args.samples}, EEVEE "
        f"{'off' if args.no_eevee else args.eevee_samples}")
    t_start = time.perf_counter()
    bench = Bench(args)
    bench.methods = library_methods()
    scene = open_scene(args, "CYCLES")
    bench.default_method = description.method_name(scene.sss.method)
    bench.mesh_notes = mesh_check.notes(
        scene, [f.material for f in pipeline.analyse(scene).materials])
    for note in bench.mesh_notes:
        log(f"{args.name}: note: {note}")
    run_rw(bench, args)
    run_sss_off(bench, args)
    if not args.no_denoise:
        denoise_rows(bench, args)
    if not args.no_eevee:
        try:
            run_eevee(bench, args)
        except Exception as e:  # keep the Cycles results
            traceback.print_exc()
            bench.skipped.append(f"EEVEE failed: {e}")
            log(f"EEVEE failed: {e}")
    score(bench, args)
    summary = summarise(bench, args)
    contact_sheet(bench, args, os.path.join(args.out, "sheet.png"))
    plot(bench, args, os.path.join(args.out, "plot.png"))
    time_plot(bench, args, os.path.join(args.out, "time.png"))
    write_tables(bench, args, summary)
    for line in summary:
        print(line)
    log(f"wrote {args.out}/results.csv, results.md, sheet.png, plot.png, "
        f"time.png "
        f"({time.perf_counter() - t_start:.0f} s)")
    if os.environ.get("SSS_COMPARE_KEEP_WORK") != "1":
        shutil.rmtree(bench.work, ignore_errors=True)
    separable_sss.unregister()


if __name__ == "__main__":
    run_main(main)
