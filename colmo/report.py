"""The report that compares search variants, read back from MLflow: the paper's Table I, its
Fig. 4 best-so-far curves, and the best policy of each variant.

    colmo-report experiment=pendulum [experiment=cheetah ...] [axis=samples|evaluations|seconds]
                 [out=DIR] [tracking_uri=URI]

`experiment` (repeatable, or comma-separated) names MLflow experiments (colmo names them after
the task); `tracking_uri` defaults to the tracker's `sqlite:///mlruns.db` in the working
directory. `out` is a new directory (default `reports/<experiments>_<date>_<time>`); one that
already holds a report is refused, so a report never overwrites another (or a tracked file).

Which runs count. Every FINISHED search run of the experiments is read (sweep parents and
`colmo-optimize` runs are not searches); runs that did not finish are counted and named, not
used. Runs are grouped by task and variant: the GFO method, its budget when tuning, and any
other setting that differs between the task's runs (`database.num_islands=5`); settings that
do not change results (tracker, executor, display) are ignored. A run repeated with the same
variant and seed is a repeat: the latest counts, and the report names the older ones.
Seeds are aggregated as mean ± sample std.

`out/` receives
- `report.md`: Table I (state and action dims, best training reward and held-out reward of the
  best program, without and with GFO, samples to reach the task's `task.target_score`), one
  line per run, the runs left out and why, and each variant's best policy;
- `best_so_far.png`: one panel per task, x = programs sampled, candidate evaluations or
  seconds of search (`axis`, so GFO and no GFO compare per sample or per unit of compute);
  solid: best over all islands, dashed: best per island; red without GFO, blue with it (other
  GFO variants in other colours); dotted: the target.
"""

from __future__ import annotations

import argparse
import datetime
import os
import re
import statistics
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional, Sequence

from matplotlib.figure import Figure
from mlflow import MlflowClient
from mlflow.entities import Run

from colmo.optimize.methods import METHODS
from colmo.store import BEST_POLICY_FILE
from colmo.track import SWEEP_TAG, connect, default_tracking_uri, draw_best_so_far, sqlite_path

REPORT_FILE = "report.md"
PLOT_FILE = "best_so_far.png"
NO_GFO = "no GFO"
_GFO_COLORS = ("tab:blue", "tab:green", "tab:purple", "tab:orange", "tab:brown", "tab:cyan")
# x axes: the metric logged at each step (samples is the step itself) and its label.
AXES = {
    "samples": (None, "programs sampled"),
    "evaluations": ("evaluations", "candidate evaluations (each over task.episodes episodes)"),
    "seconds": ("seconds", "seconds of search (wall clock)"),
}
# Settings that do not change what a search finds: not part of a variant.
_IGNORED = ("tracker.", "executor.", "search.progress", "search.queue_size", "evaluation.render", "resume", "spec.")
_VARIANT_BASE = ("task.name", "gfo.method", "gfo.budget", "seed")


@dataclass
class RunCurves:
    """One finished search as the report needs it: its best-so-far curve against `x`."""

    run: Run
    task: str
    method: str
    budget: int
    seed: int
    target: Optional[float]
    variant: str = ""
    steps: list[int] = field(default_factory=list)  # samples so far at each batch
    x: list[float] = field(default_factory=list)  # the chosen axis at each batch
    best: list[float] = field(default_factory=list)
    per_island: list[list[float]] = field(default_factory=list)

    @property
    def order(self) -> tuple:
        """No GFO first, then the GFO methods in config order, by budget; then seeds."""
        return (self.task, ("none", *METHODS).index(self.method), self.budget if self.method != "none" else 0, self.variant, self.seed)

    @property
    def final(self) -> float:
        return self.best[-1]

    @property
    def heldout(self) -> Optional[float]:
        return self.run.data.metrics.get("best_heldout_score")

    @property
    def samples_to_target(self) -> Optional[int]:
        """Programs sampled when the best score first reached the target (batch resolution)."""
        if self.target is None:
            return None
        return next((step for step, score in zip(self.steps, self.best) if score >= self.target), None)


@dataclass
class Variant:
    name: str
    runs: list[RunCurves] = field(default_factory=list)

    @property
    def gfo(self) -> bool:
        return self.runs[0].method != "none"


@dataclass
class Reading:
    """What was read from MLflow: the runs that count, and those left out with the reason."""

    curves: list[RunCurves]
    left_out: list[tuple[Run, str]]


# -- reading runs back ----------------------------------------------------------------------------


def _search_runs(client: MlflowClient, experiment_ids: list[str]) -> list[Run]:
    """Every search run (not sweep parents, not colmo-optimize runs), newest first."""
    runs, token = [], None
    while True:
        page = client.search_runs(experiment_ids, "", max_results=1000, order_by=["attributes.start_time DESC"], page_token=token)
        runs += [run for run in page if SWEEP_TAG not in run.data.tags and run.data.tags.get("colmo.command", "search") == "search"]
        token = page.token
        if not token:
            return runs


def _history(client: MlflowClient, run_id: str, key: str) -> dict[int, float]:
    """The metric's value at each step (the last one logged there)."""
    return {m.step: m.value for m in sorted(client.get_metric_history(run_id, key), key=lambda m: (m.step, m.timestamp))}


def _setting_key(params: dict[str, str]) -> dict[str, str]:
    return {key: value for key, value in params.items() if not key.startswith(_IGNORED)}


def read_runs(client: MlflowClient, experiments: Sequence[str], axis: str = "samples") -> Reading:
    """The finished search runs of `experiments` with their best-so-far histories against
    `axis`; the latest of each repeat (same settings and seed) counts, the others are left out
    with the reason, and so are runs that did not finish or have no curve."""
    ids = []
    for name in experiments:
        experiment = client.get_experiment_by_name(name)
        if experiment is None:
            raise ValueError(f"no MLflow experiment named {name!r} at {client.tracking_uri}")
        ids.append(experiment.experiment_id)
    metric, _ = AXES[axis]
    curves: list[RunCurves] = []
    left_out: list[tuple[Run, str]] = []
    counted: dict[tuple, str] = {}  # settings -> run name of the latest run with them
    for run in _search_runs(client, ids):
        params, run_id = run.data.params, run.info.run_id
        if run.info.status != "FINISHED":
            left_out.append((run, f"status {run.info.status}"))
            continue
        settings = tuple(sorted(_setting_key(params).items()))
        if settings in counted:
            left_out.append((run, f"repeat of `{counted[settings]}` (same settings and seed; the latest counts)"))
            continue
        best = _history(client, run_id, "best_score")
        if not best:
            left_out.append((run, "no batch finished: no curve"))
            continue
        xs = {step: float(step) for step in best} if metric is None else _history(client, run_id, metric)
        if not set(best) <= set(xs):
            left_out.append((run, f"no `{metric}` metric at every batch (logged by newer colmo): not on this axis"))
            continue
        counted[settings] = run.info.run_name
        target = params.get("task.target_score", "null")
        curve = RunCurves(
            run=run, task=params["task.name"], method=params["gfo.method"], budget=int(params["gfo.budget"]),
            seed=int(params["seed"]), target=None if target == "null" else float(target),
        )
        curve.steps = sorted(best)
        curve.x = [xs[step] for step in curve.steps]
        curve.best = [best[step] for step in curve.steps]
        islands = sorted((k for k in run.data.metrics if k.startswith("best_score_island_")), key=lambda k: int(k.rsplit("_", 1)[1]))
        for key in islands:
            history = _history(client, run_id, key)
            curve.per_island.append([history.get(step, float("nan")) for step in curve.steps])
        curves.append(curve)
    _name_variants(curves)
    return Reading(curves, left_out)


def _name_variants(curves: list[RunCurves]) -> None:
    """Each run's variant: the GFO method (and budget when tuning), and every other setting
    that differs between the runs of its task."""
    by_task: dict[str, list[RunCurves]] = {}
    for curve in curves:
        by_task.setdefault(curve.task, []).append(curve)
    for runs in by_task.values():
        settings = [_setting_key(curve.run.data.params) for curve in runs]
        # Keys only some runs have belong to one option's schema (gfo.sampler of gfo=bo): the
        # option itself (gfo.method, llm.name) already tells those runs apart.
        shared = set.intersection(*(set(s) for s in settings)) - set(_VARIANT_BASE)
        differing = sorted(key for key in shared if len({s[key] for s in settings}) > 1)
        for curve, setting in zip(runs, settings):
            base = NO_GFO if curve.method == "none" else f"{curve.method}, budget {curve.budget}"
            extra = [f"{key}={setting[key]}" for key in differing if not (curve.method == "none" and key.startswith("gfo."))]
            curve.variant = ", ".join([base, *extra])


def group(curves: list[RunCurves]) -> dict[str, list[Variant]]:
    """Runs by task, then by variant."""
    tasks: dict[str, dict[str, Variant]] = {}
    for curve in sorted(curves, key=lambda c: c.order):
        tasks.setdefault(curve.task, {}).setdefault(curve.variant, Variant(curve.variant)).runs.append(curve)
    return {task: list(variants.values()) for task, variants in tasks.items()}


# -- the table ------------------------------------------------------------------------------------


def mean_std(values: Sequence[float], digits: int = 1) -> str:
    """`mean ± sample std`; the mean alone for one value."""
    if len(values) == 1:
        return f"{values[0]:.{digits}f}"
    return f"{statistics.mean(values):.{digits}f} ± {statistics.stdev(values):.{digits}f}"


def reward_cell(variant: Optional[Variant]) -> str:
    return mean_std([run.final for run in variant.runs]) if variant else "—"


def heldout_cell(variant: Optional[Variant]) -> str:
    """Mean ± std of the best programs' held-out scores, over the seeds that have one."""
    if variant is None:
        return "—"
    scores = [run.heldout for run in variant.runs if run.heldout is not None]
    if not scores:
        return "—"
    return mean_std(scores) + ("" if len(scores) == len(variant.runs) else f" ({len(scores)}/{len(variant.runs)} seeds)")


def target_cell(variant: Optional[Variant]) -> str:
    """Mean ± std over the seeds that reached the target, and how many did."""
    if variant is None or variant.runs[0].target is None:
        return "—"
    reached = [run.samples_to_target for run in variant.runs if run.samples_to_target is not None]
    count = f"({len(reached)}/{len(variant.runs)} seeds)"
    return f"{mean_std(reached, 0)} {count}" if reached else f"not reached {count}"


def _bold_better(cells: list[str], variants: Sequence[Optional[Variant]], value) -> list[str]:
    """Bold the better mean of the two, as the paper does."""
    values = ([value(run) for run in variant.runs if value(run) is not None] if variant else [] for variant in variants)
    means = [statistics.mean(v) if v else None for v in values]
    if None in means:
        return cells
    better = means.index(max(means))
    return [f"**{cell}**" if index == better else cell for index, cell in enumerate(cells)]


def _dims(variants: list[Variant]) -> tuple[str, str]:
    params = next((run.run.data.params for v in variants for run in v.runs if "spec.observation_size" in run.run.data.params), {})
    return params.get("spec.observation_size", "—"), params.get("spec.action_size", "—")


def table_one(tasks: dict[str, list[Variant]]) -> list[str]:
    """Table I: one row per task and GFO variant, against the task's no-GFO runs (the first
    no-GFO variant, when settings other than GFO differ too)."""
    lines = [
        "| Task | State dim | Action dim | GFO | Reward, no GFO | Reward, GFO | Held-out, no GFO | Held-out, GFO "
        "| Target | Samples to target, no GFO | Samples to target, GFO |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for task, variants in tasks.items():
        baseline = next((v for v in variants if not v.gfo), None)
        tuned = [v for v in variants if v.gfo] or [None]
        observation_size, action_size = _dims(variants)
        target = variants[0].runs[0].target
        for variant in tuned:
            pair = (baseline, variant)
            rewards = _bold_better([reward_cell(v) for v in pair], pair, lambda run: run.final)
            heldouts = _bold_better([heldout_cell(v) for v in pair], pair, lambda run: run.heldout)
            lines.append(
                f"| {task} | {observation_size} | {action_size} | {variant.name if variant else '—'} | "
                f"{' | '.join(rewards)} | {' | '.join(heldouts)} | "
                f"{'—' if target is None else f'{target:g}'} | {target_cell(baseline)} | {target_cell(variant)} |"
            )
    return lines


def runs_table(tasks: dict[str, list[Variant]]) -> list[str]:
    lines = [
        "| Run | Variant | Seed | Best score | Held-out | Samples | Evaluations | Samples to target | Seconds | Overrides |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for variants in tasks.values():
        for variant in variants:
            for run in variant.runs:
                info, metrics = run.run.info, run.run.data.metrics
                reached = run.samples_to_target
                evaluations = metrics.get("evaluations")
                seconds = metrics.get("seconds", (info.end_time - info.start_time) / 1000)
                lines.append(
                    f"| {info.run_name} | {variant.name} | {run.seed} | {run.final:.1f} | "
                    f"{'—' if run.heldout is None else f'{run.heldout:.1f}'} | {run.steps[-1]} | "
                    f"{'—' if evaluations is None else f'{evaluations:.0f}'} | {'—' if reached is None else reached} | "
                    f"{seconds:.0f} | `{run.run.data.tags.get('overrides', '')}` |"
                )
    return lines


def left_out_lines(left_out: list[tuple[Run, str]]) -> list[str]:
    if not left_out:
        return ["None: every search run of the experiment(s) counts."]
    return [f"- `{run.info.run_name}` ({run.info.run_id[:8]}): {reason}" for run, reason in left_out]


def best_policies(client: MlflowClient, tasks: dict[str, list[Variant]]) -> list[str]:
    """Each variant's best run's `best_policy.py` artifact, as a code block."""
    lines = []
    with tempfile.TemporaryDirectory() as scratch:
        for task, variants in tasks.items():
            for variant in variants:
                best = max(variant.runs, key=lambda run: run.final)
                path = client.download_artifacts(best.run.info.run_id, BEST_POLICY_FILE, scratch)
                code = Path(path).read_text().rstrip()
                lines += [
                    f"### {task}, {variant.name}",
                    "",
                    f"Best of {len(variant.runs)} seed(s): run `{best.run.info.run_name}`, score {best.final:.1f}.",
                    "",
                    "```python",
                    code,
                    "```",
                    "",
                ]
    return lines


# -- the figure ----------------------------------------------------------------------------------


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
        observation_size, action_size = _dims(variants)
        ax.set_title(f"{task} (state {observation_size}, action {action_size})")
        ax.set_xlabel(AXES[axis][1])
        ax.set_ylabel("best score so far (dashed: per island)")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncols=3, frameon=False)  # below: never over the curves
    return fig


# -- the command ----------------------------------------------------------------------------------


def default_out(experiments: Sequence[str], now: Optional[datetime.datetime] = None) -> Path:
    stamp = (now or datetime.datetime.now()).strftime("%Y-%m-%d_%H-%M-%S")
    name = re.sub(r"[^\w.+-]+", "_", "+".join(experiments))
    return Path("reports") / f"{name}_{stamp}"


def write_report(client: MlflowClient, experiments: Sequence[str], out: Path, axis: str = "samples", command: str = "") -> Path:
    """Write `report.md` and `best_so_far.png` into the new directory `out`; return the
    Markdown file. `ValueError` if `out` already holds a report or no run can be used."""
    if (out / REPORT_FILE).exists():
        raise ValueError(f"{out} already holds a report: choose another out= (a report never overwrites one)")
    reading = read_runs(client, experiments, axis)
    tasks = group(reading.curves)
    if not tasks:
        raise ValueError(f"no finished runs with metrics in experiment(s) {', '.join(experiments)}")
    out.mkdir(parents=True, exist_ok=True)
    figure(tasks, axis).savefig(out / PLOT_FILE, dpi=130)
    count = len(reading.curves)
    lines = [
        f"# colmo report: {', '.join(experiments)}",
        "",
        f"{count + len(reading.left_out)} search runs read from MLflow on {datetime.date.today().isoformat()} "
        f"with `{command or 'colmo-report'}`; {count} count, {len(reading.left_out)} left out (listed below: "
        "runs that did not finish, and repeats: of runs with the same settings and seed, the latest counts).",
        "Rewards are each run's best search score (the mean return over `task.episodes` training episodes);",
        "held-out: that best program's mean return over `evaluation.episodes` fresh episodes. Both are",
        "mean ± sample std over seeds. Samples to target: programs sampled when the best score first",
        "reached `task.target_score`, over the seeds that reached it, at batch resolution.",
        "",
        "## Table I",
        "",
        *table_one(tasks),
        "",
        "## Best so far",
        "",
        f"![best-so-far curves]({PLOT_FILE})",
        "",
        f"x: {AXES[axis][1]}. Solid: best over all islands; dashed: best within each island. Red: no GFO; blue: GFO.",
        "",
        "## Runs",
        "",
        *runs_table(tasks),
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


_KEYS = ("experiment", "axis", "out", "tracking_uri")


def _setting(text: str) -> tuple[str, str]:
    key, sep, value = text.partition("=")
    if not sep or key not in _KEYS or not value:
        raise argparse.ArgumentTypeError(f"expected one of {', '.join(k + '=...' for k in _KEYS)}, got {text!r}")
    return key, value


def main(argv: Optional[Sequence[str]] = None) -> None:
    invoked = Path(sys.argv[0]).name
    prog = invoked if invoked == "colmo-report" else "python -m colmo.report"
    parser = argparse.ArgumentParser(
        prog=prog, description=__doc__.split("\n\n")[0],
        epilog=f"example: {prog} experiment=pendulum axis=seconds",
    )
    parser.add_argument(
        "settings", nargs="+", type=_setting, metavar="key=value",
        help="experiment=NAME[,NAME] (required, repeatable); axis=samples|evaluations|seconds (x of the figure, "
        "default samples); out=DIR (a new directory; default reports/<experiments>_<date>_<time>); "
        "tracking_uri=URI (default sqlite:///mlruns.db in the working directory)",
    )
    args = list(sys.argv[1:] if argv is None else argv)
    settings = parser.parse_args(args).settings
    experiments = [name for key, value in settings if key == "experiment" for name in value.split(",") if name]
    if not experiments:
        parser.error("experiment=NAME is required")
    options = dict(settings)
    axis = options.get("axis", "samples")
    if axis not in AXES:
        parser.error(f"axis must be one of {', '.join(AXES)}, got {axis!r}")
    os.environ.setdefault("MLFLOW_ENABLE_ARTIFACTS_PROGRESS_BAR", "false")  # one bar per policy file is noise
    uri = options.get("tracking_uri") or default_tracking_uri(Path.cwd())
    database = sqlite_path(uri)
    if database is not None and not database.is_file():
        parser.error(f"no tracking database at {database}: run a search first, or pass tracking_uri=")
    out = Path(options["out"]) if "out" in options else default_out(experiments)
    try:
        path = write_report(connect(uri), experiments, out, axis, f"{prog} {' '.join(args)}")
    except ValueError as error:
        print(f"{prog}: error: {error}", file=sys.stderr)
        sys.exit(2)
    print(path)


if __name__ == "__main__":
    main()
