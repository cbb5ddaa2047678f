"""The report's figure, the paper's Fig. 4: best score so far against model calls, candidate
evaluations or seconds, one panel per task; per variant (one colour each, in the legend) the
mean over seeds with a band from the lowest to the highest seed, and each seed's curve thin.
A curve of one point (a search that ended after its first batch) is drawn as a marker."""

from __future__ import annotations

from typing import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from colmo.report.selection import AXES, Variant
from colmo.report.tables import dims

COLORS = ("tab:red", "tab:blue", "tab:green", "tab:purple", "tab:orange", "tab:brown", "tab:cyan", "tab:olive", "tab:pink", "0.3")


def draw_seeds(ax: Axes, name: str, seeds: Sequence[tuple[Sequence[float], Sequence[float]]], color: str) -> None:
    """One variant's best-so-far curves, `(x, best)` per seed: their mean (a step curve on the
    union of their x), the band between the lowest and highest seed, and each seed thin; a
    single point as a marker."""
    label = f"{name} ({len(seeds)} seed{'s' if len(seeds) != 1 else ''})"
    for x, best in seeds:
        ax.plot(x, best, color=color, linewidth=0.8, alpha=0.5, drawstyle="steps-post", marker="o" if len(x) == 1 else None)
    grid = np.unique(np.concatenate([np.asarray(x, dtype=float) for x, _ in seeds]))
    # Best so far is a step function: each seed's value at x is its last one at or before x
    # (undefined before its first batch, and held after its last).
    values = np.full((len(seeds), len(grid)), np.nan)
    for row, (x, best) in enumerate(seeds):
        index = np.searchsorted(np.asarray(x, dtype=float), grid, side="right") - 1
        values[row, index >= 0] = np.asarray(best)[index[index >= 0]]
    defined = ~np.isnan(values).all(axis=0)
    grid, values = grid[defined], values[:, defined]
    mean = np.nanmean(values, axis=0)
    if len(grid) == 1:
        ax.plot(grid, mean, color=color, linestyle="none", marker="o", markersize=8, label=label)
    else:
        ax.plot(grid, mean, color=color, linewidth=2.2, drawstyle="steps-post", label=label)
    if len(seeds) > 1:
        ax.fill_between(grid, np.nanmin(values, axis=0), np.nanmax(values, axis=0), color=color, alpha=0.18, step="post", linewidth=0)


def figure(tasks: dict[str, list[Variant]], axis: str = "samples") -> Figure:
    """Fig. 4: one panel per task, one colour per variant, against `axis`."""
    fig = Figure(figsize=(6.5 * len(tasks), 4.8), layout="constrained")
    axes = fig.subplots(1, len(tasks), squeeze=False)[0]
    for ax, (task, variants) in zip(axes, tasks.items()):
        for index, variant in enumerate(variants):
            draw_seeds(ax, variant.name, [(run.x, run.best) for run in variant.runs], COLORS[index % len(COLORS)])
        first = variants[0].runs[0]
        if first.target is not None:
            ax.axhline(first.target, color="0.4", linestyle=":", linewidth=1.2, label=f"target {first.target:g}")
        observation_size, action_size = dims(variants)
        ax.set_title(f"{task} (state {observation_size}, action {action_size})")
        ax.set_xlabel(AXES[axis][1])
        ax.set_ylabel("best score so far")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncols=2, frameon=False)  # below: never over the curves
    return fig
