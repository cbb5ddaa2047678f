"""A Hydra job's MLflow run: a search's (`MlflowTracker`, the search's observer) or a
`colmo-optimize` job's (`track_optimize`).

Run names are unique and readable: `<task>-<gfo>-<llm>-s<seed>-<HHMMSS>` (the job's start
time), with `-j<job number>` in a sweep; `tracker.run_name` replaces the whole name.

What a search's run holds:
- params: the resolved config flattened to dot keys (`gfo.budget`); after the first batch
  (once the search has shown that the task's environment builds), the task's
  `spec.observation_size` / `spec.action_size`;
- tags: task, llm, gfo, seed, overrides (the job's command-line overrides), colmo.command,
  colmo.run_dir, colmo.version and, in a git checkout, mlflow.source.git.commit;
- metrics at step = samples so far, after every batch: `BatchReport.metrics()` (best_score,
  best_score_island_<i>, programs_evaluated, evaluations, steps, valid_program_rate,
  evaluations_per_second, seconds (since the search started), ...) and `samples`, so the run
  list shows the latest of each as a column and curves can be drawn against samples,
  evaluations or seconds; at the end also `best_heldout_score` (the best program's score on
  `heldout.episodes` fresh episodes); each rounded to 4 significant digits, the run list's
  metrics first (`colmo.track.backend`);
- the programs table `programs.json` and page `programs.html` (`colmo.track.programs`),
  rewritten whole at most every `table_every_s` seconds during the run and once at the end; the
  table is registered once in MLflow's table list, so it never grows the 8000-character tag
  that lists tables (one `log_table` per batch overflowed it after ~150 batches). Across runs:
      os.environ["MLFLOW_ENABLE_ARTIFACTS_PROGRESS_BAR"] = "false"  # no download progress bars
      mlflow.set_tracking_uri(uri); mlflow.set_experiment("pendulum")
      mlflow.load_table("programs.json", run_ids=[...], extra_columns=["run_id"])
  (`MlflowClient(uri).load_table` also searches the *global* tracking URI: set it.)
- at the end: best_policy.py, simplified_policy.py (when simplification made it), retuned_policy.py and metrics
  `retuned_score`, `retuned_heldout_score` (with `finish.retune_budget`), summary.json, the Hydra config files under `hydra/`, the
  best-so-far plot `best_so_far.png` (against model calls and against seconds, side by side), and the best policy's plot and video on a held-out episode
  under `best_policy/` (when `finish.render` made them), with `finish.robustness` its robustness report
  (`robustness.json/.csv/.png` under `robustness/`, metrics `robustness_nominal`, `robustness_worst`,
  `robustness_all_10` (every factor at 10%), `robustness_failures`); status FINISHED, KILLED (interrupted) or FAILED (the
  generator failed, or the process exited without finishing the search).
A resumed search (`resume=`) goes on in the run its earlier processes logged into
(`colmo.track.resumed`, named in the run directory's `mlflow_run.json`): reopened in its store,
its table and curves read back, the resuming overrides the tag `colmo.resumed`.

A `colmo-optimize` run (`track_optimize`) holds the same params and tags, the metrics of its
`result.json` (score_initial, score, heldout_score, evaluations, steps, seconds, n_params) and the
files tuned_policy.py and result.json.
"""

from __future__ import annotations

import atexit
import dataclasses
import datetime
import json
import logging
import math
import tempfile
import time
from pathlib import Path
from typing import Any, Optional, Sequence

import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from mlflow import MlflowClient
from mlflow.utils.mlflow_tags import MLFLOW_LOGGED_ARTIFACTS, MLFLOW_PARENT_RUN_ID

from colmo.config import OptimizeConfig, SearchConfig
from colmo.provenance import mlflow_tags
from colmo.readability import METRICS as READABILITY_METRICS
from colmo.record import BatchReport, SampleRecord, Summary
from colmo.store import BEST_POLICY_FILE, BEST_SO_FAR_PLOT, RETUNED_POLICY_FILE, SIMPLIFIED_POLICY_FILE, SUMMARY_FILE
from colmo.track.backend import FAILED, FINISHED, KILLED, RUNNING, browse_hint, default_tracking_uri, log_metrics, log_params, open_experiment, retry_locked
from colmo.track.programs import PROGRAM_COLUMNS, PROGRAMS_PAGE, PROGRAMS_TABLE, program_row, programs_page
from colmo.track.resumed import RUN_DIR_TAG, earlier_run, history, remember, remembered
from colmo.track.sweep import sweep_parent, update_parent

log = logging.getLogger("colmo.track")

TABLE_EVERY_S = 30.0
STOP_REASON_TAG = "colmo.stop_reason"  # max_samples, max_seconds, ...: which limit a finished search reached
RESUMED_TAG = "colmo.resumed"  # the overrides of the process that last resumed the search


def flatten(values: dict[str, Any], prefix: str = "") -> dict[str, str]:
    """Nested config values as MLflow params: dot keys, strings as they are, the rest as JSON."""
    flat: dict[str, str] = {}
    for name, value in values.items():
        key = f"{prefix}{name}"
        if isinstance(value, dict) and value:
            flat.update(flatten(value, f"{key}."))
        else:
            flat[key] = value if isinstance(value, str) else json.dumps(value)
    return flat


def _status(summary: Summary) -> str:
    if summary.stop_reason == "interrupted":
        return KILLED
    if summary.failure is not None:  # the generator failed, the disk is full, no program evaluated
        return FAILED
    return FINISHED


def draw_best_so_far(
    ax: Axes, steps: Sequence[float], best: Sequence[float], per_island: Sequence[Sequence[float]], color: str, label: Optional[str]
) -> None:
    """Fig. 4's curves on `ax`: solid, the best over all islands; dashed, the best of each island."""
    for island in per_island:
        ax.plot(steps, island, color=color, linestyle="--", linewidth=0.7, alpha=0.35, drawstyle="steps-post")
    ax.plot(steps, best, color=color, linewidth=2.0, label=label, drawstyle="steps-post")


# -- starting a run -------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class TrackedRun:
    """An MLflow run of this Hydra job, and its sweep's parent run if it has one."""

    client: MlflowClient
    experiment_id: str
    run_id: str
    name: str
    parent_id: Optional[str]
    sweep_dir: Optional[Path]
    hydra_dir: Optional[Path]  # Hydra's config files of this job
    continued: bool = False  # the run of a resumed search's earlier processes, reopened
    tracking_uri: str = ""

    def log_hydra_config(self) -> None:
        """Hydra's config files of this job, as the run's `hydra/` artifacts."""
        if self.hydra_dir is not None and self.hydra_dir.is_dir():
            self.client.log_artifacts(self.run_id, str(self.hydra_dir), "hydra")

    def end(self, status: str) -> None:
        retry_locked(self.client.set_terminated, self.run_id, status)
        if self.parent_id is not None:
            update_parent(self.client, self.experiment_id, self.parent_id, self.sweep_dir)


def start_run(
    cfg: SearchConfig | OptimizeConfig, variant: str, tags: dict[str, str], start_time: Optional[float] = None, resumes: Optional[str] = None,
) -> TrackedRun:
    """Start this Hydra job's MLflow run, as a child of its sweep's parent in a `-m` sweep;
    `variant` is the readable middle of the run name (`pendulum-oneplusone-mutate-s0`). A search
    that `resumes` a run directory goes on in the run its earlier processes logged into, if
    there is one: reopened, the params it lacks added (MLflow keeps a param's first value: the
    resumed process's overrides are the tag `colmo.resumed`)."""
    from hydra.core.hydra_config import HydraConfig
    from hydra.types import RunMode

    hydra = HydraConfig.get()
    launch_dir = Path(hydra.runtime.cwd)
    recalled = remembered(Path(resumes)) if resumes else {}  # where the resumed search's run is, from wherever it is resumed
    uri = cfg.tracker.tracking_uri or recalled.get("tracking_uri") or default_tracking_uri(launch_dir)
    experiment = cfg.tracker.experiment or cfg.task.name
    client, experiment_id = open_experiment(uri, experiment)
    started = start_time or time.time()
    clock = datetime.datetime.fromtimestamp(started).strftime("%H%M%S")
    tags = {**tags, "overrides": " ".join(hydra.overrides.task), **mlflow_tags()}
    parent_id = sweep_dir = None
    name = f"{variant}-{clock}"
    if hydra.mode == RunMode.MULTIRUN:
        sweep_dir = (launch_dir / hydra.sweep.dir).resolve()
        parent_tags = {key: tags[key] for key in ("colmo.version", "mlflow.source.git.commit", "colmo.uncommitted_changes") if key in tags}
        parent_id = sweep_parent(client, experiment_id, sweep_dir, f"{experiment}-sweep-{clock}", parent_tags)
        tags[MLFLOW_PARENT_RUN_ID] = parent_id
        name = f"{name}-j{hydra.job.num}"
    params = flatten(dataclasses.asdict(cfg))
    earlier = earlier_run(client, experiment_id, resumes, recalled.get("run_id")) if resumes else None
    if earlier is not None:
        run_id, name = earlier.info.run_id, earlier.info.run_name
        retry_locked(client.update_run, run_id, status=RUNNING)
        retry_locked(client.set_tag, run_id, RESUMED_TAG, tags["overrides"])
        log_params(client, run_id, {key: value for key, value in params.items() if key not in earlier.data.params})
    else:
        run = retry_locked(client.create_run, experiment_id, start_time=int(started * 1000), tags=tags, run_name=cfg.tracker.run_name or name)
        run_id, name = run.info.run_id, run.info.run_name
        log_params(client, run_id, params)
    hydra_dir = Path(hydra.runtime.output_dir) / hydra.output_subdir if hydra.output_subdir else None  # null: no config files
    went_on = " (goes on: the search resumes)" if earlier is not None else ""
    log.info("MLflow run %s%s in experiment %s; browse: %s", name, went_on, experiment, browse_hint(uri, experiment_id))
    return TrackedRun(client, experiment_id, run_id, name, parent_id, sweep_dir, hydra_dir, continued=earlier is not None, tracking_uri=uri)


# -- the search's observer ------------------------------------------------------------------------


class MlflowTracker:
    """A `SearchObserver` that logs one search into one MLflow run."""

    def __init__(self, run: TrackedRun, spec: Optional[str] = None, env: Optional[dict[str, Any]] = None, table_every_s: float = TABLE_EVERY_S):
        self.run = run
        self.table_every_s = table_every_s
        self.client, self.run_id = run.client, run.run_id
        self.spec, self.env = spec, env or {}
        self.rows: list[dict[str, Any]] = []
        self.table_written = -math.inf
        self.table_registered = False
        self.steps: list[int] = []
        self.seconds: list[float] = []
        self.best: list[float] = []
        self.per_island: list[list[float]] = []
        if run.continued:  # the table and the curves go on from what the earlier processes logged
            earlier = history(self.client, self.run_id)
            self.rows, self.steps, self.seconds, self.best, self.per_island = earlier.rows, earlier.steps, earlier.seconds, earlier.best, earlier.per_island
            self.table_registered = bool(self.rows)
        # A search that dies before on_finish must not stay RUNNING in the UI forever.
        atexit.register(self.run.end, FAILED)

    def on_batch(self, report: BatchReport, records: list[SampleRecord]) -> None:
        log_metrics(self.client, self.run_id, {**report.metrics(), "samples": report.samples}, report.samples)
        if not self.steps:
            self._log_dimensions()
        self.rows += [program_row(record) for record in records]
        if time.monotonic() - self.table_written >= self.table_every_s:
            self._write_table()
        self.steps.append(report.samples)
        self.seconds.append(report.seconds)
        self.best.append(report.best_score)
        self.per_island.append(list(report.best_per_island))

    def on_finish(self, summary: Summary) -> None:
        # The rest of the summary's totals were logged with the last batch.
        headline = {name: value for name, value in summary.robustness.items() if name.startswith("robustness_")}
        readable = {f"readability_{name}": summary.readability.get(name) for name in READABILITY_METRICS}
        retuned = {f"retuned_{name}": summary.retuned.get(name) for name in ("score", "heldout_score")} if summary.retuned else {}
        log_metrics(
            self.client, self.run_id, {"best_heldout_score": summary.best_heldout_score, **retuned, **headline, **_split(summary), **readable}, summary.samples,
        )
        heldout = {entry["sample"]: entry["heldout_score"] for entry in summary.heldout}
        for row in self.rows:
            row["heldout_score"] = heldout.get(row["sample"], row["heldout_score"])
        if self.rows:
            self._write_table()
        run_dir = Path(summary.run_dir)
        for name in (BEST_POLICY_FILE, SIMPLIFIED_POLICY_FILE, RETUNED_POLICY_FILE, SUMMARY_FILE):  # each one the search made
            if (run_dir / name).is_file():
                self.client.log_artifact(self.run_id, str(run_dir / name))
        for kind in ("plot", "video"):  # the best policy on a held-out episode
            if kind in summary.media and (run_dir / summary.media[kind]).is_file():
                self.client.log_artifact(self.run_id, str(run_dir / summary.media[kind]), "best_policy")
        for name in summary.robustness.get("files", ()):  # the best policy under model mismatch
            self.client.log_artifact(self.run_id, str(run_dir / name), "robustness")
        self.run.log_hydra_config()
        retry_locked(self.client.set_tag, self.run_id, STOP_REASON_TAG, summary.stop_reason)  # which limit the run reached
        if self.steps:
            self.client.log_figure(self.run_id, self._figure(summary.task), BEST_SO_FAR_PLOT)
        self.run.end(_status(summary))
        atexit.unregister(self.run.end)  # only now: if logging above fails, the run still ends FAILED

    def _log_dimensions(self) -> None:
        """The task's observation and action sizes as params, read from its environment once the
        first batch has shown that it builds (in the workers); a failure here only costs them."""
        if self.spec is None:
            return
        from colmo.specs import load_spec

        try:
            environment = load_spec(self.spec).make_environment(**self.env)
            dims = {"spec.observation_size": str(environment.observation_size), "spec.action_size": str(environment.action_size)}
        except Exception as error:  # the spec's code: anything can fail; the search goes on
            log.warning("MLflow: could not read the task's dimensions: %s", error)
            return
        log_params(self.client, self.run_id, dims)

    def _write_table(self) -> None:
        """Rewrite `programs.json` with every row so far (MLflow's log_table would download and
        append to it: quadratic traffic), and register it as a table once."""
        table = pd.DataFrame(self.rows, columns=list(PROGRAM_COLUMNS))
        with tempfile.TemporaryDirectory() as scratch:
            path, page = Path(scratch) / PROGRAMS_TABLE, Path(scratch) / PROGRAMS_PAGE
            table.to_json(path, orient="split", index=False, date_format="iso")  # log_table's layout
            page.write_text(programs_page(self.rows, self.run.name))
            retry_locked(self.client.log_artifact, self.run_id, str(path))
            retry_locked(self.client.log_artifact, self.run_id, str(page))
        if not self.table_registered:
            registered = json.loads(self.client.get_run(self.run_id).data.tags.get(MLFLOW_LOGGED_ARTIFACTS, "[]"))
            entry = {"path": PROGRAMS_TABLE, "type": "table"}
            if entry not in registered:
                retry_locked(self.client.set_tag, self.run_id, MLFLOW_LOGGED_ARTIFACTS, json.dumps([*registered, entry]))
            self.table_registered = True
        self.table_written = time.monotonic()

    def _figure(self, task: str) -> Figure:
        """Best so far against model calls and, beside it, against seconds of search: what a
        sample buys and what a second buys (GFO spends seconds to make each sample count)."""
        figure = Figure(figsize=(12, 4.5), layout="constrained")
        islands = [list(column) for column in zip(*self.per_island)]
        for ax, x, label in zip(figure.subplots(1, 2), (self.steps, self.seconds), ("model calls", "seconds of search (wall clock)")):
            draw_best_so_far(ax, x, self.best, islands, "tab:blue", "best over all islands")
            ax.set(xlabel=label, ylabel="score")
            ax.grid(alpha=0.3)
            ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncols=3, frameon=False)  # below: never over the curves
        figure.suptitle(f"{task}: best so far (dashed: per island)")
        return figure


def _choices() -> dict[str, str]:
    from hydra.core.hydra_config import HydraConfig

    return dict(HydraConfig.get().runtime.choices)


def start_search_run(cfg: SearchConfig, run_dir: Path) -> MlflowTracker:
    """Start this Hydra job's MLflow run for a search into `run_dir`; call inside the Hydra app.
    Builds nothing of the task: a spec that fails is the search's to report."""
    choices = _choices()
    search_dir = Path(cfg.resume).expanduser().resolve() if cfg.resume else run_dir  # where Search writes
    tags = {
        "task": cfg.task.name, "llm": choices["llm"], "gfo": choices["gfo"], "seed": str(cfg.seed),
        "colmo.command": "search", RUN_DIR_TAG: str(search_dir),
    }
    variant = f"{cfg.task.name}-{choices['gfo']}-{choices['llm']}-s{cfg.seed}"
    run = start_run(cfg, variant, tags, resumes=str(search_dir) if cfg.resume else None)
    remember(search_dir, run.tracking_uri, run.run_id)
    return MlflowTracker(run, cfg.task.spec, cfg.task.env)


# -- colmo-optimize -------------------------------------------------------------------------------

OPTIMIZE_METRICS = ("score_initial", "score", "heldout_score", "evaluations", "steps", "seconds", "n_params")


def track_optimize(cfg: OptimizeConfig, result: dict[str, Any], files: Sequence[Path], started: float) -> str:
    """Log one finished `colmo-optimize` job (its `result.json` fields and `files`) as an MLflow
    run that started at `started` (epoch seconds); its run id."""
    choices = _choices()
    tags = {
        "task": cfg.task.name, "gfo": choices["gfo"], "seed": str(cfg.seed), "colmo.command": "optimize",
        "policy_file": str(Path(cfg.policy_file).expanduser().resolve()),
    }
    variant = f"{cfg.task.name}-optimize-{choices['gfo']}-{Path(cfg.policy_file).stem}-s{cfg.seed}"
    run = start_run(cfg, variant, tags, start_time=started)
    try:
        log_metrics(run.client, run.run_id, {name: result.get(name) for name in OPTIMIZE_METRICS}, 0)
        for path in files:
            run.client.log_artifact(run.run_id, str(path))
        run.log_hydra_config()
    except BaseException:
        run.end(FAILED)
        raise
    run.end(FAILED if result.get("failure") else FINISHED)
    return run.run_id


def _split(summary: Summary) -> dict[str, Optional[float]]:
    """A search of more than one generator (`search.fill`): each one's samples, programs
    evaluated, best score and island bests, as `<metric>_<generator>`."""
    if len(summary.by_generator) < 2:
        return {}
    metrics = ("samples", "programs_evaluated", "best_score", "island_bests")
    return {f"{metric}_{name}": entry[metric] for name, entry in summary.by_generator.items() for metric in metrics}
