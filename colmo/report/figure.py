"""The report's figure, the paper's Fig. 4: best score so far against model calls, candidate
evaluations or seconds, one panel per task; per variant (one colour each, in the legend) each
seed's curve thin on its own clock, and the mean over seeds with a band from the lowest to the
highest seed where every seed has data. A curve of one point (a search that ended after its
first batch) is drawn as a marker. `budget_note` says whether the runs' budgets were equal on
the axis (the caption)."""

from __future__ import annotations

from typing import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from colmo.report.selection import AXES, Variant
from colmo.report.tables import dims
from colmo.track import STOP_REASON_TAG

EQUAL_WITHIN = 1.1  # budgets whose ends differ by at most 10% are equal for the caption
COLORS = ("tab:red", "tab:blue", "tab:green", "tab:purple", "tab:orange", "tab:brown", "tab:cyan", "tab:olive", "tab:pink", "0.3")


def draw_seeds(ax: Axes, name: str, seeds: Sequence[tuple[Sequence[float], Sequence[float]]], color: str) -> None:
    """One variant's best-so-far curves, `(x, best)` per seed: each seed thin, on its own x;
    their mean (a step curve) and the band between the lowest and highest seed only where every
    seed has data, from the latest first point to the earliest last one, so that the mean never
    mixes seeds that have started or ended with those that have not; a single point as a marker."""
    label = f"{name} ({len(seeds)} seed{'s' if len(seeds) != 1 else ''})"
    for x, best in seeds:
        ax.plot(x, best, color=color, linewidth=0.8, alpha=0.5, drawstyle="steps-post", marker="o" if len(x) == 1 else None)
    xs = [np.asarray(x, dtype=float) for x, _ in seeds]
    grid = np.unique(np.concatenate(xs))
    grid = grid[(grid >= max(x[0] for x in xs)) & (grid <= min(x[-1] for x in xs))]
    if not len(grid):  # no x where every seed has data: the seeds alone, labelled
        ax.plot([], [], color=color, linewidth=2.2, label=f"{label}, no common range")
        return
    # Best so far is a step function: each seed's value at x is its last one at or before x.
    values = np.array([np.asarray(best, dtype=float)[np.searchsorted(x, grid, side="right") - 1] for x, (_, best) in zip(xs, seeds)])
    mean = values.mean(axis=0)
    if len(grid) == 1:
        ax.plot(grid, mean, color=color, linestyle="none", marker="o", markersize=8, label=label)
    else:
        ax.plot(grid, mean, color=color, linewidth=2.2, drawstyle="steps-post", label=label)
    if len(seeds) > 1:
        ax.fill_between(grid, values.min(axis=0), values.max(axis=0), color=color, alpha=0.18, step="post", linewidth=0)


# The limit that gives every run of a sweep the same budget on an axis, and the stop reason of a
# run that used it (`colmo.track.STOP_REASON_TAG`).
_LIMITS = {"samples": ("search.max_samples", "max_samples"), "seconds": ("search.max_seconds", "max_seconds")}


def budget_note(tasks: dict[str, list[Variant]], axis: str) -> str:
    """Whether the runs had equal budgets on `axis`: every run given the same limit on it and
    stopped by that limit; else where they all end at the same x (within 10%); else the range
    of their ends, and where to compare."""
    runs = [run for variants in tasks.values() for variant in variants for run in variant.runs]
    ends = [run.x[-1] for run in runs]
    unit = AXES[axis][1]
    if axis in _LIMITS:
        param, reason = _LIMITS[axis]
        limits = {run.run.data.params.get(param) for run in runs}
        if len(limits) == 1 and all(run.run.data.tags.get(STOP_REASON_TAG) == reason for run in runs):
            return f"Equal budgets on this axis: every run was given {param}={limits.pop()} and stopped by it."
    if min(ends) == max(ends):
        return f"Equal budgets on this axis: every run ends at {min(ends):g} {unit}."
    if max(ends) <= EQUAL_WITHIN * min(ends):  # runs stopped by a time limit never end at the same second
        return f"Equal budgets on this axis (within {EQUAL_WITHIN - 1:.0%}): the runs end between {min(ends):.4g} and {max(ends):.4g} {unit}."
    return (
        f"Unequal budgets on this axis: the runs end between {min(ends):.4g} and {max(ends):.4g} {unit}; "
        "a variant's mean and band stop where its first seed ends, and variants compare only where both have data."
    )


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
