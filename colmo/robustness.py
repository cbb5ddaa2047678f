"""Robustness report: a policy's score over a grid of model-mismatch magnitudes.

Each relative factor of `colmo.config.PerturbConfig` (mass and inertia, damping, dry friction,
geom friction, actuator gain, observation and action noise) is raised alone to each magnitude,
then all of them together; the control delay, counted in steps rather than as a fraction, has
its own short grid. Every point is scored by the caller's `score` (the referee on held-out
episodes, in `colmo-evaluate robustness=true`) on the same episode seeds, whose perturbation
draws differ only in scale from one magnitude to the next, so the curves are paired and the
report is a deterministic function of the policy and the seeds. This module knows no front end.
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable, Optional, Sequence

from colmo.config import PerturbConfig
from colmo.environments.perturb import PERTURB_OPTION, with_perturbation
from colmo.evaluation import Evaluation, Evaluator

FACTORS = ("mass", "damping", "frictionloss", "friction", "gain", "obs_noise", "action_noise")
ALL = "all"
FILES = ("robustness.json", "robustness.csv", "robustness.png")  # what `save` writes
HEADLINE_MAGNITUDE = 0.1  # `headline` quotes every factor together at this magnitude


@dataclass(frozen=True)
class Point:
    """One scored perturbation: which factor (or `all`, or `delay`), how large, the outcome."""

    factor: str
    magnitude: float
    evaluation: Evaluation

    @property
    def score(self) -> Optional[float]:
        return None if self.evaluation.failure else self.evaluation.score


@dataclass(frozen=True)
class RobustnessReport:
    nominal: Evaluation
    magnitudes: tuple[float, ...]  # the nonzero relative magnitudes
    points: tuple[Point, ...]  # every factor at every magnitude, then `all`, then the delays
    delays: tuple[int, ...]

    @property
    def nominal_score(self) -> Optional[float]:
        return Point("nominal", 0.0, self.nominal).score

    def score(self, factor: str, magnitude: float) -> Optional[float]:
        return next(p.score for p in self.points if p.factor == factor and p.magnitude == magnitude)

    def entries(self) -> list[dict]:
        """One entry per magnitude, nominal (0) first: the score of each factor and of all
        together; then one entry per delay (`delay_steps`)."""
        rows = [{"magnitude": 0.0, **{name: self.nominal_score for name in (*FACTORS, ALL)}}]
        rows += [{"magnitude": m, **{name: self.score(name, m) for name in (*FACTORS, ALL)}} for m in self.magnitudes]
        return rows

    def delay_entries(self) -> list[dict]:
        return [{"delay_steps": 0, "score": self.nominal_score}] + [{"delay_steps": k, "score": self.score("delay", k)} for k in self.delays]

    def failures(self) -> list[str]:
        return [f"{p.factor} {p.magnitude:g}: {p.evaluation.failure}" for p in self.points if p.evaluation.failure]

    def headline(self) -> dict[str, Optional[float]]:
        """A few numbers that summarize the report (the metrics a tracker logs): the nominal
        score, the worst over every grid point that scored, every factor together at 10% (None
        when the grid lacks that magnitude) and the number of points that failed."""
        scores = [score for score in (self.nominal_score, *(p.score for p in self.points)) if score is not None]
        together = self.score(ALL, HEADLINE_MAGNITUDE) if HEADLINE_MAGNITUDE in self.magnitudes else None
        return {
            "robustness_nominal": self.nominal_score, "robustness_worst": min(scores, default=None),
            "robustness_all_10": together, "robustness_failures": float(len(self.failures())),
        }


def grid(magnitudes: Sequence[float], delays: Sequence[int]) -> tuple[tuple[float, ...], tuple[int, ...]]:
    """The nonzero magnitudes and delays of a grid, each once and in increasing order."""
    return tuple(sorted({float(m) for m in magnitudes if m > 0})), tuple(sorted({int(k) for k in delays if k > 0}))


def grid_points(magnitudes: Sequence[float], delays: Sequence[int]) -> int:
    """How many perturbations `robustness_report` scores, the nominal model included."""
    relative, steps = grid(magnitudes, delays)
    return 1 + (len(FACTORS) + 1) * len(relative) + len(steps)


def perturbed(evaluator: Evaluator, perturb: PerturbConfig) -> Evaluator:
    """`evaluator` on the nominal model (without the training perturbation of a search under
    `task.perturb`) with the perturbation `perturb` instead: one point of a grid."""
    nominal = {name: value for name, value in evaluator.env if name != PERTURB_OPTION}
    return replace(evaluator, env=tuple(sorted(with_perturbation(nominal, perturb).items())))


def robustness_report(
    score: Callable[[PerturbConfig], Evaluation], magnitudes: Sequence[float], delays: Sequence[int] = (),
) -> RobustnessReport:
    """Score the nominal model, every factor alone and all together at each of `magnitudes`,
    and each control delay of `delays` steps."""
    magnitudes, delays = grid(magnitudes, delays)
    points = [Point(name, m, score(PerturbConfig(**{name: m}))) for name in FACTORS for m in magnitudes]
    points += [Point(ALL, m, score(PerturbConfig(**{name: m for name in FACTORS}))) for m in magnitudes]
    points += [Point("delay", k, score(PerturbConfig(delay=k))) for k in delays]
    return RobustnessReport(score(PerturbConfig()), magnitudes, tuple(points), delays)


def _cell(value: Optional[float]) -> str:
    return "failed" if value is None or not math.isfinite(value) else f"{value:.1f}"


def table(report: RobustnessReport) -> str:
    """The scores as a plain-text table: one row per magnitude, one column per factor."""
    names = (*FACTORS, ALL)
    lines = ["magnitude " + " ".join(f"{name:>12}" for name in names)]
    for entry in report.entries():
        lines.append(f"{entry['magnitude']:>9.0%} " + " ".join(f"{_cell(entry[name]):>12}" for name in names))
    if report.delays:
        lines.append("delay (steps) " + " ".join(f"{e['delay_steps']:>3}: {_cell(e['score'])}" for e in report.delay_entries()))
    return "\n".join(lines)


def save(report: RobustnessReport, directory: Path, title: str) -> list[Path]:
    """Write `robustness.json`, `robustness.csv` and `robustness.png` (score against magnitude,
    one line per factor; the delay grid in a second panel) into `directory`."""
    from matplotlib.figure import Figure

    directory.mkdir(parents=True, exist_ok=True)
    paths = [directory / name for name in FILES]
    paths[0].write_text(json.dumps({"robustness": report.entries(), "delay": report.delay_entries()}, indent=1) + "\n")
    with paths[1].open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(["factor", "magnitude", "score"])
        for entry in report.entries():
            writer.writerows([name, entry["magnitude"], entry[name]] for name in (*FACTORS, ALL))
        writer.writerows(["delay_steps", e["delay_steps"], e["score"]] for e in report.delay_entries()[1:])
    figure = Figure(figsize=(10, 4), layout="constrained")
    axes, delay_axes = figure.subplots(1, 2, width_ratios=(3, 1))
    entries = report.entries()
    x = [100 * e["magnitude"] for e in entries]
    for name in (*FACTORS, ALL):
        y = [math.nan if e[name] is None else e[name] for e in entries]
        axes.plot(x, y, marker="o", label=name, linewidth=2.5 if name == ALL else 1.2, color="black" if name == ALL else None)
    axes.set(xlabel="perturbation magnitude (%)", ylabel="held-out score", title=title)
    axes.legend(fontsize="small")
    delay = report.delay_entries()
    delay_axes.plot([e["delay_steps"] for e in delay], [math.nan if e["score"] is None else e["score"] for e in delay], marker="o")
    delay_axes.set(xlabel="control delay (steps)", title="delay")
    figure.savefig(paths[2], dpi=100)
    return paths
