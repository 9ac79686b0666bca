"""One picture and one table of every scene's radius sweep (make sweep):
the ratio of the error with our method to the error without SSS, at
quarter resolution, against the radius scale, with the never-worse line.

    python3 scripts/sweep_summary.py out/compare/sweep [--scenes a,b,c]

Reads DIR/SCENE/sweep.csv (blender_scripts/sweep_radius.py) and writes
DIR/summary.png and DIR/summary.md; csv and matplotlib, no Blender.
"""
import argparse
import csv
import math
import os
import sys

# As sweep_radius.py: equal errors (ours recombines the same passes)
# count as never worse.
EQUAL = 1e-3


def read(path):
    """The rows of one sweep.csv; ValueError names the file and what is
    wrong in it."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise ValueError(f"{path}: no rows")
    for n, r in enumerate(rows, 2):
        try:
            for key in ("scale", "ratio_q"):
                r[key] = float(r[key])
            r["samples"] = int(r["samples"])
        except (KeyError, TypeError, ValueError) as e:
            raise ValueError(f"{path}: line {n}: {e!r} (not a sweep_radius.py "
                             "sweep.csv?)") from None
    return rows


def table(scenes):
    scales = sorted({r["scale"] for rows in scenes.values() for r in rows})
    head = "| scene | " + " | ".join(f"x{s:g}" for s in scales) + \
        " | never worse |"
    lines = [head, "|" + "---|" * (len(scales) + 2)]
    for name, rows in scenes.items():
        by = {r["scale"]: r for r in rows}
        cells = [f"{by[s]['ratio_q']:.3f}" if s in by else "" for s in scales]
        ok = all(r["ratio_q"] <= 1.0 + EQUAL for r in rows)
        lines.append(f"| {name} | " + " | ".join(cells) +
                     f" | {'yes' if ok else 'no'} |")
    return lines


def plot(scenes, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    for name, rows in scenes.items():
        rs = sorted(rows, key=lambda r: r["scale"])
        ax.plot([r["scale"] for r in rs], [r["ratio_q"] for r in rs], "o-",
                label=name)
    ax.axhline(1.0, color="r", lw=1.2, label="never worse: at most 1")
    ax.axhline(0.7, color="grey", ls=":", lw=0.8, label="30 % less error")
    ax.set_xscale("log")
    ax.set_xlabel("Subsurface scale (x the scene's radius)")
    ax.set_ylabel("error with ours / error without SSS\n"
                  "(quarter resolution, against the random walk)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    p = argparse.ArgumentParser(prog="sweep_summary.py")
    p.add_argument("dir")
    p.add_argument("--scenes", help="comma-separated (default: every "
                   "folder of DIR with a sweep.csv)")
    args = p.parse_args()
    names = args.scenes.split(",") if args.scenes else sorted(
        d for d in os.listdir(args.dir)
        if os.path.isfile(os.path.join(args.dir, d, "sweep.csv")))
    if not names:
        p.error(f"{args.dir}: no SCENE/sweep.csv (run make sweep)")
    scenes = {}
    for name in names:
        path = os.path.join(args.dir, name, "sweep.csv")
        if not os.path.isfile(path):
            p.error(f"{path}: missing")
        try:
            scenes[name] = read(path)
        except ValueError as e:
            p.error(str(e))
    lines = ["# Radius sweep: every scene", "",
             "Error with our default method over the error without SSS, "
             "RMSE over the scattering pixels at quarter resolution against "
             "the random walk with its noise taken out (never worse: at most "
             f"1, equal within {EQUAL:g}); per scene in SCENE/sweep.md.", ""]
    lines += table(scenes)
    lines += ["", "![ratio against the scale](summary.png)", ""]
    tmp = os.path.join(args.dir, ".summary.md.tmp")
    with open(tmp, "w") as f:
        f.write("\n".join(lines))
    os.replace(tmp, os.path.join(args.dir, "summary.md"))
    plot(scenes, os.path.join(args.dir, "summary.png"))
    worst = max(((n, r) for n, rows in scenes.items() for r in rows),
                key=lambda nr: nr[1]["ratio_q"])
    ok = not math.isnan(worst[1]["ratio_q"]) and \
        worst[1]["ratio_q"] <= 1.0 + EQUAL
    print(f"sweep: every scene never worse than no SSS: "
          f"{'yes' if ok else 'no'} (largest ratio "
          f"{worst[1]['ratio_q']:.3f}: {worst[0]} at x{worst[1]['scale']:g})")
    print(f"sweep: wrote {args.dir}/summary.md and summary.png")


if __name__ == "__main__":
    sys.exit(main())
