"""The report's figure, the paper's Fig. 4: best score so far against samples, candidate
evaluations or seconds, one panel per task, every run of every variant."""

from __future__ import annotations

from matplotlib.figure import Figure

from colmo.report.runs import AXES, Variant
from colmo.report.tables import dims
from colmo.track import draw_best_so_far

_GFO_COLORS = ("tab:blue", "tab:green", "tab:purple", "tab:orange", "tab:brown", "tab:cyan")


def figure(tasks: dict[str, list[Variant]], axis: str = "samples") -> Figure:
    """Fig. 4: one panel per task, every run of every variant, against `axis`."""
    fig = Figure(figsize=(6.5 * len(tasks), 4.8), layout="constrained")
    axes = fig.subplots(1, len(tasks), squeeze=False)[0]
    for ax, (task, variants) in zip(axes, tasks.items()):
        tuned = iter(_GFO_COLORS)
        for variant in variants:
            color = "tab:red" if not variant.gfo else next(tuned, "0.3")
            for index, run in enumerate(variant.runs):
                label = f"{variant.name} ({len(variant.runs)} seeds)" if index == 0 else None
                draw_best_so_far(ax, run.x, run.best, run.per_island, color, label)
        first = variants[0].runs[0]
        if first.target is not None:
            ax.axhline(first.target, color="0.4", linestyle=":", linewidth=1.2, label=f"target {first.target:g}")
        observation_size, action_size = dims(variants)
        ax.set_title(f"{task} (state {observation_size}, action {action_size})")
        ax.set_xlabel(AXES[axis][1])
        ax.set_ylabel("best score so far (dashed: per island)")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncols=3, frameon=False)  # below: never over the curves
    return fig
