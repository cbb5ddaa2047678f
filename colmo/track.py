"""Logging runs to MLflow: one MLflow run per search (per Hydra job), with every program and score.

Where runs go. `tracker.tracking_uri: null` means `sqlite:///<launch dir>/mlruns.db`, the launch
directory being the working directory `python -m colmo` was started in (Hydra 1.3 does not
chdir), so every job of a `-m` sweep shares one database; browse it with
`mlflow ui --backend-store-uri sqlite:///mlruns.db` from that directory. Artifacts go next to
the database, in `mlartifacts/<experiment>/`: the location is fixed when the experiment is
created, so runs launched from any directory land in one place. Any other URI
(`http://host:5000`, `postgresql://...`) is handed to MLflow as is.

What a run holds (experiment: `tracker.experiment`, else the task name; run name:
`tracker.run_name`, else `<task>-<gfo>-<llm>-s<seed>` from the Hydra choices):
- params: the resolved config flattened to dot keys (`gfo.budget`), and the task's
  `spec.observation_size` / `spec.action_size`;
- tags: task, llm, gfo, seed, overrides (the job's command-line overrides), colmo.run_dir,
  colmo.version and, in a git checkout, mlflow.source.git.commit;
- metrics at step = samples so far, after every batch: best_score, best_score_island_<i>,
  programs_evaluated, duplicates, failures, evaluations_per_second, generator_busy,
  evaluator_busy, generation_seconds, evaluation_seconds, queue_depth;
- every sample (evaluated, failed, duplicate or unusable; not the spec's starter) with the
  columns of `PROGRAM_COLUMNS`: `programs/batch_<k>.json` as each batch lands, and at the end
  the MLflow table `programs.json` with all of them. Across runs:
      mlflow.set_tracking_uri(uri); mlflow.set_experiment("pendulum")
      mlflow.load_table("programs.json", run_ids=[...], extra_columns=["run_id"])
  (`MlflowClient(uri).load_table` also searches the *global* tracking URI: set it.)
  The batch files use log_table's JSON layout (`pandas.read_json(path, orient="split")`) but
  are not registered as tables: MLflow lists a run's tables in one tag capped at 8000
  characters, which per-batch `log_table` calls overflow after ~150 batches (measured with
  MLflow 3.17: the tag is truncated and the run's table list no longer parses);
- at the end: best_policy.py, summary.json, the Hydra config files under `hydra/`, and the
  best-so-far plot `best_so_far.png`; status FINISHED, KILLED (interrupted) or FAILED (the
  generator failed, or the process exited without finishing the search).

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
import fcntl
import importlib.metadata
import json
import re
import subprocess
import time
from pathlib import Path
from typing import Any, Callable, Iterator, Optional, Sequence, TypeVar

import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from mlflow import MlflowClient
from mlflow.entities import Metric, Param, RunStatus
from mlflow.exceptions import MlflowException
from mlflow.utils.validation import MAX_PARAMS_TAGS_PER_BATCH

from colmo.config import ConfigError, SearchConfig
from colmo.search import BEST_POLICY_FILE, SUMMARY_FILE
from colmo.spec import SpecError, load_spec
from colmo.store import SampleRecord

DATABASE_FILE = "mlruns.db"
ARTIFACTS_DIR = "mlartifacts"
PROGRAMS_TABLE = "programs.json"
PLOT_FILE = "best_so_far.png"
PROGRAM_COLUMNS = ("sample", "batch", "status", "island", "key", "code", "params", "score", "parents", "failure")
# Report fields that are not metrics: the batch index, the step itself, and the island list
# (logged one metric per island).
_NOT_METRICS = ("batch", "samples", "best_per_island")
_LOCK_RETRIES = 6

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
def _store_lock(uri: str) -> Iterator[None]:
    """Exclusive across processes for a SQLite store; nothing to do for a server or other database."""
    path = sqlite_path(uri)
    if path is None:
        yield
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(f"{path}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def connect(uri: str) -> MlflowClient:
    """A client on `uri`, whose schema is created or migrated by one process at a time."""
    with _store_lock(uri):
        return MlflowClient(uri)  # builds (and caches per process) the store: schema set-up happens here


def open_experiment(uri: str, name: str) -> tuple[MlflowClient, str]:
    """A client on `uri` and the id of experiment `name`, created if missing, safely when
    several processes start at once."""
    with _store_lock(uri):
        client = MlflowClient(uri)
        experiment = client.get_experiment_by_name(name)
        if experiment is not None:
            return client, experiment.experiment_id
        path = sqlite_path(uri)
        # Pinned here: MLflow's default is ./mlruns relative to whichever directory the first run used.
        location = str(path.parent / ARTIFACTS_DIR / re.sub(r"[^\w.-]+", "_", name)) if path else None
        return client, client.create_experiment(name, artifact_location=location)


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
    """One sample as a row of the programs table."""
    return {
        "sample": record.sample, "batch": record.batch, "status": record.status, "island": record.island,
        "key": record.key, "code": record.code, "params": record.params, "score": record.score,
        "parents": record.parent_keys, "failure": record.failure,
    }


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


def _status(stop_reason: str) -> str:
    if stop_reason == "interrupted":
        return RunStatus.to_string(RunStatus.KILLED)
    if stop_reason.startswith("generator failed"):
        return RunStatus.to_string(RunStatus.FAILED)
    return RunStatus.to_string(RunStatus.FINISHED)


def draw_best_so_far(
    ax: Axes, steps: Sequence[int], best: Sequence[float], per_island: Sequence[Sequence[float]], color: str, label: str
) -> None:
    """Fig. 4's curves on `ax`: solid, the best over all islands; dashed, the best of each island."""
    for island in per_island:
        ax.plot(steps, island, color=color, linestyle="--", linewidth=0.7, alpha=0.35, drawstyle="steps-post")
    ax.plot(steps, best, color=color, linewidth=2.0, label=label, drawstyle="steps-post")


# -- the observer -------------------------------------------------------------------------------


class MlflowTracker:
    """A `SearchObserver` that logs one search into one MLflow run."""

    def __init__(self, client: MlflowClient, run_id: str, hydra_dir: Optional[Path]):
        self.client = client
        self.run_id = run_id
        self.hydra_dir = hydra_dir
        self.rows: list[dict[str, Any]] = []
        self.steps: list[int] = []
        self.best: list[float] = []
        self.per_island: list[list[float]] = []
        # A search that dies before on_finish must not stay RUNNING in the UI forever.
        atexit.register(self._end, RunStatus.to_string(RunStatus.FAILED))

    def on_batch(self, report: dict[str, Any], records: list[SampleRecord]) -> None:
        step = report["samples"]
        values = {name: float(value) for name, value in report.items() if name not in _NOT_METRICS}
        values.update({f"best_score_island_{i}": score for i, score in enumerate(report["best_per_island"])})
        stamp = int(time.time() * 1000)
        metrics = [Metric(name, value, stamp, step) for name, value in values.items()]
        retry_locked(self.client.log_batch, self.run_id, metrics=metrics)
        rows = [program_row(record) for record in records]
        table = {"columns": list(PROGRAM_COLUMNS), "data": [[row[c] for c in PROGRAM_COLUMNS] for row in rows]}
        self.client.log_dict(self.run_id, table, f"programs/batch_{report['batch']:05d}.json")
        self.rows += rows
        self.steps.append(step)
        self.best.append(report["best_score"])
        self.per_island.append(list(report["best_per_island"]))

    def on_finish(self, summary: dict[str, Any]) -> None:
        if self.rows:
            table = pd.DataFrame(self.rows, columns=list(PROGRAM_COLUMNS))
            # Not retried: log_table appends to an existing file, so a retry could double the rows.
            self.client.log_table(self.run_id, data=table, artifact_file=PROGRAMS_TABLE)
        run_dir = Path(summary["run_dir"])
        for name in (BEST_POLICY_FILE, SUMMARY_FILE):
            if (run_dir / name).is_file():
                self.client.log_artifact(self.run_id, str(run_dir / name))
        if self.hydra_dir is not None and self.hydra_dir.is_dir():
            self.client.log_artifacts(self.run_id, str(self.hydra_dir), "hydra")
        if self.steps:
            self.client.log_figure(self.run_id, self._figure(summary["task"]), PLOT_FILE)
        self._end(_status(summary["stop_reason"]))
        atexit.unregister(self._end)  # only now: if logging above fails, the run still ends FAILED

    def _figure(self, task: str) -> Figure:
        figure = Figure(figsize=(7, 4.5), layout="constrained")
        ax = figure.subplots()
        islands = [list(column) for column in zip(*self.per_island)]
        draw_best_so_far(ax, self.steps, self.best, islands, "tab:blue", "best over all islands")
        ax.set(title=f"{task}: best so far (dashed: per island)", xlabel="programs sampled", ylabel="score")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncols=3, frameon=False)  # below: never over the curves
        return figure

    def _end(self, status: str) -> None:
        retry_locked(self.client.set_terminated, self.run_id, status)


def make_tracker(cfg: SearchConfig, run_dir: Path) -> MlflowTracker:
    """Start this Hydra job's MLflow run; call inside the Hydra app."""
    from hydra.core.hydra_config import HydraConfig

    hydra = HydraConfig.get()
    try:
        environment = load_spec(cfg.task.spec).make_environment(**cfg.task.env)
    except SpecError as error:
        raise ConfigError(str(error)) from None
    uri = cfg.tracker.tracking_uri or default_tracking_uri(Path(hydra.runtime.cwd))
    client, experiment_id = open_experiment(uri, cfg.tracker.experiment or cfg.task.name)
    choices = hydra.runtime.choices
    search_dir = Path(cfg.resume).expanduser().resolve() if cfg.resume else run_dir  # where Search writes
    tags = {
        "task": cfg.task.name, "llm": choices["llm"], "gfo": choices["gfo"],
        "seed": str(cfg.seed), "overrides": " ".join(hydra.overrides.task), "colmo.run_dir": str(search_dir),
        "colmo.version": importlib.metadata.version("colmo"),
    }
    commit = _git_commit()
    if commit:
        tags["mlflow.source.git.commit"] = commit
    name = cfg.tracker.run_name or f"{tags['task']}-{tags['gfo']}-{tags['llm']}-s{cfg.seed}"
    run = retry_locked(client.create_run, experiment_id, tags=tags, run_name=name)
    params = flatten(dataclasses.asdict(cfg))
    params.update({"spec.observation_size": str(environment.observation_size), "spec.action_size": str(environment.action_size)})
    items = [Param(key, value) for key, value in params.items()]
    for start in range(0, len(items), MAX_PARAMS_TAGS_PER_BATCH):
        retry_locked(client.log_batch, run.info.run_id, params=items[start : start + MAX_PARAMS_TAGS_PER_BATCH])
    hydra_dir = run_dir / hydra.output_subdir if hydra.output_subdir else None  # null: Hydra wrote no config files
    return MlflowTracker(client, run.info.run_id, hydra_dir)
