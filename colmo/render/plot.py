"""The plot of an episode: observations, actions and cumulative reward over time, as a PNG.

Drawn from a recorded `colmo.trace.EpisodeTrace` alone. Matplotlib is imported when a plot is
drawn, not with this module, and only its object-oriented API is used: no pyplot, so no GUI
backend and no global figure state.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Optional

import numpy as np

from colmo.trace import EpisodeTrace

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

_LINE_PLOT_MAX_DIMS = 10  # more signals than this are drawn as a heat map, one row each
_HEAT_MAP_LABELLED_ROWS = 30  # up to this many rows, each row's tick shows its scale


def plot_episode(trace: EpisodeTrace, path: Path, title: str, applied: Optional[np.ndarray] = None) -> Path:
    """Write `episode_figure` as a PNG (1100 x 900); return its path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    episode_figure(trace, title, applied).savefig(path, dpi=100)
    return path


def episode_figure(trace: EpisodeTrace, title: str, applied: Optional[np.ndarray] = None) -> Figure:
    """The observations, actions and cumulative reward over the episode. `applied`: the actions as the simulator applied them (clamped to
    the actuators' ranges), drawn instead of the policy's, whose raw values, where they differ,
    are drawn beside them as thin dashed lines on a scale of their own (the right axis): a raw
    output of ±100 clamped to ±1 must not flatten the action that was applied.

    Up to 10 signals are drawn as labelled lines; more (the cheetah's 17 observations, the
    quadruped's 78) as a heat map with one row per signal, each row coloured from its own minimum
    to its own maximum, which its tick label gives when there are at most 30 rows.
    """
    from matplotlib.figure import Figure

    timestep = trace.control_timestep
    times = np.arange(trace.steps + 1) * (timestep or 1.0)
    figure = Figure(figsize=(11, 9), layout="constrained")
    obs_axes, action_axes, reward_axes = figure.subplots(3, 1, sharex=True, height_ratios=(3, 2, 1.4))
    _plot_signals(figure, obs_axes, times, trace.observations, "observation", "obs")
    # An action holds for its control period: drawn as steps to the next observation's time.
    actions = trace.actions if applied is None else applied
    _plot_signals(figure, action_axes, times, np.vstack([actions, actions[-1:]]), "action", "act", steps=True)
    if applied is not None and not np.array_equal(applied, trace.actions):
        raw = np.vstack([trace.actions, trace.actions[-1:]])
        if raw.shape[1] <= _LINE_PLOT_MAX_DIMS:
            raw_axes = action_axes.twinx()
            for i in range(raw.shape[1]):
                raw_axes.plot(times, raw[:, i], linewidth=0.7, linestyle="--", color="0.5", drawstyle="steps-post")
            raw_axes.set_ylabel("raw output (dashed)", color="0.4")
        action_axes.set_title("applied (clamped to the actuator range), left axis; dashed: the policy's raw output, right axis", fontsize=9, loc="left")
    reward_axes.plot(times, np.concatenate([[0.0], np.cumsum(trace.rewards)]), color="tab:green", linewidth=1.5)
    reward_axes.set_ylabel("cumulative reward")
    reward_axes.set_title(f"return {trace.episode_return:.4g} over {trace.steps} steps", fontsize=9, loc="left")
    reward_axes.grid(alpha=0.3)
    reward_axes.set_xlabel("time (s)" if timestep else "step")
    reward_axes.set_xlim(times[0], times[-1])
    figure.suptitle(title)
    return figure


def _plot_signals(figure: Figure, axes: Axes, times: np.ndarray, values: np.ndarray, label: str, short: str, steps: bool = False) -> None:
    dims = values.shape[1]
    if dims <= _LINE_PLOT_MAX_DIMS:
        for i in range(dims):
            axes.plot(times, values[:, i], linewidth=1.1, label=f"{short}[{i}]", drawstyle="steps-post" if steps else "default")
        axes.legend(loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=8, frameon=False)
        axes.set_ylabel(label)
        axes.grid(alpha=0.3)
        return
    # Each row spans its own range: signals differ in scale by orders of magnitude and many sit
    # far from zero (the A1's joint angles), so a shared or zero-centred scale would hide them.
    low, high = values.min(axis=0), values.max(axis=0)
    span = np.where(high > low, high - low, 1.0)
    if steps:  # one column per control period, from its start to the next one's
        cells, left, right = values[:-1], times[0], times[-1]
    else:  # one column per sample, centred on its time
        half = (times[1] - times[0]) / 2
        cells, left, right = values, times[0] - half, times[-1] + half
    image = axes.imshow(
        ((cells - low) / span).T, aspect="auto", cmap="viridis", vmin=0, vmax=1, extent=(left, right, dims - 0.5, -0.5)
    )
    if dims <= _HEAT_MAP_LABELLED_ROWS:
        axes.set_yticks(range(dims), [f"{i} [{lo:.2g}, {hi:.2g}]" for i, (lo, hi) in enumerate(zip(low, high))], fontsize=7)
    axes.set_ylabel(f"{label} index")
    colorbar = figure.colorbar(image, ax=axes, pad=0.01, fraction=0.03, ticks=(0, 1))
    colorbar.ax.set_yticklabels(["row min", "row max"], fontsize=8)
