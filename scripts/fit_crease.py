"""Fit the crease term's table (csrc/sss_calibration.c, section 6) to a
`calibrate.py --part crease` run, and report how well the shipped term
matches the random walk:

    python3 scripts/fit_crease.py OUT/crease_random_walk_skin.csv \
        [--plot crease.png] [--albedos 0.3,0.55,0.85]

For each albedo (one per channel of each render): the walk's excess over
the library without the crease term on the unlit face, as a function of
t (metres from the edge), is fitted by kappa x the mean over each row's
extent of F(t), F the mass of Burley's 1-D marginal beyond t with
d = gamma x radius; gamma from a grid, kappa by least squares, over every
radius of the run. Printed per albedo: gamma, kappa, the fit's RMS, and
the RMS of the walk against the library without and with the term (the
csv's `crease` column) over the unlit face, all in units of the lit
face's scattered light. A run with the `stopped` column (the blur
stopped at the edge, nothing carried over: the walks whose blur stops
there, Random Walk (Skin) on 4.x) is fitted against it instead: the gain
on the unlit face, and in the same way the lit face's loss (the stopped
blur over the walk there), printed after the gain as loss gamma, kappa
and RMS. --plot draws, for a few albedos, the profile
across the edge: the walk, the library without and with the term.
"""
import argparse
import csv
import os
import sys

import numpy as np

GAMMAS = np.concatenate([np.arange(0.01, 0.1, 0.005),
                         np.arange(0.1, 1.0, 0.01)])


def unit_tail():
    """F for d = 1 on a grid: the share of Burley's radial profile beyond
    a line at distance u, the mass of its 1-D marginal there."""
    r = np.geomspace(1e-4, 60.0, 6000)
    pdf = (np.exp(-r) + np.exp(-r / 3)) / 4
    dr = np.gradient(r)
    u = np.concatenate([[0.0], np.geomspace(1e-4, 60.0, 600)])
    tail = [np.sum(pdf * dr * np.where(r > a, np.arccos(np.clip(
        a / r, -1, 1)) / np.pi, 0.0)) for a in u]
    return u, np.array(tail)


U, TAIL = unit_tail()


def row_means(t, step, d):
    """The mean of F (shape d) over each row's extent [t - step/2,
    t + step/2] (clipped at the edge), per unit of the whole row."""
    res = []
    for ti in t:
        x = np.linspace(max(ti - step / 2, 0.0), ti + step / 2, 17)
        res.append(np.trapz(np.interp(x / d, U, TAIL, right=0.0), x) / step)
    return np.array(res)


REQUIRED = ("radius", "albedo", "t", "rw", "ours")


def load(path):
    """The run's rows by albedo and radius; exits with a message naming
    the file when it cannot be read or is not a crease run."""
    try:
        with open(path, newline="") as f:
            reader = csv.DictReader(f)
            missing = [c for c in REQUIRED
                       if c not in (reader.fieldnames or [])]
            if missing:
                sys.exit(f"fit_crease.py: {path}: not a calibrate.py "
                         f"--part crease table (no column "
                         f"{', '.join(missing)})")
            groups = {}
            for line, row in enumerate(reader, start=2):
                try:
                    key = (float(row["albedo"]), float(row["radius"]))
                    float(row["t"]), float(row["rw"]), float(row["ours"])
                except (TypeError, ValueError):
                    sys.exit(f"fit_crease.py: {path}, line {line}: not a "
                             f"number in {', '.join(REQUIRED)}")
                groups.setdefault(key[0], {}).setdefault(key[1],
                                                         []).append(row)
    except OSError as e:
        sys.exit(f"fit_crease.py: cannot read {path}: {e.strerror}")
    if not groups or any(len(rows) < 2 for by in groups.values()
                         for rows in by.values()):
        sys.exit(f"fit_crease.py: {path}: no profile of two rows or more")
    return groups


def plot(groups, albedos, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(albedos), figsize=(4.2 * len(albedos),
                                                       3.4), sharey=True)
    for ax, want in zip(np.atleast_1d(axes), albedos):
        albedo = min(groups, key=lambda a: abs(a - want))
        radius, rows = sorted(groups[albedo].items())[0]
        t = np.array([float(r["t"]) for r in rows]) * 1000.0
        for key, label, style in (("rw", "random walk", "k-"),
                                  ("ours", "library, no crease term", "C0--"),
                                  ("crease", "library", "C1-")):
            ax.plot(t, [float(r.get(key, "nan")) for r in rows], style,
                    label=label, lw=1.4)
        ax.axvline(0.0, color="0.6", lw=0.8)
        ax.set_xlim(-30, 40)
        ax.set_title(f"albedo {albedo:g}, radius {radius * 100:g} cm")
        ax.set_xlabel("mm from the edge (lit face < 0 < unlit face)")
    np.atleast_1d(axes)[0].set_ylabel("light over the lit face's")
    np.atleast_1d(axes)[0].legend(fontsize=8)
    fig.tight_layout()
    root, ext = os.path.splitext(path)
    partial = f"{root}.partial{ext}"  # whole or not at all
    fig.savefig(partial, dpi=110)
    os.replace(partial, path)
    print("wrote", path)


def main(argv):
    p = argparse.ArgumentParser(prog="fit_crease.py")
    p.add_argument("csv")
    p.add_argument("--plot", help="PNG of the profiles across the edge")
    p.add_argument("--albedos", default="0.3,0.55,0.85",
                   help="for --plot, comma-separated")
    args = p.parse_args(argv)
    try:
        albedos = [float(a) for a in args.albedos.split(",")]
    except ValueError:
        p.error(f"--albedos {args.albedos!r}: comma-separated numbers")
    groups = load(args.csv)
    if args.plot:
        plot(groups, albedos, args.plot)
    stopped = all("stopped" in r for by in groups.values()
                  for rows in by.values() for r in rows)
    print(f"{'albedo':>6} {'gamma':>6} {'kappa':>7} {'fit':>7} "
          f"{'without':>8} {'with':>7}" +
          (f" {'loss g':>6} {'kappa':>7} {'fit':>7}" if stopped else ""))
    for albedo, by_radius in sorted(groups.items()):
        gain, loss = [], []
        for radius, rows in by_radius.items():
            t = np.array([float(r["t"]) for r in rows])
            base = np.array([float(r["stopped" if stopped else "ours"])
                             for r in rows])
            rw = np.array([float(r["rw"]) for r in rows])
            after = np.array([float(r["rw"]) - float(r.get("crease", "nan"))
                              for r in rows])
            unlit, lit = t > 0, t < 0
            gain.append((radius, t[unlit], (rw - base)[unlit], after[unlit],
                         np.abs(np.diff(t[unlit])).mean()))
            loss.append((radius, -t[lit], (base - rw)[lit], after[lit],
                         np.abs(np.diff(t[lit])).mean()))
        best = fit(gain)
        n = sum(len(e) for _, _, e, _, _ in gain)
        without = np.sqrt(sum((e ** 2).sum() for _, _, e, _, _ in gain) / n)
        with_term = np.sqrt(sum((a ** 2).sum() for _, _, _, a, _ in gain) / n)
        line = (f"{albedo:6.3f} {best[0]:6.3f} {best[1]:7.3f} {best[2]:7.4f} "
                f"{without:8.4f} {with_term:7.4f}")
        if stopped:
            lb = fit(loss)
            line += f" {lb[0]:6.3f} {lb[1]:7.3f} {lb[2]:7.4f}"
        print(line)


def fit(data):
    """(gamma, kappa, RMS) of kappa x row_means(t, step, gamma r) against
    the excess e, over every radius's (radius, t, e, _, step)."""
    best = None
    for g in GAMMAS:
        models = [row_means(t, step, g * radius)
                  for radius, t, _, _, step in data]
        num = sum(m @ e for m, (_, _, e, _, _) in zip(models, data))
        den = sum(m @ m for m in models)
        kappa = num / den
        err = np.sqrt(sum(((kappa * m - e) ** 2).sum()
                          for m, (_, _, e, _, _) in zip(models, data)) /
                      sum(len(e) for _, _, e, _, _ in data))
        if best is None or err < best[2]:
            best = (g, kappa, err)
    return best


if __name__ == "__main__":
    main(sys.argv[1:])
