"""The report that compares search variants, read back from MLflow: the paper's Table I, its
Fig. 4 best-so-far curves, and the best policy of each variant.

    colmo-report experiment=pendulum [experiment=cheetah ...] [sweep=latest|all|NAME]
                 [axis=samples,seconds] [out=DIR] [tracking_uri=URI]

`experiment` (repeatable, or comma-separated) names MLflow experiments (colmo names them after
the task); `tracking_uri` defaults to the tracker's `sqlite:///mlruns.db` in the working
directory. `out` is a new directory (default `reports/<experiments>_<date>_<time>`); one that
already holds a report is refused, so a report never overwrites another (or a tracked file).

Which runs count. One sweep is compared: `sweep=latest` (default) the latest `-m` sweep (its
parent run, and one per experiment when it spans tasks), `sweep=NAME` the sweep whose parent
run is named NAME (`pendulum-sweep-121503`), `sweep=all` every run of the experiments (also
the default when they hold no sweep). Its FINISHED search runs are read (sweep parents and
`colmo-optimize` runs are not searches); runs that did not finish are counted and named, not
used. Runs are grouped by task and variant: the GFO method, its budget when tuning, and any
other setting that differs between the task's runs (`database.num_islands=5`); settings that
do not change results (tracker, executor, display) are ignored. A run repeated with the same
variant and seed is a repeat: the latest counts, and the report names the older ones.
Seeds are aggregated as mean ± sample std.

`out/` receives
- `report.md`: Table I (state and action dims, best training reward and held-out reward of the
  best program, without and with GFO, samples to reach the task's `task.target_score`; bold
  only where the difference is significant), each variant against the baseline (the difference
  of means with its bootstrap interval, "no significant difference" when it holds 0; the cost:
  wall and worker seconds, model calls, evaluations: `colmo.comparison`), one line per
  run, where each run's samples and time went (valid programs, duplicates, tokens/s,
  generator and evaluator busy), each run's best policy's readability (`colmo.readability`), the
  runs left out and why, and each variant's best policy;
- `best_so_far.png`: one panel per task, x = model calls (programs sampled), candidate
  evaluations or seconds of search (the first of `axis`, a comma-separated list of
  samples, evaluations, seconds; default `samples,seconds`); one colour per variant, named in
  the legend: each seed thin, and where every seed has data its mean over seeds (thick) and
  the band from its lowest to its highest seed; a curve of one point is a marker; dotted: the
  target; the caption says whether the runs' budgets were equal on the axis;
- `best_so_far_<axis>.png`: the same against each further axis, so GFO and no GFO compare
  per model call and per second (what GFO spends to make each sample count).
"""

from __future__ import annotations

import datetime
import re
from pathlib import Path
from typing import Optional, Sequence

from mlflow import MlflowClient

from colmo.comparison import CONFIDENCE
from colmo.report.figure import budget_note, figure
from colmo.report.selection import AXES, LATEST, group, read_runs
from colmo.report.tables import (
    best_policies,
    comparison_table,
    generation_table,
    left_out_lines,
    mean_std,
    readability_table,
    runs_table,
    table_one,
    yield_table,
)
from colmo.store import BEST_SO_FAR_PLOT

__all__ = ["AXES", "default_out", "mean_std", "read_runs", "write_report"]

REPORT_FILE = "report.md"
DEFAULT_AXES = ("samples", "seconds")


def plot_file(axis: str, first: bool) -> str:
    return BEST_SO_FAR_PLOT if first else f"best_so_far_{axis}.png"


def default_out(experiments: Sequence[str], now: Optional[datetime.datetime] = None) -> Path:
    stamp = (now or datetime.datetime.now()).strftime("%Y-%m-%d_%H-%M-%S")
    name = re.sub(r"[^\w.+-]+", "_", "+".join(experiments))
    return Path("reports") / f"{name}_{stamp}"


def write_report(
    client: MlflowClient, experiments: Sequence[str], out: Path, axes: Sequence[str] = DEFAULT_AXES, command: str = "",
    sweep: str = LATEST,
) -> Path:
    """Write `report.md` and a best-so-far figure per axis of `axes` (the tables read the runs
    as the first axis does) of one sweep (`sweep`: latest, all or a parent run's name) into the
    new directory `out`; return the Markdown file. `ValueError` if `out` already holds a
    report, the sweep does not exist or no run can be used."""
    if (out / REPORT_FILE).exists():
        raise ValueError(f"{out} already holds a report: choose another out= (a report never overwrites one)")
    axis, *further = axes
    reading = read_runs(client, experiments, axis, sweep)
    tasks = group(reading.curves)
    if not tasks:
        raise ValueError(f"no finished runs with metrics in experiment(s) {', '.join(experiments)}")
    out.mkdir(parents=True, exist_ok=True)
    figure(tasks, axis).savefig(out / BEST_SO_FAR_PLOT, dpi=130)
    plots = [f"![best so far against {AXES[axis][1]}]({BEST_SO_FAR_PLOT})", "", f"x: {AXES[axis][1]}. {budget_note(tasks, axis)}"]
    for other in further:
        other_tasks = group(read_runs(client, experiments, other, sweep).curves)
        if other_tasks:  # runs logged before colmo logged the axis's metric have no curve on it
            figure(other_tasks, other).savefig(out / plot_file(other, first=False), dpi=130)
            plots += [
                "", f"![best so far against {AXES[other][1]}]({plot_file(other, first=False)})", "",
                f"x: {AXES[other][1]}. {budget_note(other_tasks, other)}",
            ]
    count = len(reading.curves)
    lines = [
        f"# colmo report: {', '.join(experiments)}",
        "",
        f"Compared: {reading.sweep}.",
        "",
        f"{count + len(reading.left_out)} search runs read from MLflow on {datetime.date.today().isoformat()} "
        f"with `{command or 'colmo-report'}`; {count} count, {len(reading.left_out)} left out (listed below: "
        "runs that did not finish, and repeats: of runs with the same settings and seed, the latest counts).",
        "Rewards are each run's best search score (the mean return over `task.episodes` training episodes);",
        "held-out: that best program's mean return over `heldout.episodes` fresh episodes. Both are",
        "mean ± sample std over seeds. Samples to target: programs sampled when the best score first",
        "reached `task.target_score`, over the seeds that reached it, at batch resolution.",
        "",
        "## Table I",
        "",
        *table_one(tasks),
        "",
        "A score is bold only where the difference of the two means is significant: its "
        f"{CONFIDENCE:.0%} bootstrap interval (seeds resampled per variant) leaves out 0.",
        "",
        "## Variants compared",
        "",
        "Each variant against its task's baseline (its first variant without GFO): the difference of the mean "
        "best score and of the mean held-out score, with its bootstrap interval, and what the variant cost, "
        "mean ± std over its seeds: wall seconds, the evaluation workers' busy seconds, model calls, candidate evaluations.",
        "",
        *comparison_table(tasks),
        "",
        "## Best so far",
        "",
        *plots,
        "",
        "One colour per variant (legend): thin, each seed on its own clock; thick, the mean over seeds and band, "
        "lowest to highest seed, where every seed has data; a marker, a run of one batch.",
        "",
        "## Runs",
        "",
        *runs_table(tasks),
        "",
        "## Model calls that yield a program",
        "",
        "Of each run's model calls (duplicates generated again included), how many gave a program that was evaluated.",
        "",
        *yield_table(tasks),
        "",
        "## Generation and evaluation",
        "",
        *generation_table(tasks),
        "",
        "## Readability of each run's best policy",
        "",
        "Lines and parameters as the search found it and as the simplifier left it; its branches decided the same way at every "
        "test over the training and held-out episodes (one side never taken); clips that returned a limit for every value; "
        "divisions by zero; variables whose names contradict the task's; comparisons the code decides, read from the code "
        "(`colmo.readability`).",
        "",
        *readability_table(tasks),
        "",
        "## Runs left out",
        "",
        *left_out_lines(reading.left_out),
        "",
        "## Best policy per variant",
        "",
        *best_policies(client, tasks),
    ]
    path = out / REPORT_FILE
    path.write_text("\n".join(lines).rstrip() + "\n")
    return path
