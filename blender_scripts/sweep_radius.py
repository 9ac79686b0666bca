"""Never worse than no SSS, from a vanishing radius to one far larger than
the objects: one scene rendered with every scattering material's
Subsurface radius scaled by each of a range of factors, headless.

    blender -b --python-exit-code 1 --python blender_scripts/sweep_radius.py \\
        -- --scene SCENE.blend --out DIR [--scales 1e-6,1e-4,...,1e3]
        [--resolution 160x120] [--ref-samples 256] [--samples 64]
        [--name NAME] [--keep-work]

For each scale, in this one run: Cycles' random walk at --ref-samples
(the reference: two renders of half as many samples with two other seeds,
averaged), Cycles with material SSS off at each --samples count, and the
scene's default method on those passes (the add-on's own pipeline, as
compare.py). The error is compare.py's rmse_c: RMSE over the scattering
pixels against the noise-free image the reference estimates (its own
noise taken out), at full and at quarter resolution (where the renders'
noise averages away and the bias stays).

Writes into DIR (and with --keep-work each scale's renders and scene
descriptions into DIR/work/xSCALE): sweep.csv, sweep.md (one row per scale and sample
count: the largest radius in metres, the kernel's half-width in pixels on
the nearest scattering object, both errors without and with our method,
their ratio at quarter resolution (never worse: at most 1), how far ours
is from the render without SSS, and the random walk's mean over that
render's per channel) and sweep.png (both errors and their ratio against
the scale, the never-worse line drawn).

Screen space sees one side of each object: once light scatters about as
far as the objects are thick, the random walk carries it through them and
out of sides the camera does not see. The sweep shows what that does to
the error for the scene's geometry and lights. The .blend is opened,
never saved.
"""
import argparse
import csv
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import compare_runs as compare  # noqa: E402  (puts the add-on on sys.path)
from separable_sss import blender_compat as compat  # noqa: E402
import compare_metrics as cm  # noqa: E402
import numpy as np  # noqa: E402
from exr_io import read_exr  # noqa: E402
from script_cli import run_main, script_argv  # noqa: E402

COLUMNS = ("scene", "scale", "radius_m", "kernel_px", "samples",
           "rmse_no_sss", "rmse_ours", "cut", "rmse_q_no_sss",
           "rmse_q_ours", "cut_q", "ratio_q", "ours_vs_plain",
           "rw_over_plain", "render_s", "post_s")
DEFAULT_SCALES = "1e-6,1e-4,1e-2,0.1,0.3,1,3,10,100,1000"


def log(*a):
    print("sweep:", *a, flush=True)


def parse_args():
    argv = script_argv()
    p = argparse.ArgumentParser(prog="sweep_radius.py")
    p.add_argument("--scene", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--name")
    p.add_argument("--scales", default=DEFAULT_SCALES)
    p.add_argument("--resolution", default="160x120")
    p.add_argument("--ref-samples", type=int, default=256)
    p.add_argument("--samples", default="64")
    p.add_argument("--keep-work", action="store_true",
                   help="keep each scale's renders and scene descriptions "
                        "in DIR/work/xSCALE")
    args = p.parse_args(argv)
    try:
        args.scales = sorted({float(x) for x in args.scales.split(",")})
        args.samples = sorted({int(x) for x in args.samples.split(",")})
        w, _, h = args.resolution.partition("x")
        args.resolution = (int(w), int(h))
    except ValueError as e:
        p.error(f"--scales, --samples or --resolution: {e}")
    if not args.scales or min(args.scales) <= 0:
        p.error("--scales must be positive numbers")
    if min(args.samples) < 1 or args.ref_samples <= max(args.samples):
        p.error("--ref-samples must exceed every --samples count")
    args.scene = os.path.abspath(args.scene)
    args.out = os.path.abspath(args.out)
    args.name = args.name or os.path.splitext(os.path.basename(
        args.scene))[0]
    # compare.open_scene reads these.
    args.eevee_samples = 1
    return args


def scale_subsurface(found, scale):
    """Multiply the scattering radius of every scattering material's
    Principled BSDF by scale (blender_compat.scale_radius: Subsurface Scale
    from 4.0, Subsurface Radius in 3.x, whose Subsurface is also the
    diffuse / subsurface mix and, scaled past 1, made the walk's colour an
    extrapolation)."""
    done = set()
    for f in found.materials:
        if f.material.name in done:
            continue
        done.add(f.material.name)
        for node in f.material.node_tree.nodes:
            if node.type != "BSDF_PRINCIPLED":
                continue
            try:
                compat.scale_radius(node, scale)
            except ValueError as e:
                raise RuntimeError(f"material {f.material.name!r}: {e}; "
                                   "the sweep scales only a value") from None


def one_scale(args, scale, default_code, work):
    from separable_sss import native, pipeline
    scene = compare.open_scene(args, "CYCLES")
    found = pipeline.analyse(scene)
    if not found.materials:
        raise RuntimeError("nothing scatters in this scene")
    scale_subsurface(found, scale)
    found = pipeline.analyse(scene)
    radius = max(max(f.radius) for f in found.materials)
    kernel = max(pipeline.kernel_pixels(scene, f) for f in found.materials)

    halves, _ = compare.render_reference(scene, args.ref_samples,
                                         os.path.join(work, "ref"))
    ref = (halves[0] + halves[1]) / 2

    rows = []
    for n in args.samples:
        scene.cycles.samples = n
        inp = os.path.join(work, f"off_{n}_passes.exr")
        desc = os.path.join(work, f"off_{n}_scene.json")
        out = os.path.join(work, f"off_{n}_sss.exr")
        seconds = compare.render_sss_off(scene, found, inp, desc)
        ch = read_exr(inp)
        mask = compare.scattering_pixels(ch, found)[0]
        base = compare.rgb(ch, "Combined")
        with native.Scene(desc) as sc:
            t = sc.process(inp, out, method=default_code)
        res = read_exr(out)
        ours = compare.rgb(res, "SSS.Combined") if "SSS.Combined.R" in res \
            else compare.rgb(res, "Combined")
        metrics = [cm.all_metrics(img, ref, mask, 1.0, halves)
                   for img in (base, ours)]
        e0, e1 = (m["rmse_c"] for m in metrics)
        q0, q1 = (m["rmse_q_c"] for m in metrics)
        rows.append(dict(scene=args.name, scale=scale, radius_m=radius,
                         kernel_px=kernel, samples=n, rmse_no_sss=e0,
                         rmse_ours=e1, cut=_cut(e0, e1), rmse_q_no_sss=q0,
                         rmse_q_ours=q1, cut_q=_cut(q0, q1),
                         ratio_q=_ratio(q1, q0),
                         ours_vs_plain=relative_difference(ours, base, mask),
                         rw_over_plain=mean_ratio(ref, base, mask),
                         render_s=seconds, post_s=t["scatter"]))
        log(f"scale {scale:g} ({radius:.4g} m, {kernel:.1f} px) {n} spp: "
            f"RMSE {e0:.4g} -> {e1:.4g} ({rows[-1]['cut']:.1f} % less), "
            f"quarter {q0:.4g} -> {q1:.4g} ({rows[-1]['cut_q']:.1f} % less)"
            f"; ours vs no SSS {rows[-1]['ours_vs_plain']:.3g}, random walk "
            f"over no SSS {rows[-1]['rw_over_plain']}")
    return rows


def relative_difference(img, base, mask):
    """The largest per-pixel, per-channel |img - base| over the scattering
    pixels, relative to base (floored at 1 % of base's mean there, so that
    black pixels do not divide by zero): 0 where ours is the render
    without SSS."""
    a, b = img[mask].astype(np.float64), base[mask].astype(np.float64)
    floor = 0.01 * max(float(np.mean(np.abs(b))), 1e-12)
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), floor)))


def mean_ratio(ref, base, mask):
    """The random walk's mean over the scattering pixels over the render
    without SSS's, per channel, as "r/g/b"."""
    r = ref[mask].astype(np.float64).mean(axis=0)
    b = base[mask].astype(np.float64).mean(axis=0)
    return "/".join(f"{x / y:.3f}" if y > 0 else "nan" for x, y in zip(r, b))


def _ratio(ours, without):
    """ours / without, where both 0 (ours is the render without SSS and
    that render is already the random walk's) reads 1."""
    if without > 0:
        return ours / without
    return 1.0 if ours == 0 else float("inf")


def _cut(before, after):
    return 100.0 * (1.0 - after / before) if before > 0 else float("nan")


def write(args, rows):
    def fmt(v):
        return f"{v:.4g}" if isinstance(v, float) else str(v)
    with open(os.path.join(args.out, "sweep.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(COLUMNS)
        for r in rows:
            w.writerow([fmt(r[c]) for c in COLUMNS])
    lines = [f"# Radius sweep: {args.name}", "",
             f"Scene `{args.scene}`, {args.resolution[0]}x"
             f"{args.resolution[1]}; every scattering material's Subsurface "
             f"times `scale` (1 = the scene as built). Reference: random walk "
             f"{args.ref_samples} spp (two halves, other seeds); RMSE over the "
             "scattering pixels with the reference's own noise taken out "
             "(compare.py's rmse_c), `_q` at quarter resolution; `cut`: % less "
             "error with our default method than without SSS, `ratio_q` "
             "the quarter-resolution errors' ratio (never worse: at most "
             "1). `radius_m`: the largest Subsurface x Subsurface Radius; "
             "`kernel_px`: the kernel's half-width on the nearest "
             "scattering object; `ours_vs_plain`: the largest relative "
             "difference of ours from the render without SSS; "
             "`rw_over_plain`: the random walk's mean over that render's, "
             "per channel.", "",
             "| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    lines += ["| " + " | ".join(fmt(r[c]) for c in COLUMNS) + " |"
              for r in rows]
    lines += ["", verdict(rows), "",
              "![errors and their ratio against the scale](sweep.png)", ""]
    with open(os.path.join(args.out, "sweep.md"), "w") as f:
        f.write("\n".join(lines))


# Equal errors count as never worse: where ours is the render without SSS
# recombined from its passes, the two differ by float rounding only.
EQUAL = 1e-3


def verdict(rows):
    """One line: whether ours is never worse than no SSS at quarter
    resolution, and where it is closest to (or past) the line."""
    worst = max(rows, key=lambda r: r["ratio_q"])
    ok = all(r["ratio_q"] <= 1.0 + EQUAL for r in rows)
    return (f"Never worse than no SSS at quarter resolution: "
            f"{'yes' if ok else 'no'} (largest ratio {worst['ratio_q']:.3f} "
            f"at x{worst['scale']:g}, {worst['samples']} spp).")


def plot(args, rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    ax = axes[0]
    for n in args.samples:
        rs = sorted((r for r in rows if r["samples"] == n),
                    key=lambda r: r["scale"])
        x = [r["scale"] for r in rs]

        def shown(key):
            # An error of 0 (the walk is the diffuse render: Cycles below
            # its smallest radius) has no place on a log axis.
            return [r[key] if r[key] > 0 else float("nan") for r in rs]
        line, = ax.plot(x, shown("rmse_q_no_sss"), "s--",
                        label=f"no SSS, {n} spp")
        ax.plot(x, shown("rmse_q_ours"), "o-",
                color=line.get_color(), label=f"no SSS {n} spp + ours")
        for r in rs:
            if r["rmse_q_ours"] > 0:
                ax.annotate(f"{r['kernel_px']:.2g} px",
                            (r["scale"], r["rmse_q_ours"]), fontsize=6,
                            xytext=(3, 3), textcoords="offset points")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylabel("RMSE against the random walk, quarter resolution\n"
                  f"(reference {args.ref_samples} spp, its noise removed)")
    ax.set_title(f"{args.name}: error (labels: kernel half-width)")
    ax.legend(fontsize=7)
    ax = axes[1]
    for n in args.samples:
        for key, style, what in (("ratio_q", "o-", "quarter resolution"),
                                 (None, "^:", "full resolution")):
            rs = sorted((r for r in rows if r["samples"] == n),
                        key=lambda r: r["scale"])
            y = [r[key] if key else (r["rmse_ours"] / r["rmse_no_sss"]
                                     if r["rmse_no_sss"] > 0 else float("nan"))
                 for r in rs]
            ax.plot([r["scale"] for r in rs], y, style,
                    label=f"{n} spp, {what}")
    ax.axhline(1.0, color="r", lw=1.2, label="never worse: at most 1")
    ax.axhline(0.7, color="grey", ls=":", lw=0.8, label="30 % less error")
    ax.set_xscale("log")
    ax.set_ylabel("error with ours / error without SSS")
    ax.set_title(f"{args.name}: ratio")
    ax.legend(fontsize=7)
    for ax in axes:
        ax.set_xlabel("Subsurface scale (x the scene's radius)")
        ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    args = parse_args()
    os.environ.setdefault("SSS_LIB", os.path.join(compare.ROOT, "build",
                                                  "libsss.so"))
    import separable_sss
    separable_sss.register()
    os.makedirs(args.out, exist_ok=True)
    work = os.path.join(args.out, "work")
    os.makedirs(work, exist_ok=True)
    t0 = time.perf_counter()
    scene = compare.open_scene(args, "CYCLES")
    default = scene.sss.method.lower()
    codes = dict(compare.library_methods())
    if default not in codes:
        raise RuntimeError(f"the scene's method {default!r} is not one of "
                           f"the library's ({', '.join(codes)})")
    log(f"{args.name}: scales {args.scales}, {args.resolution[0]}x"
        f"{args.resolution[1]}, reference {args.ref_samples} spp, SSS off "
        f"{args.samples}, method {default}")
    rows = []
    for scale in args.scales:
        work_scale = os.path.join(work, f"x{scale:g}")
        os.makedirs(work_scale, exist_ok=True)
        rows += one_scale(args, scale, codes[default], work_scale)
    write(args, rows)
    plot(args, rows, os.path.join(args.out, "sweep.png"))
    if not args.keep_work:
        import shutil
        shutil.rmtree(work, ignore_errors=True)
    separable_sss.unregister()
    log(verdict(rows))
    log(f"wrote {args.out}/sweep.csv, sweep.md, sweep.png "
        f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    run_main(main)
