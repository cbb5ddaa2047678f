"""The report that compares search variants, read back from MLflow: the paper's Table I, its
Fig. 4 best-so-far curves, and the best policy of each variant.

    python -m colmo.report experiment=pendulum [experiment=cheetah ...] [out=docs/report] [tracking_uri=URI]

`experiment` (repeatable, or comma-separated) names MLflow experiments (colmo names them after
the task); `tracking_uri` defaults to the tracker's `sqlite:///mlruns.db` in the working
directory. The FINISHED runs are grouped by task and GFO variant (`gfo.method`, and
`gfo.budget` when tuning), seeds are aggregated as mean ± sample std, and `out/` receives
- `report.md`: Table I (state and action dims, best reward without and with GFO, samples to
  reach the task's `task.target_score`), one line per run, and each variant's best policy;
- `best_so_far.png`: one panel per task; solid: best over all islands, dashed: best per island;
  red without GFO, blue with it (other GFO variants in other colours); dotted: the target.
"""

from __future__ import annotations

import argparse
import datetime
import os
import statistics
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional, Sequence

from matplotlib.figure import Figure
from mlflow import MlflowClient
from mlflow.entities import Run

from colmo.config import GFO_METHODS
from colmo.search import BEST_POLICY_FILE
from colmo.track import connect, default_tracking_uri, draw_best_so_far, sqlite_path

REPORT_FILE = "report.md"
PLOT_FILE = "best_so_far.png"
NO_GFO = "no GFO"
_GFO_COLORS = ("tab:blue", "tab:green", "tab:purple", "tab:orange", "tab:brown", "tab:cyan")


@dataclass
class RunCurves:
    """One finished search as the report needs it."""

    run: Run
    task: str
    method: str
    budget: int
    seed: int
    target: Optional[float]
    steps: list[int] = field(default_factory=list)
    best: list[float] = field(default_factory=list)
    per_island: list[list[float]] = field(default_factory=list)

    @property
    def variant(self) -> str:
        return NO_GFO if self.method == "none" else f"{self.method}, budget {self.budget}"

    @property
    def order(self) -> tuple[str, int, int, int]:
        """No GFO first, then the GFO methods in config order, by budget; then seeds."""
        return (self.task, GFO_METHODS.index(self.method), self.budget if self.method != "none" else 0, self.seed)

    @property
    def final(self) -> float:
        return self.best[-1]

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


# -- reading runs back ----------------------------------------------------------------------------


def _finished_runs(client: MlflowClient, experiment_ids: list[str]) -> list[Run]:
    """Newest first."""
    runs, token = [], None
    while True:
        page = client.search_runs(
            experiment_ids, "attributes.status = 'FINISHED'", max_results=1000, order_by=["attributes.start_time DESC"], page_token=token
        )
        runs += page
        token = page.token
        if not token:
            return runs


def _history(client: MlflowClient, run_id: str, key: str) -> list[tuple[int, float]]:
    return sorted((m.step, m.value) for m in client.get_metric_history(run_id, key))


def read_runs(client: MlflowClient, experiments: Sequence[str]) -> list[RunCurves]:
    """The finished runs of `experiments` with their best-so-far histories; of a job run more
    than once (same run name and variant), the latest."""
    ids = []
    for name in experiments:
        experiment = client.get_experiment_by_name(name)
        if experiment is None:
            raise ValueError(f"no MLflow experiment named {name!r} at {client.tracking_uri}")
        ids.append(experiment.experiment_id)
    curves, seen = [], set()
    for run in _finished_runs(client, ids):
        params, run_id = run.data.params, run.info.run_id
        target = params["task.target_score"]
        curve = RunCurves(
            run=run, task=params["task.name"], method=params["gfo.method"], budget=int(params["gfo.budget"]),
            seed=int(params["seed"]), target=None if target == "null" else float(target),
        )
        if (run.info.run_name, curve.variant) in seen:
            continue
        seen.add((run.info.run_name, curve.variant))
        history = _history(client, run_id, "best_score")
        if not history:
            continue  # stopped before its first batch: nothing to compare
        curve.steps, curve.best = [step for step, _ in history], [score for _, score in history]
        islands = sorted((k for k in run.data.metrics if k.startswith("best_score_island_")), key=lambda k: int(k.rsplit("_", 1)[1]))
        curve.per_island = [[score for _, score in _history(client, run_id, key)] for key in islands]
        curves.append(curve)
    return curves


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


def target_cell(variant: Optional[Variant]) -> str:
    """Mean ± std over the seeds that reached the target, and how many did."""
    if variant is None or variant.runs[0].target is None:
        return "—"
    reached = [run.samples_to_target for run in variant.runs if run.samples_to_target is not None]
    count = f"({len(reached)}/{len(variant.runs)} seeds)"
    return f"{mean_std(reached, 0)} {count}" if reached else f"not reached {count}"


def table_one(tasks: dict[str, list[Variant]]) -> list[str]:
    """Table I: one row per task and GFO variant, against the task's no-GFO runs."""
    lines = [
        "| Task | State dim | Action dim | GFO | Reward, no GFO | Reward, GFO | Target | Samples to target, no GFO | Samples to target, GFO |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for task, variants in tasks.items():
        baseline = next((v for v in variants if v.name == NO_GFO), None)
        tuned = [v for v in variants if v.name != NO_GFO] or [None]
        params = variants[0].runs[0].run.data.params
        target = variants[0].runs[0].target
        for variant in tuned:
            rewards = [reward_cell(baseline), reward_cell(variant)]
            if baseline and variant:  # bold the better mean, as the paper does
                means = [statistics.mean(run.final for run in v.runs) for v in (baseline, variant)]
                better = means.index(max(means))
                rewards[better] = f"**{rewards[better]}**"
            lines.append(
                f"| {task} | {params['spec.observation_size']} | {params['spec.action_size']} | "
                f"{variant.name if variant else '—'} | {rewards[0]} | {rewards[1]} | "
                f"{'—' if target is None else f'{target:g}'} | {target_cell(baseline)} | {target_cell(variant)} |"
            )
    return lines


def runs_table(tasks: dict[str, list[Variant]]) -> list[str]:
    lines = ["| Run | Variant | Seed | Best score | Samples | Samples to target | Wall time (s) | Overrides |", "|---|---|---|---|---|---|---|---|"]
    for variants in tasks.values():
        for variant in variants:
            for run in variant.runs:
                info = run.run.info
                reached = run.samples_to_target
                lines.append(
                    f"| {info.run_name} | {variant.name} | {run.seed} | {run.final:.1f} | {run.steps[-1]} | "
                    f"{'—' if reached is None else reached} | {(info.end_time - info.start_time) / 1000:.0f} | "
                    f"`{run.run.data.tags.get('overrides', '')}` |"
                )
    return lines


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


def figure(tasks: dict[str, list[Variant]]) -> Figure:
    """Fig. 4: one panel per task, every run of every variant."""
    fig = Figure(figsize=(6.5 * len(tasks), 4.8), layout="constrained")
    axes = fig.subplots(1, len(tasks), squeeze=False)[0]
    for ax, (task, variants) in zip(axes, tasks.items()):
        tuned = iter(_GFO_COLORS)
        for variant in variants:
            color = "tab:red" if variant.name == NO_GFO else next(tuned)
            for index, run in enumerate(variant.runs):
                label = f"{variant.name} ({len(variant.runs)} seeds)" if index == 0 else None
                draw_best_so_far(ax, run.steps, run.best, run.per_island, color, label)
        first = variants[0].runs[0]
        if first.target is not None:
            ax.axhline(first.target, color="0.4", linestyle=":", linewidth=1.2, label=f"target {first.target:g}")
        params = first.run.data.params
        ax.set_title(f"{task} (state {params['spec.observation_size']}, action {params['spec.action_size']})")
        ax.set_xlabel("programs sampled")
        ax.set_ylabel("best score so far (dashed: per island)")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncols=3, frameon=False)  # below: never over the curves
    return fig


# -- the command ----------------------------------------------------------------------------------


def write_report(client: MlflowClient, experiments: Sequence[str], out: Path) -> Path:
    """Write `report.md` and `best_so_far.png` into `out`; return the Markdown file."""
    tasks = group(read_runs(client, experiments))
    if not tasks:
        raise ValueError(f"no finished runs with metrics in experiment(s) {', '.join(experiments)}")
    out.mkdir(parents=True, exist_ok=True)
    figure(tasks).savefig(out / PLOT_FILE, dpi=130)
    count = sum(len(v.runs) for variants in tasks.values() for v in variants)
    lines = [
        f"# colmo report: {', '.join(experiments)}",
        "",
        f"{count} finished runs, read from MLflow on {datetime.date.today().isoformat()} with "
        f"`python -m colmo.report {' '.join(f'experiment={e}' for e in experiments)}`.",
        "Of a job run more than once (same run name and variant), the latest run counts.",
        "Rewards are each run's best search score (the mean return over `task.episodes` episodes),",
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
        "Solid: best over all islands; dashed: best within each island. Red: no GFO; blue: GFO.",
        "",
        "## Runs",
        "",
        *runs_table(tasks),
        "",
        "## Best policy per variant",
        "",
        *best_policies(client, tasks),
    ]
    path = out / REPORT_FILE
    path.write_text("\n".join(lines).rstrip() + "\n")
    return path


_KEYS = ("experiment", "out", "tracking_uri")


def _setting(text: str) -> tuple[str, str]:
    key, sep, value = text.partition("=")
    if not sep or key not in _KEYS or not value:
        raise argparse.ArgumentTypeError(f"expected one of {', '.join(k + '=...' for k in _KEYS)}, got {text!r}")
    return key, value


def main(argv: Optional[Sequence[str]] = None) -> None:
    parser = argparse.ArgumentParser(
        prog="python -m colmo.report", description=__doc__.split("\n\n")[0],
        epilog="example: python -m colmo.report experiment=pendulum out=docs/report",
    )
    parser.add_argument(
        "settings", nargs="+", type=_setting, metavar="key=value",
        help="experiment=NAME[,NAME] (required, repeatable); out=DIR (default docs/report); "
        "tracking_uri=URI (default sqlite:///mlruns.db in the working directory)",
    )
    settings = parser.parse_args(argv).settings
    experiments = [name for key, value in settings if key == "experiment" for name in value.split(",") if name]
    if not experiments:
        parser.error("experiment=NAME is required")
    options = dict(settings)
    os.environ.setdefault("MLFLOW_ENABLE_ARTIFACTS_PROGRESS_BAR", "false")  # one bar per policy file is noise
    uri = options.get("tracking_uri") or default_tracking_uri(Path.cwd())
    database = sqlite_path(uri)
    if database is not None and not database.is_file():
        parser.error(f"no tracking database at {database}: run a search first, or pass tracking_uri=")
    try:
        path = write_report(connect(uri), experiments, Path(options.get("out", "docs/report")))
    except ValueError as error:
        print(f"colmo.report: error: {error}", file=sys.stderr)
        sys.exit(2)
    print(path)


if __name__ == "__main__":
    main()
