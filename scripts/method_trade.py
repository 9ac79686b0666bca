"""How far each method is from the brute-force reference, per material,
and what it costs: the speed/accuracy trade inside the library, on one
frame's passes (the random walk is not involved; make compare and make
sweep measure against it).

    python3 scripts/method_trade.py PASSES.exr --scene SCENE.json --out DIR
        [--variants separable,separable:taps=17,disk:samples=32,...]
        [--threads 1] [--repeat 3] [--sss build/sss]

A variant is a method name with optional `:taps=N` (the scene's tap
budget) and `:samples=N` (the disk method's). The reference always runs
(once: it is slow); the others run --repeat times and the fastest time is
kept. Per material (IndexMA) the error is the relative RMS of SSS.Combined
against the reference's over that material's pixels. Writes
DIR/method_trade.{csv,md,png}. Passes and scene come from the add-on's
files, from `make sweep SWEEP_ARGS=--keep-work` (work/xSCALE/off_*) or
from any render the `sss` command reads.
"""
import argparse
import csv
import json
import os
import re
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "blender_scripts"))
from exr_io import read_exr_parts, rgb, single  # noqa: E402

DEFAULT_VARIANTS = ("separable:taps=9,separable:taps=17,separable,"
                    "separable:taps=65,disk:samples=16,disk:samples=32,disk,"
                    "separable-exact")
TIME = re.compile(r", sss ([0-9.]+) s,")


def parse_variant(text):
    """'disk:samples=32' -> ('disk', {'samples': 32}); ValueError names
    the variant."""
    method, *opts = text.split(":")
    params = {}
    for o in opts:
        key, _, value = o.partition("=")
        if key not in ("taps", "samples") or not value.isdigit():
            raise ValueError(f"variant {text!r}: expected METHOD[:taps=N]"
                             "[:samples=N]")
        params[key] = int(value)
    if not method:
        raise ValueError(f"variant {text!r}: no method")
    return method, params


def known_methods(sss):
    """The method names `sss --help` lists under "methods:"."""
    proc = subprocess.run([sss, "--help"], capture_output=True, text=True)
    text = proc.stdout + proc.stderr
    block = text.partition("\nmethods:\n")[2].split("\n\n")[0]
    return {line.split()[0] for line in block.splitlines() if line.strip()}


def combined(path):
    ch = read_exr_parts(path)[0]
    if "SSS.Combined.R" not in ch:
        raise ValueError(f"{path}: no SSS.Combined (not an sss output?)")
    return rgb(ch, "SSS.Combined").astype(np.float64)


def material_index(path):
    try:
        return np.rint(single(read_exr_parts(path)[0], "IndexMA")) \
            .astype(np.int64)
    except KeyError:
        raise ValueError(f"{path}: no IndexMA pass") from None


def run_sss(args, passes, scene, method, params, out, repeat):
    cmd = [args.sss, passes, "-o", out, "--scene", scene, "-m", method,
           "-t", str(args.threads)]
    if "samples" in params:
        cmd += ["--samples", str(params["samples"])]
    best = None
    for _ in range(repeat):
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)}: {proc.stderr.strip()}")
        m = TIME.search(proc.stdout + proc.stderr)
        if not m:
            raise RuntimeError(f"{' '.join(cmd)}: no time in its output")
        t = float(m.group(1))
        best = t if best is None else min(best, t)
    return best


def scene_with_taps(scene_path, taps, work):
    with open(scene_path) as f:
        desc = json.load(f)
    desc["taps"] = taps
    path = os.path.join(work, f"scene_taps{taps}.json")
    with open(path, "w") as f:
        json.dump(desc, f)
    return path


def measure(args):
    with open(args.scene) as f:
        names = {m["pass_index"]: m.get("name", f"index {m['pass_index']}")
                 for m in json.load(f).get("materials", [])}
    index = material_index(args.passes)
    rows = []
    with tempfile.TemporaryDirectory() as work:
        ref_out = os.path.join(work, "reference.exr")
        ref_time = run_sss(args, args.passes, args.scene, "reference", {},
                           ref_out, 1)
        ref = combined(ref_out)
        for text in ["reference"] + args.variants:
            method, params = parse_variant(text)
            if text == "reference":
                seconds, img = ref_time, ref
            else:
                scene = (scene_with_taps(args.scene, params["taps"], work)
                         if "taps" in params else args.scene)
                out = os.path.join(work, "variant.exr")
                seconds = run_sss(args, args.passes, scene, method, params,
                                  out, args.repeat)
                img = combined(out)
            for idx in sorted(names):
                mask = index == idx
                if not mask.any():
                    continue
                a, b = img[mask], ref[mask]
                err = float(np.sqrt(((a - b) ** 2).mean()) /
                            max(np.sqrt((b ** 2).mean()), 1e-30))
                rows.append({"variant": text, "material": names[idx],
                             "pass_index": idx, "pixels": int(mask.sum()),
                             "seconds": seconds, "error": err})
            print(f"method_trade: {text}: {seconds:.3f} s", flush=True)
    return rows


def write(rows, out):
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "method_trade.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    materials = list(dict.fromkeys(r["material"] for r in rows))
    variants = list(dict.fromkeys(r["variant"] for r in rows))
    lines = ["| variant | time (s) | " + " | ".join(
        f"{m} error vs reference" for m in materials) + " |",
        "|---|---|" + "---|" * len(materials)]
    for v in variants:
        cells = {r["material"]: r for r in rows if r["variant"] == v}
        t = next(iter(cells.values()))["seconds"]
        lines.append(f"| {v} | {t:.3f} | " + " | ".join(
            f"{cells[m]['error']:.4f}" for m in materials) + " |")
    lines += ["", "Time: the scatter stage of `sss` (signal, blur and "
              "recombination), the fastest of the repeats."]
    with open(os.path.join(out, "method_trade.md"), "w") as f:
        f.write("\n".join(lines) + "\n")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for m in materials:
        pts = [r for r in rows if r["material"] == m and r["error"] > 0]
        ax.plot([r["seconds"] for r in pts], [r["error"] for r in pts], "o",
                label=m)
        for r in pts:
            ax.annotate(r["variant"], (r["seconds"], r["error"]),
                        fontsize=7, xytext=(3, 3), textcoords="offset points")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("scatter time (s)")
    ax.set_ylabel("relative RMS error vs reference")
    ax.set_title("Speed against accuracy per material (reference = 0)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "method_trade.png"), dpi=110)
    plt.close(fig)


def main():
    p = argparse.ArgumentParser(prog="method_trade.py")
    p.add_argument("passes")
    p.add_argument("--scene", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--variants", default=DEFAULT_VARIANTS)
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--sss", default=os.path.join(ROOT, "build", "sss"))
    args = p.parse_args()
    try:
        args.variants = [v for v in args.variants.split(",") if v]
        for v in args.variants:
            parse_variant(v)
    except ValueError as e:
        p.error(f"--variants: {e}")
    if args.repeat < 1:
        p.error("--repeat must be at least 1")
    for path in (args.passes, args.scene, args.sss):
        if not os.path.exists(path):
            p.error(f"{path}: no such file")
    # before the reference's long run, not after it
    methods = known_methods(args.sss)
    for v in args.variants:
        if methods and parse_variant(v)[0] not in methods:
            p.error(f"--variants: {v!r}: unknown method (known: "
                    f"{', '.join(sorted(methods))})")
    try:
        rows = measure(args)
    except (RuntimeError, ValueError, OSError) as e:
        print(f"method_trade.py: {e}", file=sys.stderr)
        return 1
    if not rows:
        print(f"method_trade.py: {args.passes}: no pixel of the scene's "
              "materials", file=sys.stderr)
        return 1
    write(rows, args.out)
    print(f"method_trade: wrote {args.out}/method_trade.csv, .md, .png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
