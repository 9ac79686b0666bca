"""The pictures of make compare (compare.py): the contact sheet (one crop
and one exposure for every image, with its error heat-map against the
reference), the plot of error against time, and the trade at equal wall
time of ours + OIDN against the denoised random walk (time.png)."""
import numpy as np

from compare_metrics import crop_box
from compare_report import equal_time, err
from trade_plot import draw_time_plot


def groups(bench):
    """Rows of the sheet: random walk, then each (renderer, samples)."""
    out = [("Cycles random walk", [r for r in bench.rows
                                   if r["method"].startswith("random")])]
    seen = []
    for r in bench.rows:
        key = (r["renderer"], r["samples"])
        if r["method"].startswith("random") or key in seen:
            continue
        seen.append(key)
        label = f"Cycles SSS off {key[1]} spp" if key[0] == "cycles" else \
            f"EEVEE {key[1]} spp"
        out.append((label, [x for x in bench.rows if
                            (x["renderer"], x["samples"]) == key and not
                            x["method"].startswith("random")]))
    return out


def contact_sheet(bench, args, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    y0, y1, x0, x1 = crop_box(bench.mask)
    rows = groups(bench)
    ncol = max(len(g) for _, g in rows)
    aspect = (y1 - y0) / max(1, x1 - x0)
    cw = 2.3
    fig, axes = plt.subplots(2 * len(rows), ncol, squeeze=False,
                             figsize=(cw * ncol + 0.8, 2 * len(rows) *
                                      (cw * aspect + 0.4) + 0.5),
                             layout="constrained")
    ref = next(r for r in bench.rows if r["method"].endswith("(ref)"))
    heat_max = 0.25
    im = None
    for gi, (label, items) in enumerate(rows):
        for ci in range(ncol):
            a, b = axes[2 * gi, ci], axes[2 * gi + 1, ci]
            a.axis("off")
            b.axis("off")
            if ci >= len(items):
                continue
            r = items[ci]
            img = r["image"][y0:y1, x0:x1] * bench.exposure
            a.imshow(np.clip(img, 0, 1) ** (1 / 2.2), interpolation="nearest")
            a.set_title(f"{label}\n{r['method']}  "
                        f"{r['total_s']:.1f} s", fontsize=7)
            err = np.abs(r["image"] - ref["image"]).mean(axis=2)[y0:y1,
                                                               x0:x1]
            im = b.imshow(err * bench.exposure, cmap="inferno", vmin=0,
                          vmax=heat_max, interpolation="nearest")
            b.set_title(f"|error| RMSE {r['rmse']:.3g} SSIM "
                        f"{r['ssim']:.3f}", fontsize=6.5)
    fig.suptitle(f"{args.name}: same crop and exposure for every image\n"
                 f"heat maps: mean |error| per pixel vs random walk "
                 f"{ref['samples']} spp (x exposure, 0 to {heat_max})",
                 fontsize=8)
    if im is not None:
        fig.colorbar(im, ax=axes.ravel().tolist(), fraction=0.02,
                     shrink=0.5)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot(bench, args, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    series = {}
    for r in bench.rows:
        if r["method"].endswith("(ref)"):
            continue
        series.setdefault((r["renderer"], r["method"]), []).append(r)
    for ax, key, title in ((axes[0], "rmse", "RMSE, full resolution"),
                           (axes[1], "rmse_q", "RMSE, quarter resolution")):
        title += " (reference noise removed)" if bench.ref_halves else ""
        for (renderer, method), rs in series.items():
            rs = sorted(rs, key=lambda r: r["total_s"])
            t = [r["total_s"] for r in rs]
            e = [max(err(r, key), 1e-6) for r in rs]
            style = "o-" if renderer == "cycles" else "s--"
            ax.plot(t, e, style, label=f"{renderer} {method}")
            for r in rs:
                ax.annotate(str(r["samples"]), (r["total_s"],
                                                max(err(r, key), 1e-6)),
                            fontsize=6, xytext=(3, 3),
                            textcoords="offset points")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("total time, s (render + SSS post-process)")
        ax.set_ylabel("error vs reference")
        ax.set_title(f"{args.name}: {title}")
        ax.grid(True, which="both", alpha=0.3)
    axes[1].legend(fontsize=7, loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def time_plot(bench, args, path):
    """Error at quarter resolution against wall time (render + SSS +
    OIDN), log axes: the denoised random walk and ours + OIDN (default
    method) through their sample counts, the times where ours is ahead
    shaded, and the summary's line on it as the title."""
    line, ours, walk, result = equal_time(bench, args)
    draw_time_plot(path, line, ours, walk, result,
                   f"SSS off + libsss ({bench.default_method}) + OIDN",
                   "RMSE at quarter resolution vs reference" +
                   (" (its noise removed)" if bench.ref_halves else ""))
