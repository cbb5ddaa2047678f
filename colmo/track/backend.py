"""The MLflow tracking store: where runs go, opening it safely from processes that start together,
and the experiment with colmo's view of its run list.

Where runs go. `tracker.tracking_uri: null` means `sqlite:///<launch dir>/mlruns.db`, the launch
directory being the working directory `colmo` was started in (Hydra 1.3 does not chdir), so
every job of a `-m` sweep shares one database; browse it with
`mlflow ui --backend-store-uri sqlite:///mlruns.db` from that directory. Artifacts go next to
the database, in `mlartifacts/<experiment>/`: the location is fixed when the experiment is
created, so runs launched from any directory land in one place. Any other URI
(`http://host:5000`, `postgresql://...`) is handed to MLflow as is.

Experiments (`tracker.experiment`, else the task name) are tagged as classic ML experiments
(`mlflow.experimentKind: custom_model_development`, which MLflow 3.0-3.4's UI reads), with
`best_score` as their primary metric (greater is better: the metric the run list's chart view
opens on) and a shared view of the run list (`mlflow.sharedViewState.colmo`, `view_state`):
the runs grouped by GFO method, each group open with its average on its row, best first, seed
and generator, then the key metrics as the first columns. (MLflow's UI does not carry which
parent rows are open in a shared view; sorted by start time it nested a sweep's jobs under its
parent's one collapsed row.) MLflow 3.17's
UI opens in its GenAI view (traces, judges) whatever the kind tag says, and shows no metric
column until one is chosen, so each run logs where to look: `browse_hint`, the address of
`ui_path(experiment_id)`, which selects the classic view and colmo's columns (the UI's
"Override saved view" keeps them).

Metrics are logged rounded to `METRIC_DIGITS` significant digits (integer digits kept, so
counts stay exact): MLflow's run list and run page show a metric as stored (0.833333333), and
no setting of MLflow's changes that. The exact values are in the run's `summary.json` and
`programs.json`. The view's metrics are logged first: MLflow's compare page plots the first
metric a run has (the chart view, when no primary metric is set, too).

Concurrency. MLflow's SQLAlchemy store creates and migrates its schema on first use without a
lock, so sweep jobs starting together collide ("duplicate column name: step", "table already
exists"). Opening the store and getting or creating the experiment therefore happen under an
exclusive `fcntl.flock` on `<db>.lock`. Later writes are short transactions; a "database is
locked" that outlasts SQLite's busy timeout is retried.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import math
import re
import time
from pathlib import Path
from typing import Any, Callable, Iterator, Optional, Sequence, TypeVar

from mlflow import MlflowClient
from mlflow.entities import Metric, Param, RunStatus
from mlflow.exceptions import MlflowException
from mlflow.utils.mlflow_tags import MLFLOW_EXPERIMENT_PRIMARY_METRIC_GREATER_IS_BETTER, MLFLOW_EXPERIMENT_PRIMARY_METRIC_NAME
from mlflow.utils.validation import MAX_METRICS_PER_BATCH, MAX_PARAMS_TAGS_PER_BATCH

DATABASE_FILE = "mlruns.db"
ARTIFACTS_DIR = "mlartifacts"
EXPERIMENT_KIND_TAG = "mlflow.experimentKind"
CLASSIC_ML = "custom_model_development"  # MLflow 3's value for a classic (not GenAI) experiment
PRIMARY_METRIC = "best_score"
# A view of the run list that MLflow's UI opens from `?viewStateShareKey=colmo`: the runs grouped
# by GFO method (each group's row the average over its runs, every group open: a sweep's jobs
# are rows of their variant, where nesting under the sweep's parent run hid them in a collapsed
# row; parents fall into MLflow's "Additional runs"), best first, and the columns a person
# compares searches by in this order (the UI shows no metric column unless chosen): seed and
# generator, then the scores, samples and seconds; the rest of the view's metrics to the right.
VIEW_KEY = "colmo"
VIEW_TAG = f"mlflow.sharedViewState.{VIEW_KEY}"
VIEW_PARAMS = ("seed", "llm.name")
VIEW_METRICS = (
    PRIMARY_METRIC, "best_heldout_score", "samples", "seconds", "worker_seconds", "load", "steps_per_worker_second", "runs", "programs_evaluated",
    "valid_program_rate", "evaluations", "steps",
)
VIEW_GROUP = "gfo.method"


def view_state(groups: Sequence[str]) -> str:
    """The view's JSON, with the group of each of `groups` (values of `VIEW_GROUP`) open."""
    columns = [f"params.`{p}`" for p in VIEW_PARAMS] + [f"metrics.`{m}`" for m in VIEW_METRICS]
    return json.dumps({
        "selectedColumns": columns, "columnOrder": columns, "orderByKey": f"metrics.`{PRIMARY_METRIC}`", "orderByAsc": False,
        "groupBy": {"aggregateFunction": "average", "groupByKeys": [{"mode": "param", "groupByData": VIEW_GROUP}]},
        "groupsExpanded": {f"param.{VIEW_GROUP}.{group}": True for group in groups},
    })
METRIC_DIGITS = 4
MLFLOW_UI_PORT = 5000  # `mlflow ui`'s default, named in the command colmo logs
_LOCK_RETRIES = 6
RUNNING, FINISHED, FAILED, KILLED = (RunStatus.to_string(s) for s in (RunStatus.RUNNING, RunStatus.FINISHED, RunStatus.FAILED, RunStatus.KILLED))

T = TypeVar("T")



def default_tracking_uri(launch_dir: Path) -> str:
    return f"sqlite:///{(launch_dir / DATABASE_FILE).resolve()}"


def sqlite_path(uri: str) -> Optional[Path]:
    """The database file of a `sqlite:///` URI (relative paths are relative to the cwd)."""
    if not uri.startswith("sqlite:///"):
        return None
    return Path(uri.removeprefix("sqlite:///")).resolve()


@contextlib.contextmanager
def file_lock(path: Path) -> Iterator[None]:
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
    with file_lock(Path(f"{path}.lock")):
        yield


def connect(uri: str) -> MlflowClient:
    """A client on `uri`, whose schema is created or migrated by one process at a time."""
    with _store_lock(uri):
        return MlflowClient(uri)  # builds (and caches per process) the store: schema set-up happens here


def open_experiment(uri: str, name: str) -> tuple[MlflowClient, str]:
    """A client on `uri` and the id of experiment `name`, created if missing (a classic ML
    experiment with `best_score` as its primary metric and colmo's view of its run list), safely
    when several processes start at once. An experiment made before gets the tags it lacks, and
    colmo's view as this colmo lays it out."""
    from colmo.optimize.methods import METHODS  # every method registered by now: each one's group opens

    tags = {
        EXPERIMENT_KIND_TAG: CLASSIC_ML, VIEW_TAG: view_state(list(METHODS)),
        MLFLOW_EXPERIMENT_PRIMARY_METRIC_NAME: PRIMARY_METRIC, MLFLOW_EXPERIMENT_PRIMARY_METRIC_GREATER_IS_BETTER: "True",
    }
    with _store_lock(uri):
        client = MlflowClient(uri)
        experiment = client.get_experiment_by_name(name)
        if experiment is not None:
            for key, value in tags.items():
                # made by an older colmo, or by hand: a person's own settings stay, colmo's view is colmo's
                if key not in experiment.tags or (key == VIEW_TAG and experiment.tags[key] != value):
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


def browse_hint(uri: str, experiment_id: str) -> str:
    """How to see an experiment's runs in MLflow's UI: a tracking server's own address (the
    tracking URI, `http://host:8080/...`), else the `mlflow ui` command that serves the store
    and the address it serves it at."""
    if uri.startswith(("http://", "https://")):
        return uri.rstrip("/") + ui_path(experiment_id)
    return f"mlflow ui --backend-store-uri {uri} --port {MLFLOW_UI_PORT}, then http://127.0.0.1:{MLFLOW_UI_PORT}{ui_path(experiment_id)}"


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



def rounded(value: float) -> float:
    """`value` to `METRIC_DIGITS` significant digits, never fewer than its integer digits:
    601.7312 -> 601.7, 0.8333333 -> 0.8333, 0.0004321 stays, 15000.0 stays."""
    if value == 0:
        return 0.0
    return round(value, max(0, METRIC_DIGITS - 1 - math.floor(math.log10(abs(value)))))


def log_metrics(client: MlflowClient, run_id: str, values: dict[str, Optional[float]], step: int) -> None:
    """The finite values of `values` at `step` (a failed score is None or -inf: not a point),
    `rounded`, the view's metrics first (module docstring)."""
    stamp = int(time.time() * 1000)
    first = lambda key: VIEW_METRICS.index(key) if key in VIEW_METRICS else len(VIEW_METRICS)  # noqa: E731
    metrics = [Metric(k, rounded(float(values[k])), stamp, step) for k in sorted(values, key=first) if values[k] is not None and math.isfinite(values[k])]
    for start in range(0, len(metrics), MAX_METRICS_PER_BATCH):
        retry_locked(client.log_batch, run_id, metrics=metrics[start : start + MAX_METRICS_PER_BATCH])


def log_params(client: MlflowClient, run_id: str, params: dict[str, str]) -> None:
    items = [Param(key, value) for key, value in params.items()]
    for start in range(0, len(items), MAX_PARAMS_TAGS_PER_BATCH):
        retry_locked(client.log_batch, run_id, params=items[start : start + MAX_PARAMS_TAGS_PER_BATCH])
