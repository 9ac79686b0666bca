"""Fit the slab transmittance of one of Blender 4.x's random walks
(Random Walk (Skin), or plain Random Walk) to scripts/
measure_transmission4.sh runs of that method, and write it as the
library's table (csrc/sss_walk4_KIND_table.c) and the test's measured
points (tests/transmission4_KIND_measured.h), KIND skin or rw:

    SSS_LIB=build/libsss.so python3 scripts/fit_transmission4.py \\
        build/t4/m64 [--replicate build/t4/m48] [--kind skin|rw] [--write]

A run holds, per slab colour (a - d: the grid, e: a check not fitted),
measure_transmission.py's slab.json: per thickness and channel the walk's
transmitted light over the library's (t_rw / t_model) and the library's
transmittance there (t_library). Their product is the walk's, in the
library's terms (what multiplies the back light before the blur; the
albedo and the calibration's gain multiply it after):

    T4 = t_rw / t_model x t_library,

at x = t / l, l the medium's mean free path (sss_transmission_slab: l =
1.5 (a - zb)). The table is ln T4 on a grid of x (X_NODES) and albedo
(A_NODES): per albedo the measured curve (the runs' points, weighted by
their pixel counts, the same slab's in both) interpolated linearly in x,
made non-increasing; before the first point extrapolated linearly in x
(at most 1 / A: no more light leaves than arrived); after the last
reliable point (where the walk's light is at least FLOOR of the back
light) the slab model's own decay (T4 / T_slab held, as the library
does beyond the last node) or the last two points' where that is
steeper (at high albedo the walk's limit on its steps cuts it off). Printed: the table, the fit's residual
(ln of table over measured, RMS and largest, on the fitted points and on
the check), the slab model's (before) on the same points, and, with
--replicate, the noise: the same points in a second run.
"""
import argparse
import importlib.util
import json
import math
import os

import numpy as np

ROOT = os.path.normpath(os.path.join(os.path.dirname(
    os.path.abspath(__file__)), ".."))
# The add-on's ctypes module alone (its package needs Blender).
_spec = importlib.util.spec_from_file_location(
    "sss_native", os.path.join(ROOT, "addon", "separable_sss", "native.py"))
native = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(native)

X_NODES = [0.0, 0.25, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 5.5, 7.5, 10.0, 12.0,
           14.0, 17.0, 20.0, 24.0, 28.0, 34.0, 40.0, 48.0, 56.0, 66.0, 80.0]
A_NODES = [0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95]
GRID_SETS = "abcd"
CHECK_SETS = "e"
# Per kind: the walk's name in Blender, and the calibration the add-on
# gives its materials (what a run of measure_transmission4.sh's METHOD
# RANDOM_WALK_SKIN or RANDOM_WALK records in slab.json).
KINDS = {"skin": ("Random Walk (Skin)", "cycles4-random-walk-skin"),
         "rw": ("Random Walk", "cycles4-random-walk")}
# The walk's transmitted light, as a share of the back light, below which
# a point is noise (see the replicate's spread).
FLOOR = 1e-4


def slab_T(s, a, zb, t):
    """The library's slab (sss.h, sss_transmission_slab)."""
    L = max(t + 2.0 * zb, 2.0 * a)
    x = s * L
    if x < 1e-6:
        return a / L
    y = s * a
    return min(1.0, -math.expm1(-2 * y) * math.exp(-(x - 2 * y)) /
               -math.expm1(-2 * x))


def load(run, sets, kind):
    """Points: dicts with set, row, channel, A, x, T4, the slab's T and
    the walk's light over the back light (W). A run of another walk than
    kind's is an error."""
    pts = []
    for s in sets:
        path = os.path.join(run, s, "slab.json")
        if not os.path.exists(path):
            continue
        with open(path) as f:
            rows = json.load(f)
        for i, r in enumerate(rows):
            mat = r["material"]
            if mat.get("calibration") != KINDS[kind][1]:
                raise SystemExit(
                    f"{path}: the slab's calibration is "
                    f"{mat.get('calibration')!r}, not {KINDS[kind][1]!r}: "
                    f"measure_transmission4.sh ran another walk than "
                    f"--kind {kind}")
            base = dict(mat, calibration="cycles-random-walk")
            sig, a, zb = native.transmission_slab(base)
            t = r["thickness"]
            for c in range(3):
                A = mat["albedo"][c]
                l = 1.5 * (a[c] - zb[c])
                # (no light from the library: nothing to measure against)
                ratio = r["t_rw"][c] / r["t_model"][c] \
                    if r["t_model"][c] > 0 else math.nan
                T4 = ratio * r["t_library"][c] / \
                    mat["transmission_color"][c] / mat["transmission_strength"]
                Ts = slab_T(sig[c], a[c], zb[c], t)
                W = A * T4  # the walk's light over the back light, about
                pts.append(dict(set=s, row=i, c=c, A=A, x=t / l, T4=T4,
                                Ts=Ts, W=W, slab=(sig[c] * l, a[c] / l,
                                                  zb[c] / l)))
    return pts


def unit_slab(A):
    """The slab's (s, a, zb) for l = 1 at albedo A, from the library."""
    m = {"profile": "burley", "radius": [1.0, 1.0, 1.0], "albedo": [A] * 3,
         "mapping": "cycles-random-walk", "transmission": "burley"}
    sig, a, zb = native.transmission_slab(m)
    l = 1.5 * (a[0] - zb[0])
    return sig[0] * l, a[0] / l, zb[0] / l


def curve_nodes(xs, ys, A):
    """ln T4 at X_NODES from one albedo's measured (x, ln T4), sorted."""
    s, a, zb = unit_slab(A)
    out = []
    for xn in X_NODES:
        if xn < xs[0]:
            k = (ys[1] - ys[0]) / (xs[1] - xs[0])
            v = min(ys[0] + k * (xn - xs[0]), -math.log(A))
            out.append(max(v, ys[0]))
        elif xn > xs[-1]:
            # the slab's decay, or the last segment's where steeper (the
            # walk's own limit on its steps cuts it off at high albedo)
            k = (ys[-1] - ys[-2]) / (xs[-1] - xs[-2])
            slab = math.log(slab_T(s, a, zb, xn)) - \
                math.log(slab_T(s, a, zb, xs[-1]))
            out.append(ys[-1] + min(slab, k * (xn - xs[-1])))
        else:
            out.append(float(np.interp(xn, xs, ys)))
    return out


def fit(runs, weights):
    """The table: ln T4 [len(A_NODES)][len(X_NODES)]; and the points it
    was fitted to (the first run's)."""
    table = []
    for A in A_NODES:
        curves = []
        for run, w in zip(runs, weights):
            for s in GRID_SETS:
                p = sorted((q for q in run if q["set"] == s and
                            abs(q["A"] - A) < 1e-4), key=lambda q: q["x"])
                if not p:
                    continue
                keep = []
                for q in p:  # up to the first point in the noise
                    if not (q["W"] >= FLOOR and q["T4"] > 0):
                        break
                    keep.append(q)
                xs = [q["x"] for q in keep]
                ys = [math.log(q["T4"]) for q in keep]
                curves.append((w, curve_nodes(xs, ys, A)))
        if not curves:
            raise SystemExit(f"no measurement at albedo {A}")
        wsum = sum(w for w, _ in curves)
        row = [sum(w * c[j] for w, c in curves) / wsum
               for j in range(len(X_NODES))]
        for j in range(1, len(row)):  # non-increasing in x
            row[j] = min(row[j], row[j - 1])
        table.append(row)
    return table


def evaluate(table, x, A):
    """The table as the library reads it (sss_transmission.c, walk4_T)."""
    A = min(max(A, A_NODES[0]), A_NODES[-1])
    i = int(np.searchsorted(A_NODES, A, side="right")) - 1
    i = min(i, len(A_NODES) - 2)
    f = (A - A_NODES[i]) / (A_NODES[i + 1] - A_NODES[i])

    def row(k):
        r = table[k]
        if x >= X_NODES[-1]:
            s, a, zb = unit_slab(A_NODES[k])
            return r[-1] + math.log(slab_T(s, a, zb, x)) - \
                math.log(slab_T(s, a, zb, X_NODES[-1]))
        return float(np.interp(x, X_NODES, r))
    return math.exp((1 - f) * row(i) + f * row(i + 1))


def residual(table, pts):
    d = [math.log(evaluate(table, q["x"], q["A"]) / q["T4"]) for q in pts]
    b = [math.log(q["Ts"] / q["T4"]) for q in pts]
    return (float(np.sqrt(np.mean(np.square(d)))), float(np.max(np.abs(d))),
            float(np.sqrt(np.mean(np.square(b)))), float(np.max(np.abs(b))),
            d)


def usable(pts):
    return [q for q in pts if q["W"] >= FLOOR and q["T4"] > 0]


def write_c(table, kind, path, info):
    name = KINDS[kind][0]
    lines = [
        f"/* sss_walk4_{kind}_table.c - generated by "
        "scripts/fit_transmission4.py",
        f" * --kind {kind}; do not edit. The slab transmittance of Blender "
        "4.x's",
        f" * {name}, ln T4 at x = t / l (columns, x) and albedo (rows,",
        " * albedo), measured on Blender 4.5.15",
        f" * ({info}). */",
        '#include "sss_transmission.h"', ""]
    lines += c_arrays(X_NODES, "SSS__WALK4_NX", table, "ln_t", 5)
    lines += ["", f"const sss__walk4_table sss__walk4_{kind} = "
              "{x, albedo, ln_t};"]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def c_arrays(x_nodes, x_macro, table, name, digits):
    """A generated table's C arrays: x (x_macro long), albedo (A_NODES)
    and name[albedo][x] = table."""
    lines = [f"static const float x[{x_macro}] = {{"]
    for k in range(0, len(x_nodes), 8):
        lines.append("\t" + ", ".join(f"{v!r}f" for v in x_nodes[k:k + 8]) +
                     ",")
    lines += ["};", "", "static const float albedo[SSS__WALK4_NA] = {"]
    lines += ["\t" + ", ".join(f"{v!r}f" for v in A_NODES) + ",", "};", ""]
    lines.append(f"static const float {name}[SSS__WALK4_NA][{x_macro}] = {{")
    for A, r in zip(A_NODES, table):
        vals = [f"{v:.{digits}f}f" for v in r]
        lines.append(f"\t{{ /* A {A:g} */")
        for k in range(0, len(vals), 6):
            lines.append("\t\t" + ", ".join(vals[k:k + 6]) + ",")
        lines.append("\t},")
    lines.append("};")
    return lines


def write_h(pts, kind, path, rms, worst):
    K = kind.upper()
    lines = [
        f"/* transmission4_{kind}_measured.h - generated by",
        f" * scripts/fit_transmission4.py --kind {kind}; do not edit.",
        f" * Blender 4.5.15's {KINDS[kind][0]} through back-lit slabs",
        " * (scripts/measure_transmission4.sh, 64x64, 1024 spp): albedo,",
        " * thickness over mean free path, T4 (the walk's light in the",
        " * library's terms); and the fit's residual in ln T4 over them. */",
        f"#define WALK4_{K}_FIT_RMS {rms:.4f}",
        f"#define WALK4_{K}_FIT_WORST {worst:.4f}",
        f"static const double walk4_{kind}_measured[][3] = {{"]
    for q in pts:
        lines.append(f"\t{{{q['A']:.4g}, {q['x']:.5g}, {q['T4']:.6g}}},")
    lines.append("};")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def main():
    p = argparse.ArgumentParser(prog="fit_transmission4.py")
    p.add_argument("run")
    p.add_argument("--replicate")
    p.add_argument("--kind", choices=sorted(KINDS), default="skin",
                   help="which walk the runs measured (default skin)")
    p.add_argument("--write", action="store_true")
    a = p.parse_args()
    runs = [load(a.run, GRID_SETS + CHECK_SETS, a.kind)]
    weights = [1.0]
    if a.replicate:
        runs.append(load(a.replicate, GRID_SETS + CHECK_SETS, a.kind))
        weights.append(48 * 48 / (64 * 64))
    grid = [q for q in runs[0] if q["set"] in GRID_SETS]
    check = [q for q in runs[0] if q["set"] in CHECK_SETS]
    table = fit([[q for q in r if q["set"] in GRID_SETS] for r in runs],
                weights)
    print("ln T4, rows A", A_NODES, "columns x", X_NODES)
    for A, r in zip(A_NODES, table):
        print(f"{A:5g}", " ".join(f"{v:7.3f}" for v in r))
    fitted = usable(grid)
    rms, worst, brms, bworst, d = residual(table, fitted)
    print(f"fit over {len(fitted)} points (W >= {FLOOR:g}): ln(table / "
          f"walk) RMS {rms:.3f}, largest {worst:.3f}; the slab model "
          f"(before): RMS {brms:.3f}, largest {bworst:.3f}")
    ch = usable(check)
    if ch:
        crms, cworst, cb, cbw, _ = residual(table, ch)
        print(f"check (set e, {len(ch)} points): RMS {crms:.3f}, largest "
              f"{cworst:.3f}; slab model RMS {cb:.3f}, largest {cbw:.3f}")
    for q, e in sorted(zip(fitted, d), key=lambda z: -abs(z[1]))[:5]:
        print(f"  worst: A {q['A']:.2f} x {q['x']:.2f} T4 {q['T4']:.4g} "
              f"ln ratio {e:+.3f}")
    if a.replicate:
        other = {(q["set"], q["row"], q["c"]): q for q in runs[1]}
        spread = []
        for q in usable(runs[0]):
            o = other.get((q["set"], q["row"], q["c"]))
            if o and o["T4"] > 0:
                spread.append((q["W"], abs(math.log(q["T4"] / o["T4"]))))
        for lo, hi in ((1e-1, 1.0), (1e-2, 1e-1), (1e-3, 1e-2),
                       (FLOOR, 1e-3)):
            s = [v for w, v in spread if lo <= w < hi]
            if s:
                print(f"noise, W in [{lo:g}, {hi:g}): |ln 64x64 / 48x48| "
                      f"median {np.median(s):.3f}, largest {max(s):.3f} "
                      f"({len(s)} points)")
    if a.write:
        info = (f"fit residual in ln T4: RMS {rms:.3f}, largest "
                f"{worst:.3f} over {len(fitted)} points")
        c_path = os.path.join("csrc", f"sss_walk4_{a.kind}_table.c")
        h_path = os.path.join("tests", f"transmission4_{a.kind}_measured.h")
        write_c(table, a.kind, os.path.join(ROOT, c_path), info)
        write_h(fitted, a.kind, os.path.join(ROOT, h_path), rms, worst)
        print(f"wrote {c_path}, {h_path}")


if __name__ == "__main__":
    main()
