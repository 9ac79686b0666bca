"""The scores and tables of make compare (compare.py): each image's error
against the reference (compare_metrics.py), results.csv and results.md,
and the summary: the error cut of our methods against no SSS, the
random-walk sample count that reaches the same error, and up to what wall
time ours + OIDN is ahead of the denoised random walk."""
import csv
import math
import os

import compare_metrics as cm
from compare_runs import DENOISED, DENOISED_PASSES


COLUMNS = ("scene", "renderer", "method", "samples", "render_s", "post_s",
           "io_s", "total_s", "rmse", "rel_mae", "rmse_q", "rel_mae_q",
           "rmse_c", "rmse_q_c", "rmse_in_c", "ssim", "max_err")


def cut(after, before):
    """% less error after than before."""
    return 100 * (1 - after / before) if before > 0 else float("nan")


def err(r, key):
    """r's error `key` ("rmse" or "rmse_q") against the noise-free image
    the reference estimates where measured, else against the reference."""
    c = r.get(key + "_c", float("nan"))
    return c if math.isfinite(c) else r[key]


def score(bench, args):
    ref = next(r for r in bench.rows if r["method"].endswith("(ref)"))
    mask = bench.mask
    bench.exposure = cm.exposure_for(ref["image"], mask)
    for r in bench.rows:
        r.update(cm.all_metrics(r["image"], ref["image"], mask,
                                bench.exposure, bench.ref_halves,
                                bench.edges))
        r["scene"] = args.name
    return ref


def fmt(v, col):
    if isinstance(v, float):
        if col.endswith("_s"):
            return f"{v:.3f}"
        return f"{v:.5g}"
    return str(v)


def write_tables(bench, args, summary):
    with open(os.path.join(args.out, "results.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(COLUMNS)
        for r in bench.rows:
            w.writerow([fmt(r[c], c) for c in COLUMNS])
    lines = [f"# SSS comparison: {args.name}", "",
             f"Scene `{args.scene}`, {args.resolution[0]}x"
             f"{args.resolution[1]}, reference: Cycles random walk at "
             f"{max(args.rw_samples)} samples (two renders of half as "
             "many with two other seeds, averaged). Errors over "
             f"the {int(bench.mask.sum())} scattering pixels, linear "
             "light; `_q`: at quarter resolution (4x4 boxes); `_c`: against "
             "the noise-free image the reference estimates (its own noise, "
             "measured from the difference of its halves, removed; the "
             "summary uses these); `rmse_in_c`: `rmse_c` away from "
             "silhouettes (pixels next to another material or a depth "
             "step). Times in "
             "seconds, measured in this run; post = the library's scatter "
             "time (io = its EXR read + write, not counted in total).", "",
             "| " + " | ".join(COLUMNS) + " |",
             "|" + "---|" * len(COLUMNS)]
    for r in bench.rows:
        lines.append("| " + " | ".join(fmt(r[c], c) for c in COLUMNS) +
                     " |")
    if bench.skipped:
        lines += ["", "Skipped: " + "; ".join(bench.skipped)]
    lines += ["", "## Summary", "", "```", *summary, "```", "",
              "![contact sheet](sheet.png)", "", "![error against time]"
              "(plot.png)", ""]
    with open(os.path.join(args.out, "results.md"), "w") as f:
        f.write("\n".join(lines))
    with open(os.path.join(args.out, "summary.txt"), "w") as f:
        f.write("\n".join(summary) + "\n")


def summarise(bench, args):
    rows = bench.rows
    rw = sorted((r for r in rows if r["method"] == "random-walk"),
                key=lambda r: r["samples"])
    rw_all = sorted((r for r in rows if r["renderer"] == "cycles" and
                     r["method"].startswith("random-walk")),
                    key=lambda r: r["samples"])
    ours = [m for m, _ in bench.methods]
    default = bench.default_method
    out = [f"scene {args.name}: error = RMSE over scattering pixels vs "
           f"random walk {max(args.rw_samples)} spp"
           + (" with its own noise removed (rmse_c)" if bench.ref_halves
              else "") + f"; default method {default}"]
    for renderer, counts in (("cycles", args.samples),
                             ("eevee", [args.eevee_samples])):
        for n in counts:
            base = next((r for r in rows if r["renderer"] == renderer and
                         r["method"] == "no-sss" and r["samples"] == n),
                        None)
            if base is None:
                continue
            cands = [r for r in rows if r["renderer"] == renderer and
                     r["samples"] == n and r["method"] in ours]
            if not cands:
                continue
            best = min(cands, key=lambda r: err(r, "rmse"))
            dflt = next((r for r in cands if r["method"] == default), best)
            out.append(f"  {renderer} {n} spp: no-sss RMSE "
                       f"{err(base, 'rmse'):.4g} ({base['total_s']:.2f} s)")
            ceiling = noise_ceiling(rows, base)
            if ceiling:
                out.append(f"    {ceiling}")
            for label, r in (("default", dflt), ("best", best)):
                red = cut(err(r, "rmse"), err(base, "rmse"))
                s, how = cm.interp_samples([x["samples"] for x in rw],
                                           [err(x, "rmse") for x in rw],
                                           err(r, "rmse"))
                t_rw = cm.time_at([x["samples"] for x in rw_all],
                                  [x["render_s"] for x in rw_all], s) \
                    if math.isfinite(s) else float("nan")
                out.append(
                    f"    {label:<7} {r['method']:<16} RMSE "
                    f"{err(r, 'rmse'):.4g}: {red:.1f} % less error than no-sss; "
                    f"random walk reaches it at ~{s:.0f} spp ({how}) "
                    f"in ~{t_rw:.2f} s; ours {r['total_s']:.2f} s "
                    f"(render {r['render_s']:.2f} + post "
                    f"{r['post_s']:.3f})")
                # At quarter resolution noise averages away, bias stays.
                sq, howq = cm.interp_samples([x["samples"] for x in rw],
                                             [err(x, "rmse_q") for x in rw],
                                             err(r, "rmse_q"))
                redq = cut(err(r, "rmse_q"), err(base, "rmse_q"))
                out.append(
                    f"      quarter res: RMSE {err(r, 'rmse_q'):.4g} vs no-sss "
                    f"{err(base, 'rmse_q'):.4g} ({redq:.1f} % less); random walk "
                    f"reaches it at ~{sq:.0f} spp ({howq})")
                if math.isfinite(r["rmse_in_c"]) and \
                        math.isfinite(base["rmse_in_c"]):
                    share = 100 * (bench.mask & ~bench.edges).sum() / \
                        bench.mask.sum()
                    out.append(
                        f"      away from silhouettes ({share:.0f} % of the "
                        f"pixels): RMSE {r['rmse_in_c']:.4g} vs no-sss "
                        f"{base['rmse_in_c']:.4g} ("
                        f"{cut(r['rmse_in_c'], base['rmse_in_c']):.1f} % less)")
            if renderer == "cycles":
                out += oidn_lines(rows, n, default)
    out += goal_lines(rows, default)
    for r in rows:
        if r["method"] == "eevee-sss":
            out.append(f"  eevee own SSS {r['samples']} spp: RMSE "
                       f"{err(r, 'rmse'):.4g} in {r['total_s']:.2f} s")
    out.append(equal_time(bench, args)[0])
    out += [f"  note: {n}" for n in bench.mesh_notes]
    return out


def equal_time_series(rows, default):
    """(ours, walk) for compare_metrics.equal_time: the default method and
    the random walk, both denoised (OIDN), as (total seconds, error at
    quarter resolution, samples) per sample count."""
    def series(method):
        return [(r["total_s"], err(r, "rmse_q"), r["samples"]) for r in rows
                if r["renderer"] == "cycles" and r["method"] == method]
    return series(default + DENOISED), series("random-walk" + DENOISED)


def equal_time(bench, args):
    """(the summary's line on the trade at equal wall time, ours, walk,
    compare_metrics.equal_time's result)."""
    ours, walk = equal_time_series(bench.rows, bench.default_method)
    result = cm.equal_time(ours, walk)
    return cm.equal_time_line(args.name, result, walk), ours, walk, result


def oidn_lines(rows, n, default):
    """The default method and SSS off, both denoised (OIDN), and the random
    walk denoised at the same samples."""
    def row(method):
        return next((r for r in rows if r["renderer"] == "cycles" and
                     r["method"] == method and r["samples"] == n), None)
    base, ours = row("no-sss" + DENOISED), row(default + DENOISED)
    if not (base and ours):
        return []
    rw = row("random-walk" + DENOISED)
    lines = [f"    with OIDN on both: {default}{DENOISED} RMSE "
             f"{err(ours, 'rmse'):.4g} vs no-sss{DENOISED} "
             f"{err(base, 'rmse'):.4g}: "
             f"{cut(err(ours, 'rmse'), err(base, 'rmse')):.1f} % less error"
             + (f"; random-walk{DENOISED} at {n} spp: RMSE "
                f"{err(rw, 'rmse'):.4g}" if rw else "")]
    passes = row(default + DENOISED_PASSES)
    if passes:
        lines.append(f"    light passes denoised before the blur: "
                     f"{default}{DENOISED_PASSES} RMSE "
                     f"{err(passes, 'rmse'):.4g} "
                     f"({cut(err(passes, 'rmse'), err(base, 'rmse')):.1f} % "
                     f"less error than no-sss{DENOISED})")
    return lines


def noise_ceiling(rows, base):
    """What the render's own noise leaves to win at base's sample count:
    its RMSE (compare_metrics.render_noise, from the no-sss errors at this
    and the next count) and the error reduction of a post-process with no
    bias at all that left that noise as it is. Scattering blurs only the
    diffuse light, so the noise of every other pass stays in the result;
    a blur also lowers the diffuse noise, which can take a method a little
    past this."""
    more = sorted((r for r in rows if r["renderer"] == base["renderer"] and
                   r["method"] == "no-sss" and
                   r["samples"] > base["samples"]),
                  key=lambda r: r["samples"])
    if not more:
        return ""
    noise = cm.render_noise(err(base, "rmse"), base["samples"],
                            err(more[0], "rmse"), more[0]["samples"])
    if not math.isfinite(noise):
        return ""
    head = (f"the render's own noise is {noise:.4g} RMSE here (from the "
            f"no-sss errors at {base['samples']} and {more[0]['samples']} "
            "spp)")
    if noise >= 0.95 * err(base, "rmse"):
        return (f"{head}: about all of its error; only blurring its diffuse "
                "noise can lower it")
    return (f"{head}: with no bias left and that noise as it is, a "
            f"post-process would have {cut(noise, err(base, 'rmse')):.1f} % "
            "less error (blurring the diffuse noise adds a little)")


GOAL_CUT = 30.0        # % less error than the render without SSS ...


GOAL_TIME_SHARE = 0.05  # ... in at most this share of the reference's time


def goal_lines(rows, default):
    """The product's accuracy goal, judged on the most samples whose render
    plus post-process stays within GOAL_TIME_SHARE of the reference's
    render time (Cycles rows)."""
    ref = next(r for r in rows if r["method"].endswith("(ref)"))
    budget = GOAL_TIME_SHARE * ref["render_s"]
    ours = [r for r in rows if r["renderer"] == "cycles" and
            r["method"] == default and r["total_s"] <= budget]
    head = (f"  goal: {GOAL_CUT:.0f} % less error than no-sss within "
            f"{100 * GOAL_TIME_SHARE:.0f} % of the reference's "
            f"{ref['render_s']:.1f} s")
    if not ours:
        return [f"{head}: no render with material SSS off fits in "
                f"{budget:.2f} s; measure with more reference samples"]
    r = max(ours, key=lambda r: r["samples"])
    base = next(x for x in rows if x["renderer"] == "cycles" and
                x["method"] == "no-sss" and x["samples"] == r["samples"])
    full, full_q = cut(err(r, "rmse"), err(base, "rmse")), \
        cut(err(r, "rmse_q"), err(base, "rmse_q"))
    raw, raw_q = cut(r["rmse"], base["rmse"]), cut(r["rmse_q"], base["rmse_q"])
    inner = cut(r["rmse_in_c"], base["rmse_in_c"])
    ceiling = noise_ceiling(rows, base)
    return [f"{head}: {'met' if full >= GOAL_CUT else 'missed'} at "
            f"{r['samples']} spp ({100 * r['total_s'] / ref['render_s']:.1f}"
            f" % of it): {full:.1f} % less at full resolution, {full_q:.1f} "
            f"% at quarter resolution, {inner:.1f} % away from silhouettes "
            f"(against the reference itself, with its noise: {raw:.1f} % and "
            f"{raw_q:.1f} %)"] + \
        ([f"    {ceiling}"] if ceiling else [])
