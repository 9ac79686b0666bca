"""The plot of the trade at equal wall time, ours + OIDN against the
denoised random walk (make compare's and make error-budget's time.png);
no Blender needed."""
import textwrap


def draw_time_plot(path, line, ours, walk, result, ours_label, ylabel):
    """The plot of time_plot: ours and walk [(seconds, error, samples)],
    result compare_metrics.equal_time's on them, line its summary line
    (the title)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7.5, 5))
    drawn = []
    for pts, style, label in (
            (walk, "o-", "Cycles random walk + OIDN"),
            (ours, "s-", ours_label)):
        pts = sorted(p for p in pts if p[1] > 0)
        if not pts:
            continue
        drawn += pts
        ax.plot([p[0] for p in pts], [p[1] for p in pts], style,
                label=label)
        for t, e, n in pts:
            ax.annotate(f"{n}", (t, e), fontsize=7, xytext=(3, 3),
                        textcoords="offset points")
    if drawn:
        right = max(p[0] for p in drawn) * 1.5
        for i, (a, b) in enumerate(result["intervals"]):
            ax.axvspan(a, min(b, right), color="C1", alpha=0.12,
                       label="ours + OIDN ahead" if i == 0 else None)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.legend(fontsize=8, loc="best")
    ax.set_xlabel("wall time, s (render + SSS post-process + OIDN; "
                  "labels: samples)")
    ax.set_ylabel(ylabel)
    ax.set_title("\n".join(textwrap.wrap(line, 90)), fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
