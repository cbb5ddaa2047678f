"""Robustness report: a policy's score over a grid of model-mismatch magnitudes.

Each relative factor of `colmo.config.PerturbConfig` (mass and inertia, damping, dry friction,
geom friction, actuator gain, observation and action noise) is raised alone to each magnitude,
then all of them together; the control delay, counted in steps rather than as a fraction, has
its own short grid. Every point is scored by the caller's `score` (the referee on held-out
episodes, in `colmo-evaluate robustness=true`) on the same episode seeds, whose perturbation
draws differ only in scale from one magnitude to the next, so the curves are paired and the
report is a deterministic function of the policy and the seeds. Each point carries the 95%
confidence interval of its mean over the episodes (Student's t), so that a reader can tell a
fragile policy from an unlucky draw. This module knows no front end.
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable, Optional, Sequence

from colmo.comparison import CONFIDENCE, half_width
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

    @property
    def interval(self) -> Optional[float]:
        """Half the interval of the score over the point's episodes."""
        return None if self.evaluation.failure else half_width(self.evaluation.returns)

    def differences(self, nominal: Evaluation) -> Optional[list[float]]:
        """Per episode, this point's return less the nominal model's on the same episode."""
        if self.evaluation.failure or nominal.failure or len(self.evaluation.returns) != len(nominal.returns):
            return None
        return [a - b for a, b in zip(self.evaluation.returns, nominal.returns)]


@dataclass(frozen=True)
class RobustnessReport:
    nominal: Evaluation
    magnitudes: tuple[float, ...]  # the nonzero relative magnitudes
    points: tuple[Point, ...]  # every factor at every magnitude, then `all`, then the delays
    delays: tuple[int, ...]

    @property
    def nominal_score(self) -> Optional[float]:
        return self.point(ALL, 0.0).score

    def point(self, factor: str, magnitude: float) -> Point:
        if magnitude == 0:
            return Point("nominal", 0.0, self.nominal)
        return next(p for p in self.points if p.factor == factor and p.magnitude == magnitude)

    def score(self, factor: str, magnitude: float) -> Optional[float]:
        return self.point(factor, magnitude).score

    def entries(self, value: Callable[[Point], Optional[float]] = lambda point: point.score) -> list[dict]:
        """One entry per magnitude, nominal (0) first: the score of each factor and of all
        together (or `value` of each point, e.g. its interval)."""
        return [{"magnitude": m, **{name: value(self.point(name, m)) for name in (*FACTORS, ALL)}} for m in (0.0, *self.magnitudes)]

    def delay_entries(self, value: Callable[[Point], Optional[float]] = lambda point: point.score) -> list[dict]:
        """One entry per control delay (`delay_steps`), none first."""
        return [{"delay_steps": k, "score": value(self.point("delay", k))} for k in (0, *self.delays)]

    def change(self, point: Point) -> Optional[float]:
        """The point's score less the nominal one (the mean of the paired differences)."""
        differences = point.differences(self.nominal)
        return None if differences is None else float(sum(differences) / len(differences))

    def change_interval(self, point: Point) -> Optional[float]:
        """Half the interval of `change`, from the paired differences: every point plays the
        nominal model's episodes, so this is far narrower than the score's own interval."""
        differences = point.differences(self.nominal)
        return None if differences is None else half_width(differences)

    def as_json(self) -> dict:
        """The report as `robustness.json` holds it: the scores; beside them, in the same layout,
        the half-widths of their `CONFIDENCE` intervals, each point's change from the nominal
        score and the half-width of that change's paired interval."""
        return {
            "robustness": self.entries(), "delay": self.delay_entries(), "confidence": CONFIDENCE, "episodes": len(self.nominal.returns),
            "robustness_interval": self.entries(lambda p: p.interval), "delay_interval": self.delay_entries(lambda p: p.interval),
            "robustness_change": self.entries(self.change), "delay_change": self.delay_entries(self.change),
            "robustness_change_interval": self.entries(self.change_interval), "delay_change_interval": self.delay_entries(self.change_interval),
        }

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


def precise(report: RobustnessReport, precision: float) -> bool:
    """Whether every scored point's interval, the nominal one's included, is within `precision`
    times the nominal score's magnitude (points that failed have none and never will)."""
    nominal = report.nominal_score
    if nominal is None:
        return True
    intervals = [Point(ALL, 0.0, report.nominal).interval, *(point.interval for point in report.points)]
    return all(interval is None or interval <= precision * abs(nominal) for interval in intervals)


def adaptive_report(
    score: Callable[[PerturbConfig, int, int], Evaluation], magnitudes: Sequence[float], delays: Sequence[int], episodes: int,
    precision: Optional[float] = None, max_episodes: Optional[int] = None, may_add: Callable[[int, int], bool] = lambda scored, added: True,
) -> RobustnessReport:
    """`robustness_report` on the first `episodes` episodes (`score(perturb, start, stop)`: a
    point's evaluation on episodes start..stop-1). With `precision`, more episodes for every
    point, doubling, until the report is `precise`, `max_episodes` are scored or `may_add(scored,
    added)` (episodes per point so far, and to add) says no (a time limit): every point gets
    the same episodes, so that the points stay paired; a point that failed is not run again."""
    scored: dict[str, Evaluation] = {}
    span = (0, episodes)

    def score_so_far(perturb: PerturbConfig) -> Evaluation:
        earlier = scored.get(repr(perturb))
        if earlier is not None and earlier.failure:
            return earlier
        part = score(perturb, *span)
        scored[repr(perturb)] = part if earlier is None else Evaluation.joined([earlier, part])
        return scored[repr(perturb)]

    report = robustness_report(score_so_far, magnitudes, delays)
    most = max(episodes, max_episodes or episodes)
    while precision is not None and span[1] < most and not precise(report, precision):
        span = (span[1], min(2 * span[1], most))
        if not may_add(span[0], span[1] - span[0]):
            break
        report = robustness_report(score_so_far, magnitudes, delays)
    return report


def _cell(value: Optional[float], interval: Optional[float], sign: str = "") -> str:
    if value is None or not math.isfinite(value):
        return "failed"
    return f"{value:{sign}.1f}" if interval is None else f"{value:{sign}.1f}±{interval:.1f}"


def table(report: RobustnessReport) -> str:
    """The scores as a plain-text table: one row per magnitude, one column per factor, each
    score with the half-width of its interval."""
    names, episodes = (*FACTORS, ALL), len(report.nominal.returns)
    header = "magnitude " + " ".join(f"{name:>14}" for name in names)
    lines = [f"held-out score ± {CONFIDENCE:.0%} interval, {episodes} episodes per point", header]
    for magnitude in (0.0, *report.magnitudes):
        lines.append(f"{magnitude:>9.0%} " + " ".join(f"{_cell(p.score, p.interval):>14}" for p in (report.point(n, magnitude) for n in names)))
    lines += ["", f"change from nominal, paired over the same {episodes} episodes, ± {CONFIDENCE:.0%} interval", header]
    for magnitude in report.magnitudes:
        points = (report.point(n, magnitude) for n in names)
        lines.append(f"{magnitude:>9.0%} " + " ".join(f"{_cell(report.change(p), report.change_interval(p), '+'):>14}" for p in points))
    if report.delays:
        lines.append("")
        lines.append("delay (steps) " + " ".join(f"{k:>3}: {_cell(p.score, p.interval)}" for k in (0, *report.delays) for p in [report.point("delay", k)]))
    return "\n".join(lines)


def save(report: RobustnessReport, directory: Path, title: str) -> list[Path]:
    """Write `robustness.json`, `robustness.csv` and `robustness.png` (score against magnitude,
    one line per factor; the delay grid in a second panel) into `directory`."""
    from matplotlib.figure import Figure

    directory.mkdir(parents=True, exist_ok=True)
    paths = [directory / name for name in FILES]
    paths[0].write_text(json.dumps(report.as_json(), indent=1) + "\n")
    with paths[1].open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(["factor", "magnitude", "score", "interval", "change", "change_interval"])
        rows = [(name, magnitude) for magnitude in (0.0, *report.magnitudes) for name in (*FACTORS, ALL)]
        rows += [("delay", k) for k in report.delays]
        for name, magnitude in rows:
            p = report.point(name, magnitude)
            writer.writerow([name if name != "delay" else "delay_steps", magnitude, p.score, p.interval, report.change(p), report.change_interval(p)])
    figure = Figure(figsize=(10, 4), layout="constrained")
    axes, delay_axes = figure.subplots(1, 2, width_ratios=(3, 1))
    magnitudes = (0.0, *report.magnitudes)
    for name in (*FACTORS, ALL):
        line = _band(axes, [100 * m for m in magnitudes], [report.point(name, m) for m in magnitudes], name)
        if name == ALL:
            line.set(linewidth=2.5, color="black")
    axes.set(xlabel="perturbation magnitude (%)", ylabel=f"held-out score ({CONFIDENCE:.0%} interval shaded)", title=title)
    axes.legend(fontsize="small")
    delays = (0, *report.delays)
    _band(delay_axes, delays, [report.point("delay", k) for k in delays], "delay")
    delay_axes.set(xlabel="control delay (steps)", title="delay")
    figure.savefig(paths[2], dpi=100)
    return paths


def _band(axes, x: Sequence[float], points: Sequence[Point], label: str):
    """One curve of scores with its intervals as a shaded band; the line drawn."""
    y = [math.nan if p.score is None else p.score for p in points]
    width = [math.nan if p.interval is None else p.interval for p in points]
    (line,) = axes.plot(x, y, marker="o", label=label, linewidth=1.2)
    axes.fill_between(x, [a - w for a, w in zip(y, width)], [a + w for a, w in zip(y, width)], color=line.get_color(), alpha=0.15, linewidth=0)
    return line
