"""The README's picture, docs/images/head.png: the bundled head scene at
equal wall time, both sides denoised: the render without SSS (as it
comes, for what scattering changes), with libsss + OIDN,
Cycles' random walk + OIDN at the sample count whose time is closest to
ours, and the reference; each captioned with its samples, wall time and
error, from the output of blender_scripts/compare.py on that scene (`make
figures` runs both).

    /usr/bin/python3 scripts/readme_figure.py [--compare out/compare/head]
        [--out docs/images/head.png] [--samples N] [--method NAME]
        [--width 1000]

Reads, under the compare folder: results.csv (the times: total_s is the
render plus the library's scatter time plus the denoise; the errors:
rmse_q_c, RMSE at quarter resolution against the reference with its noise
taken out), summary.txt (the default method) and the work/ folder, which
compare.py keeps when SSS_COMPARE_KEEP_WORK=1: cycles_N_passes.exr (the
render with material SSS off) and cycles_N_scene.json (the scattering
materials), the denoised images cycles_N_METHOD_oidn.exr and
rw_M_oidn.exr, and rw_R_1.exr and rw_R_2.exr
for the reference (the random walk at its highest count, the mean of two
renders of half its samples). Where compare has no OIDN rows (a Blender
without OpenImageDenoise) the images are not denoised and the captions say
so.

Every panel has compare's contact-sheet view: the same crop (the
scattering pixels' bounding box) and exposure (the reference's 99th
percentile luminance over the scattering pixels at 0.85), gamma 2.2.
Defaults: the largest SSS-off sample count and the scene's default method.
"""
import argparse
import csv
import json
import os
import re
import sys

import numpy as np

ROOT = os.path.normpath(os.path.join(os.path.dirname(
    os.path.abspath(__file__)), ".."))
sys.path.insert(0, os.path.join(ROOT, "blender_scripts"))
import compare_metrics as cm  # noqa: E402  (numpy only)
from exr_io import read_exr  # noqa: E402  (OpenImageIO; 5.0's names)

REF = "random-walk (ref)"


def fail(msg):
    sys.exit(f"readme_figure: {msg}")


def parse_args():
    p = argparse.ArgumentParser(prog="readme_figure.py")
    p.add_argument("--compare", default=os.path.join(ROOT, "out", "compare",
                                                     "head"),
                   help="compare.py's output folder for the scene")
    p.add_argument("--out", default=os.path.join(ROOT, "docs", "images",
                                                 "head.png"))
    p.add_argument("--samples", type=int, help="samples of the SSS-off "
                   "render (default: the largest measured)")
    p.add_argument("--method", help="library method (default: the scene's, "
                   "from summary.txt)")
    p.add_argument("--width", type=int, default=1000, help="pixels")
    return p.parse_args()


def read_rows(folder):
    path = os.path.join(folder, "results.csv")
    if not os.path.exists(path):
        fail(f"no {path}: run `make figures` (or make compare "
             "COMPARE_SCENES=head with SSS_COMPARE_KEEP_WORK=1) first")
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        r["samples"] = int(r["samples"])
        for k in ("render_s", "post_s", "total_s", "rmse_q", "rmse_q_c"):
            r[k] = float(r[k])
        r["error"] = r["rmse_q_c"] if np.isfinite(r["rmse_q_c"]) else \
            r["rmse_q"]
    return rows


def default_method(folder):
    path = os.path.join(folder, "summary.txt")
    text = open(path).read() if os.path.exists(path) else ""
    m = re.search(r"default method (\S+)", text)
    return m.group(1) if m else "auto"


def pick(rows, method, samples=None):
    cands = [r for r in rows if r["renderer"] == "cycles" and
             r["method"] == method and
             (samples is None or r["samples"] == samples)]
    if not cands:
        fail(f"results.csv has no Cycles row for {method}"
             + (f" at {samples} spp" if samples else "")
             + f" (have: {sorted({(r['method'], r['samples']) for r in rows})})")
    return max(cands, key=lambda r: r["samples"])


def rgb(channels, name, path):
    """(h, w, 3) of name.R/G/B in the render's own layer (not the add-on's
    SSSBackLight) or, for the library's result, the SSS layer."""
    keys = [k for k in channels if k.endswith(f".{name}.R") or
            k == f"{name}.R"]
    if "." not in name:  # the render's own layer
        keys = [k for k in keys if k.split(".")[0] not in
                ("SSS", "SSSBackLight")]
    if not keys:
        fail(f"{path}: no {name} pass")
    prefix = keys[0][:-2]
    return np.stack([channels[f"{prefix}.{c}"] for c in "RGB"], axis=-1)


def work_file(folder, name):
    path = os.path.join(folder, "work", name)
    if not os.path.exists(path):
        fail(f"no {path}: compare.py removes its work folder unless "
             "SSS_COMPARE_KEEP_WORK=1 (make figures sets it)")
    return path


DENOISED = "+oidn"   # compare_runs.DENOISED (that module needs bpy)


def images(args, rows):
    folder = args.compare
    method = args.method or default_method(folder)
    off = pick(rows, "no-sss", args.samples)
    n = off["samples"]
    passes_path = work_file(folder, f"cycles_{n}_passes.exr")
    passes = read_exr(passes_path)
    dn = DENOISED if any(r["method"] == method + DENOISED for r in rows) \
        else ""
    suffix = "_oidn" if dn else ""
    layer = "Composite.Combined" if dn else None

    def image(row, name, own):
        path = work_file(folder, name + suffix + ".exr")
        return row, rgb(read_exr(path), layer or own, path)

    off_img = rgb(passes, "Combined", passes_path)
    ours, ours_img = image(pick(rows, method + dn, n),
                           f"cycles_{n}_{method}", "SSS.Combined")
    # The random walk whose wall time is closest to ours'.
    walks = [r for r in rows if r["renderer"] == "cycles" and
             r["method"] == "random-walk" + dn]
    if not walks:
        fail(f"results.csv has no random-walk{dn} row")
    near = min(walks, key=lambda r: abs(r["total_s"] - ours["total_s"]))
    rw, rw_img = image(near, f"rw_{near['samples']}", "Combined")

    # The reference: the mean of its two halves, as compare.py takes it.
    ref = pick(rows, REF)
    halves = [rgb(read_exr(p), "Combined", p) for p in (
        work_file(folder, f"rw_{ref['samples']}_{k}.exr") for k in (1, 2))]
    ref_img = (halves[0] + halves[1]) / 2

    # The scattering pixels, as compare.py takes them: a scattering
    # material's index (from the scene description) in front of the
    # background.
    desc = json.load(open(work_file(folder, f"cycles_{n}_scene.json")))
    indices = [m["pass_index"] for m in desc.get("materials", [])]
    index_key = next((k for k in passes if k.endswith(".IndexMA.X") and
                      not k.startswith("SSSBackLight.")), None)
    depth_key = next((k for k in passes if k.endswith(".Depth.Z") and
                      not k.startswith("SSSBackLight.")), None)
    if not index_key or not depth_key:
        fail(f"{passes_path}: no IndexMA or Depth pass")
    mask = np.isin(np.rint(passes[index_key]), indices) & \
        (passes[depth_key] < 1e9)
    if not mask.any():
        fail(f"{passes_path}: no scattering pixels")

    # The reference's exposure, as on compare's contact sheet.
    exposure = cm.exposure_for(ref_img, mask)

    plus = " + OIDN" if dn else " (not denoised: no OIDN)"
    panels = [
        ("no SSS", off, off_img),
        (f"libsss ({method})" + plus, ours, ours_img),
        ("Cycles random walk" + plus, rw, rw_img),
        ("reference: random walk", ref, ref_img),
    ]
    return panels, mask, exposure


def caption(title, row):
    how = f"{row['samples']} spp, {row['total_s']:.1f} s"
    if row["method"] == REF:
        return f"{title}\n{how}"
    return f"{title}\n{how}, error {row['error']:.3f}"


def draw(args, panels, mask, exposure):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    y0, y1, x0, x1 = cm.crop_box(mask)  # compare's crop
    aspect = (y1 - y0) / max(1, x1 - x0)
    dpi = 100
    width = args.width / dpi
    panel_w = width / len(panels)
    fig, axes = plt.subplots(1, len(panels), figsize=(
        width, panel_w * aspect + 0.55), dpi=dpi)
    fig.subplots_adjust(left=0.005, right=0.995, bottom=0.005, wspace=0.02,
                        top=1 - 0.55 / (panel_w * aspect + 0.55))
    for ax, (title, row, img) in zip(axes, panels):
        view = np.clip(img[y0:y1, x0:x1] * exposure, 0, 1) ** (1 / 2.2)
        ax.imshow(view, interpolation="lanczos")
        ax.set_title(caption(title, row), fontsize=9)
        ax.axis("off")
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    tmp = args.out + ".tmp.png"
    fig.savefig(tmp, dpi=dpi)
    plt.close(fig)
    # A palette of 256 colours keeps the PNG small enough for git.
    from PIL import Image
    with Image.open(tmp) as im:
        im.convert("RGB").quantize(colors=256, method=Image.MEDIANCUT,
                                   dither=Image.FLOYDSTEINBERG) \
            .save(tmp, optimize=True)
    os.replace(tmp, args.out)


def main():
    args = parse_args()
    rows = read_rows(args.compare)
    panels, mask, exposure = images(args, rows)
    draw(args, panels, mask, exposure)
    for title, row, _ in panels:
        print(f"readme_figure: {caption(title, row)}".replace("\n", ": "))
    print(f"readme_figure: wrote {args.out} "
          f"({os.path.getsize(args.out) // 1024} KiB)")


if __name__ == "__main__":
    main()
