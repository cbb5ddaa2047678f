"""Logging runs to MLflow: one MLflow run per search or tuning (per Hydra job), a parent run per
`-m` sweep, with every program and score.

Where runs go. `tracker.tracking_uri: null` means `sqlite:///<launch dir>/mlruns.db`, the launch
directory being the working directory `colmo` was started in (Hydra 1.3 does not chdir), so
every job of a `-m` sweep shares one database; browse it with
`mlflow ui --backend-store-uri sqlite:///mlruns.db` from that directory. Artifacts go next to
the database, in `mlartifacts/<experiment>/`: the location is fixed when the experiment is
created, so runs launched from any directory land in one place. Any other URI
(`http://host:5000`, `postgresql://...`) is handed to MLflow as is.

Experiments (`tracker.experiment`, else the task name) are tagged as classic ML experiments
(`mlflow.experimentKind: custom_model_development`, which MLflow 3.0-3.4's UI reads) and carry a
shared view of the run list (`mlflow.sharedViewState.colmo`): the key metrics and GFO/LLM/seed
as columns, best score first. MLflow 3.17's UI opens in its GenAI view (traces, judges) whatever
the tag says, and shows no metric column until one is chosen, so each run logs where to look:
`<UI address>` + `ui_path(experiment_id)`, which selects the classic view and colmo's columns
(the UI's "Override saved view" keeps them).

Sweeps. Every job of a `-m` sweep is a child run (tag `mlflow.parentRunId`) of one parent run
per sweep and experiment, named `<experiment>-sweep-<HHMMSS>`. Whichever job comes first creates
the parent; the others find it by its tag `colmo.sweep` (a hash of the absolute
`hydra.sweep.dir`), all under an exclusive file lock in the sweep directory, so this holds for
any launcher (basic, joblib, submitit) and any tracking store. The parent holds the sweep's
overrides (from Hydra's `multirun.yaml`) and, after each job, the best `best_score` and
`best_heldout_score` over its children and their count (`runs`); its status is RUNNING while a
child runs, else FAILED or KILLED if a child did, else FINISHED (between two jobs of the basic
launcher it is briefly FINISHED).

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
  `evaluation.episodes` fresh episodes);
- the MLflow table `programs.json`, one row per sample (evaluated, failed, duplicate or unusable;
  not the spec's starter) with the columns of `PROGRAM_COLUMNS`, the code in full, and the same
  rows as the page `programs.html`, best first, each program's code laid out as code (the UI's
  table view cuts cells to one line; it renders an HTML artifact as a page). Both are rewritten
  whole at most every `TABLE_EVERY_S` seconds during the run and once at the end; the table is
  registered once in MLflow's table list, so it never grows the 8000-character tag that lists
  tables (one `log_table` per batch overflowed it after ~150 batches). Across runs:
      os.environ["MLFLOW_ENABLE_ARTIFACTS_PROGRESS_BAR"] = "false"  # no download progress bars
      mlflow.set_tracking_uri(uri); mlflow.set_experiment("pendulum")
      mlflow.load_table("programs.json", run_ids=[...], extra_columns=["run_id"])
  (`MlflowClient(uri).load_table` also searches the *global* tracking URI: set it.)
- at the end: best_policy.py, summary.json, the Hydra config files under `hydra/`, the
  best-so-far plot `best_so_far.png`, and the best policy's plot and video on a held-out episode
  under `best_policy/` (when `evaluation.render` made them); status FINISHED, KILLED (interrupted) or FAILED (the
  generator failed, or the process exited without finishing the search).

A `colmo-optimize` run (`track_optimize`) holds the same params and tags, the metrics of its
`result.json` (score_initial, score, heldout_score, evaluations, steps, seconds, n_params) and the
files tuned_policy.py and result.json.

Concurrency. MLflow's SQLAlchemy store creates and migrates its schema on first use without a
lock, so sweep jobs starting together collide ("duplicate column name: step", "table already
exists"). Opening the store and getting or creating the experiment therefore happen under an
exclusive `fcntl.flock` on `<db>.lock`. Later writes are short transactions; a "database is
locked" that outlasts SQLite's busy timeout is retried.
"""

from __future__ import annotations

import atexit
import contextlib
import dataclasses
import datetime
import fcntl
import hashlib
import html
import importlib.metadata
import json
import logging
import math
import re
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any, Callable, Iterator, Optional, Sequence, TypeVar

import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from mlflow import MlflowClient
from mlflow.entities import Metric, Param, RunStatus
from mlflow.exceptions import MlflowException
from mlflow.utils.mlflow_tags import MLFLOW_LOGGED_ARTIFACTS, MLFLOW_PARENT_RUN_ID
from mlflow.utils.validation import MAX_METRICS_PER_BATCH, MAX_PARAMS_TAGS_PER_BATCH

from colmo.config import OptimizeConfig, SearchConfig
from colmo.record import BatchReport, SampleRecord, Summary
from colmo.store import BEST_POLICY_FILE, SUMMARY_FILE

log = logging.getLogger("colmo.track")

DATABASE_FILE = "mlruns.db"
ARTIFACTS_DIR = "mlartifacts"
PROGRAMS_TABLE = "programs.json"
PLOT_FILE = "best_so_far.png"
# The UI shows a table's first columns: score and code first, bookkeeping last.
PROGRAM_COLUMNS = ("sample", "score", "heldout_score", "status", "code", "failure", "island", "batch", "key", "params", "parents")
PROGRAMS_PAGE = "programs.html"
TABLE_EVERY_S = 30.0
EXPERIMENT_KIND_TAG = "mlflow.experimentKind"
CLASSIC_ML = "custom_model_development"  # MLflow 3's value for a classic (not GenAI) experiment
# A view of the run list that MLflow's UI opens from `?viewStateShareKey=colmo`: the columns a
# person compares searches by, best score first (the UI shows no metric column unless chosen).
VIEW_KEY = "colmo"
VIEW_TAG = f"mlflow.sharedViewState.{VIEW_KEY}"
VIEW_METRICS = (
    "best_score", "best_heldout_score", "samples", "programs_evaluated", "valid_program_rate",
    "evaluations_per_second", "evaluations", "steps", "seconds",
)
VIEW_PARAMS = ("gfo.method", "gfo.budget", "llm.name", "seed")
VIEW_STATE = json.dumps({
    "selectedColumns": [f"metrics.`{m}`" for m in VIEW_METRICS] + [f"params.`{p}`" for p in VIEW_PARAMS],
    "orderByKey": "metrics.`best_score`", "orderByAsc": False,
})
SWEEP_TAG = "colmo.sweep"
SWEEP_LOCK = ".mlflow_parent.lock"
_LOCK_RETRIES = 6
_RUNNING, _FINISHED, _FAILED, _KILLED = (RunStatus.to_string(s) for s in (RunStatus.RUNNING, RunStatus.FINISHED, RunStatus.FAILED, RunStatus.KILLED))

T = TypeVar("T")


# -- the tracking store -----------------------------------------------------------------------


def default_tracking_uri(launch_dir: Path) -> str:
    return f"sqlite:///{(launch_dir / DATABASE_FILE).resolve()}"


def sqlite_path(uri: str) -> Optional[Path]:
    """The database file of a `sqlite:///` URI (relative paths are relative to the cwd)."""
    if not uri.startswith("sqlite:///"):
        return None
    return Path(uri.removeprefix("sqlite:///")).resolve()


@contextlib.contextmanager
def _file_lock(path: Path) -> Iterator[None]:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


@contextlib.contextmanager
def _store_lock(uri: str) -> Iterator[None]:
    """Exclusive across processes for a SQLite store; nothing to do for a server or other database."""
    path = sqlite_path(uri)
    if path is None:
        yield
        return
    with _file_lock(Path(f"{path}.lock")):
        yield


def connect(uri: str) -> MlflowClient:
    """A client on `uri`, whose schema is created or migrated by one process at a time."""
    with _store_lock(uri):
        return MlflowClient(uri)  # builds (and caches per process) the store: schema set-up happens here


def open_experiment(uri: str, name: str) -> tuple[MlflowClient, str]:
    """A client on `uri` and the id of experiment `name`, created if missing (a classic ML
    experiment, with colmo's view of its run list), safely when several processes start at once."""
    tags = {EXPERIMENT_KIND_TAG: CLASSIC_ML, VIEW_TAG: VIEW_STATE}
    with _store_lock(uri):
        client = MlflowClient(uri)
        experiment = client.get_experiment_by_name(name)
        if experiment is not None:
            for key, value in tags.items():
                if key not in experiment.tags:  # made by an older colmo, or by hand
                    client.set_experiment_tag(experiment.experiment_id, key, value)
            return client, experiment.experiment_id
        path = sqlite_path(uri)
        # Pinned here: MLflow's default is ./mlruns relative to whichever directory the first run used.
        location = str(path.parent / ARTIFACTS_DIR / re.sub(r"[^\w.-]+", "_", name)) if path else None
        return client, client.create_experiment(name, artifact_location=location, tags=tags)


def ui_path(experiment_id: str) -> str:
    """Where MLflow's UI (`mlflow ui`, `mlflow server`) shows an experiment's runs as colmo
    lays them out: MLflow 3.17's UI chooses its GenAI or classic view from `workflowType`, not
    from the experiment's kind tag (which earlier 3.x UIs read)."""
    return f"/#/experiments/{experiment_id}/runs?workflowType=machine_learning&viewStateShareKey={VIEW_KEY}"


def retry_locked(call: Callable[..., T], *args: Any, **kwargs: Any) -> T:
    """`call(*args, **kwargs)`, retried with backoff while SQLite says "database is locked"
    (a writer that waited out the busy timeout, or a read lock that could not be upgraded)."""
    for attempt in range(_LOCK_RETRIES - 1):
        try:
            return call(*args, **kwargs)
        except MlflowException as error:
            if "database is locked" not in str(error):
                raise
            time.sleep(0.2 * 2**attempt)
    return call(*args, **kwargs)


# -- what is logged -----------------------------------------------------------------------------


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


def program_row(record: SampleRecord) -> dict[str, Any]:
    """One sample as a row of the programs table (its held-out score is filled in at the end)."""
    return {
        "sample": record.sample, "score": record.score, "heldout_score": record.heldout_score, "status": record.status,
        "code": record.code, "failure": record.failure, "island": record.island, "batch": record.batch,
        "key": record.key, "params": record.params, "parents": record.parent_keys,
    }


def programs_page(rows: Sequence[dict[str, Any]], title: str) -> str:
    """The programs as an HTML page: evaluated ones best first, then the rest by sample, each
    with its code in full."""
    ordered = sorted(rows, key=lambda r: (r["score"] is None, -(r["score"] or 0.0), r["sample"]))
    number = lambda value: "" if value is None else f"{value:.2f}"  # noqa: E731
    cells = []
    for row in ordered:
        code = html.escape(row["code"] or "")
        failure = html.escape(row["failure"] or "")
        cells.append(
            f"<tr><td>{row['sample']}</td><td>{number(row['score'])}</td><td>{number(row['heldout_score'])}</td>"
            f"<td>{row['status']}</td><td>{row['island']}</td><td><pre>{code}</pre>{failure}</td></tr>"
        )
    style = "body{font-family:sans-serif;font-size:13px}td{vertical-align:top;border-top:1px solid #ddd;padding:4px 8px}pre{margin:0}"
    return (
        f"<!doctype html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title><style>{style}</style></head><body>"
        f"<h3>{html.escape(title)}: {len(rows)} samples, best first</h3><table><tr><th>sample</th><th>score</th>"
        f"<th>held-out</th><th>status</th><th>island</th><th>code / failure</th></tr>{''.join(cells)}</table></body></html>"
    )


def _git_commit() -> Optional[str]:
    """HEAD of the colmo checkout this module runs from; None for an installed package (even
    one installed inside some other repository's virtual environment)."""
    package = Path(__file__).resolve().parent
    try:
        result = subprocess.run(
            ["git", "rev-parse", "--show-toplevel", "HEAD"], cwd=package, capture_output=True, text=True, timeout=10
        )
    except (OSError, subprocess.TimeoutExpired):
        return None
    lines = result.stdout.split()
    if result.returncode != 0 or len(lines) != 2 or Path(lines[0]).resolve() != package.parent:
        return None
    return lines[1]


def _status(summary: Summary) -> str:
    if summary.stop_reason == "interrupted":
        return _KILLED
    if summary.resumable:  # the generator failed, the disk is full
        return _FAILED
    return _FINISHED


def _log_metrics(client: MlflowClient, run_id: str, values: dict[str, Optional[float]], step: int) -> None:
    """The finite values of `values` at `step` (a failed score is None or -inf: not a point)."""
    stamp = int(time.time() * 1000)
    metrics = [Metric(k, float(v), stamp, step) for k, v in values.items() if v is not None and math.isfinite(v)]
    for start in range(0, len(metrics), MAX_METRICS_PER_BATCH):
        retry_locked(client.log_batch, run_id, metrics=metrics[start : start + MAX_METRICS_PER_BATCH])


def _log_params(client: MlflowClient, run_id: str, params: dict[str, str]) -> None:
    items = [Param(key, value) for key, value in params.items()]
    for start in range(0, len(items), MAX_PARAMS_TAGS_PER_BATCH):
        retry_locked(client.log_batch, run_id, params=items[start : start + MAX_PARAMS_TAGS_PER_BATCH])


def draw_best_so_far(
    ax: Axes, steps: Sequence[float], best: Sequence[float], per_island: Sequence[Sequence[float]], color: str, label: Optional[str]
) -> None:
    """Fig. 4's curves on `ax`: solid, the best over all islands; dashed, the best of each island."""
    for island in per_island:
        ax.plot(steps, island, color=color, linestyle="--", linewidth=0.7, alpha=0.35, drawstyle="steps-post")
    ax.plot(steps, best, color=color, linewidth=2.0, label=label, drawstyle="steps-post")


# -- sweeps: one parent run, each job a child -----------------------------------------------------


def sweep_parent(client: MlflowClient, experiment_id: str, sweep_dir: Path, name: str, tags: dict[str, str]) -> str:
    """The id of the parent run of the sweep writing into `sweep_dir`, in `experiment_id`: made
    by the first job that asks, found by the others (under a lock in the sweep directory)."""
    sweep_id = hashlib.sha1(str(sweep_dir).encode()).hexdigest()[:16]
    with _file_lock(sweep_dir / SWEEP_LOCK):
        found = retry_locked(client.search_runs, [experiment_id], f"tags.`{SWEEP_TAG}` = '{sweep_id}'", max_results=1)
        if found:
            parent = found[0].info
            if parent.status != _RUNNING:  # a job of the basic launcher after the one before ended
                retry_locked(client.update_run, parent.run_id, status=_RUNNING)
            return parent.run_id
        tags = {**tags, SWEEP_TAG: sweep_id, "colmo.sweep_dir": str(sweep_dir)}
        multirun = sweep_dir / "multirun.yaml"  # written by Hydra's basic sweeper before any job
        if multirun.is_file():
            from omegaconf import OmegaConf

            tags["overrides"] = " ".join(OmegaConf.load(multirun).hydra.overrides.task)
        run_id = retry_locked(client.create_run, experiment_id, tags=tags, run_name=name).info.run_id
        if multirun.is_file():
            client.log_artifact(run_id, str(multirun), "hydra")
        return run_id


def update_parent(client: MlflowClient, experiment_id: str, parent_id: str, sweep_dir: Path) -> None:
    """The parent's metrics and status from its children's, after a child ended (under the
    sweep's lock, so that a job attaching meanwhile is seen)."""
    with _file_lock(sweep_dir / SWEEP_LOCK):
        children = retry_locked(client.search_runs, [experiment_id], f"tags.`{MLFLOW_PARENT_RUN_ID}` = '{parent_id}'", max_results=10000)
        statuses = [child.info.status for child in children]
        best = lambda key: max((c.data.metrics[key] for c in children if key in c.data.metrics), default=None)  # noqa: E731
        values = {"best_score": best("best_score"), "best_heldout_score": best("best_heldout_score"), "runs": len(children)}
        _log_metrics(client, parent_id, values, len(children) - statuses.count(_RUNNING))
        if _RUNNING in statuses:
            return
        status = _FAILED if _FAILED in statuses else _KILLED if _KILLED in statuses else _FINISHED
        retry_locked(client.set_terminated, parent_id, status)


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

    def end(self, status: str) -> None:
        retry_locked(self.client.set_terminated, self.run_id, status)
        if self.parent_id is not None:
            update_parent(self.client, self.experiment_id, self.parent_id, self.sweep_dir)


def start_run(cfg: SearchConfig | OptimizeConfig, variant: str, tags: dict[str, str], start_time: Optional[float] = None) -> TrackedRun:
    """Start this Hydra job's MLflow run, as a child of its sweep's parent in a `-m` sweep;
    `variant` is the readable middle of the run name (`pendulum-oneplusone-mutate-s0`)."""
    from hydra.core.hydra_config import HydraConfig
    from hydra.types import RunMode

    hydra = HydraConfig.get()
    launch_dir = Path(hydra.runtime.cwd)
    uri = cfg.tracker.tracking_uri or default_tracking_uri(launch_dir)
    experiment = cfg.tracker.experiment or cfg.task.name
    client, experiment_id = open_experiment(uri, experiment)
    started = start_time or time.time()
    clock = datetime.datetime.fromtimestamp(started).strftime("%H%M%S")
    tags = {
        **tags, "overrides": " ".join(hydra.overrides.task), "colmo.version": importlib.metadata.version("colmo"),
    }
    commit = _git_commit()
    if commit:
        tags["mlflow.source.git.commit"] = commit
    parent_id = sweep_dir = None
    name = f"{variant}-{clock}"
    if hydra.mode == RunMode.MULTIRUN:
        sweep_dir = (launch_dir / hydra.sweep.dir).resolve()
        parent_tags = {key: tags[key] for key in ("colmo.version", "mlflow.source.git.commit") if key in tags}
        parent_id = sweep_parent(client, experiment_id, sweep_dir, f"{experiment}-sweep-{clock}", parent_tags)
        tags[MLFLOW_PARENT_RUN_ID] = parent_id
        name = f"{name}-j{hydra.job.num}"
    run = retry_locked(
        client.create_run, experiment_id, start_time=int(started * 1000), tags=tags, run_name=cfg.tracker.run_name or name
    )
    _log_params(client, run.info.run_id, flatten(dataclasses.asdict(cfg)))
    hydra_dir = Path(hydra.runtime.output_dir) / hydra.output_subdir if hydra.output_subdir else None  # null: no config files
    browse = f"mlflow ui --backend-store-uri {uri}, then http://127.0.0.1:5000" if sqlite_path(uri) else uri
    log.info("MLflow run %s in experiment %s; browse: %s%s", run.info.run_name, experiment, browse, ui_path(experiment_id))
    return TrackedRun(client, experiment_id, run.info.run_id, run.info.run_name, parent_id, sweep_dir, hydra_dir)


# -- the search's observer ------------------------------------------------------------------------


class MlflowTracker:
    """A `SearchObserver` that logs one search into one MLflow run."""

    def __init__(self, run: TrackedRun, spec: Optional[str] = None, env: Optional[dict[str, Any]] = None):
        self.run = run
        self.client, self.run_id = run.client, run.run_id
        self.spec, self.env = spec, env or {}
        self.rows: list[dict[str, Any]] = []
        self.table_written = -math.inf
        self.table_registered = False
        self.steps: list[int] = []
        self.best: list[float] = []
        self.per_island: list[list[float]] = []
        # A search that dies before on_finish must not stay RUNNING in the UI forever.
        atexit.register(self.run.end, _FAILED)

    def on_batch(self, report: BatchReport, records: list[SampleRecord]) -> None:
        _log_metrics(self.client, self.run_id, {**report.metrics(), "samples": report.samples}, report.samples)
        if not self.steps:
            self._log_dimensions()
        self.rows += [program_row(record) for record in records]
        if time.monotonic() - self.table_written >= TABLE_EVERY_S:
            self._write_table()
        self.steps.append(report.samples)
        self.best.append(report.best_score)
        self.per_island.append(list(report.best_per_island))

    def on_finish(self, summary: Summary) -> None:
        # The rest of the summary's totals were logged with the last batch.
        _log_metrics(self.client, self.run_id, {"best_heldout_score": summary.best_heldout_score}, summary.samples)
        heldout = {entry["sample"]: entry["heldout_score"] for entry in summary.heldout}
        for row in self.rows:
            row["heldout_score"] = heldout.get(row["sample"], row["heldout_score"])
        if self.rows:
            self._write_table()
        run_dir = Path(summary.run_dir)
        for name in (BEST_POLICY_FILE, SUMMARY_FILE):
            if (run_dir / name).is_file():
                self.client.log_artifact(self.run_id, str(run_dir / name))
        for kind in ("plot", "video"):  # the best policy on a held-out episode
            if kind in summary.media and (run_dir / summary.media[kind]).is_file():
                self.client.log_artifact(self.run_id, str(run_dir / summary.media[kind]), "best_policy")
        if self.run.hydra_dir is not None and self.run.hydra_dir.is_dir():
            self.client.log_artifacts(self.run_id, str(self.run.hydra_dir), "hydra")
        if self.steps:
            self.client.log_figure(self.run_id, self._figure(summary.task), PLOT_FILE)
        self.run.end(_status(summary))
        atexit.unregister(self.run.end)  # only now: if logging above fails, the run still ends FAILED

    def _log_dimensions(self) -> None:
        """The task's observation and action sizes as params, read from its environment once the
        first batch has shown that it builds (in the workers); a failure here only costs them."""
        if self.spec is None:
            return
        from colmo.spec import load_spec

        try:
            environment = load_spec(self.spec).make_environment(**self.env)
            dims = {"spec.observation_size": str(environment.observation_size), "spec.action_size": str(environment.action_size)}
        except Exception as error:  # the spec's code: anything can fail; the search goes on
            log.warning("MLflow: could not read the task's dimensions: %s", error)
            return
        _log_params(self.client, self.run_id, dims)

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
        figure = Figure(figsize=(7, 4.5), layout="constrained")
        ax = figure.subplots()
        islands = [list(column) for column in zip(*self.per_island)]
        draw_best_so_far(ax, self.steps, self.best, islands, "tab:blue", "best over all islands")
        ax.set(title=f"{task}: best so far (dashed: per island)", xlabel="programs sampled", ylabel="score")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncols=3, frameon=False)  # below: never over the curves
        return figure


def _choices() -> dict[str, str]:
    from hydra.core.hydra_config import HydraConfig

    return dict(HydraConfig.get().runtime.choices)


def make_tracker(cfg: SearchConfig, run_dir: Path) -> MlflowTracker:
    """Start this Hydra job's MLflow run for a search into `run_dir`; call inside the Hydra app.
    Builds nothing of the task: a spec that fails is the search's to report."""
    choices = _choices()
    search_dir = Path(cfg.resume).expanduser().resolve() if cfg.resume else run_dir  # where Search writes
    tags = {
        "task": cfg.task.name, "llm": choices["llm"], "gfo": choices["gfo"], "seed": str(cfg.seed),
        "colmo.command": "search", "colmo.run_dir": str(search_dir),
    }
    run = start_run(cfg, f"{cfg.task.name}-{choices['gfo']}-{choices['llm']}-s{cfg.seed}", tags)
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
        _log_metrics(run.client, run.run_id, {name: result.get(name) for name in OPTIMIZE_METRICS}, 0)
        for path in files:
            run.client.log_artifact(run.run_id, str(path))
        if run.hydra_dir is not None and run.hydra_dir.is_dir():
            run.client.log_artifacts(run.run_id, str(run.hydra_dir), "hydra")
    except BaseException:
        run.end(_FAILED)
        raise
    run.end(_FAILED if result.get("failure") else _FINISHED)
    return run.run_id
