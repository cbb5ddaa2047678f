"""A resumed search's MLflow run: the run the search's earlier processes logged into, and what it
already holds read back (the programs table and the best-so-far curves), so that the resumed
process goes on in the same run instead of starting a second one with half the history. A
search's run directory names its run (`mlflow_run.json`: the tracking URI and the run's id), so
a search resumed from another directory goes on in the store it began in; a run directory made
before that file is found by the tag `colmo.run_dir` in the store the resume uses."""

from __future__ import annotations

import json
import math
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional

from mlflow import MlflowClient
from mlflow.entities import Run
from mlflow.exceptions import MlflowException

from colmo.track.backend import retry_locked
from colmo.track.programs import PROGRAMS_TABLE

RUN_DIR_TAG = "colmo.run_dir"
RUN_FILE = "mlflow_run.json"
_ISLAND_METRIC = "best_score_island_"


def remember(run_dir: Path, tracking_uri: str, run_id: str) -> None:
    """Write into a search's run directory where its MLflow run is."""
    (run_dir / RUN_FILE).write_text(json.dumps({"tracking_uri": tracking_uri, "run_id": run_id}) + "\n")


def remembered(run_dir: Path) -> dict[str, str]:
    """Where the MLflow run of the search in `run_dir` is (`tracking_uri`, `run_id`); empty if it
    does not say (made before the file, or by `tracker=none`)."""
    try:
        found = json.loads((run_dir / RUN_FILE).read_text())
    except (OSError, ValueError):
        return {}
    return found if isinstance(found, dict) and {"tracking_uri", "run_id"} <= found.keys() else {}


def earlier_run(client: MlflowClient, experiment_id: str, run_dir: str, run_id: Optional[str] = None) -> Optional[Run]:
    """The search run of `experiment_id` that wrote into `run_dir`: `run_id` if the store holds
    it, else the newest run tagged with that directory; None if there is none."""
    if run_id is not None:
        try:
            run = client.get_run(run_id)
        except MlflowException:  # another store, or the run was deleted
            run = None
        if run is not None and run.info.experiment_id == experiment_id and run.info.lifecycle_stage == "active":
            return run
    quoted = run_dir.replace("\\", "\\\\").replace("'", "\\'")
    found = retry_locked(
        client.search_runs, [experiment_id], f"tags.`{RUN_DIR_TAG}` = '{quoted}' and tags.`colmo.command` = 'search'",
        max_results=1, order_by=["attributes.start_time DESC"],
    )
    return found[0] if found else None


@dataclass
class History:
    """What an MLflow search run holds of its batches: the programs table's rows, and per batch
    the samples so far (the step), the search's seconds, the best score and each island's."""

    rows: list[dict[str, Any]] = field(default_factory=list)
    steps: list[int] = field(default_factory=list)
    seconds: list[float] = field(default_factory=list)
    best: list[float] = field(default_factory=list)
    per_island: list[list[float]] = field(default_factory=list)


def history(client: MlflowClient, run_id: str) -> History:
    """The rows and curves the run holds (empty where it holds none: a run stopped before its first batch)."""
    run = retry_locked(client.get_run, run_id)

    def by_step(key: str) -> dict[int, float]:
        return {metric.step: metric.value for metric in retry_locked(client.get_metric_history, run.info.run_id, key)}

    best = by_step("best_score")
    seconds = by_step("seconds")
    islands = sorted((key for key in run.data.metrics if key.startswith(_ISLAND_METRIC)), key=lambda key: int(key[len(_ISLAND_METRIC):]))
    per_island = [by_step(key) for key in islands]
    steps = sorted(best)
    return History(
        rows=_rows(client, run_id),
        steps=steps,
        seconds=[seconds.get(step, math.nan) for step in steps],
        best=[best[step] for step in steps],
        per_island=[[island.get(step, math.nan) for island in per_island] for step in steps],
    )


def _rows(client: MlflowClient, run_id: str) -> list[dict[str, Any]]:
    """The rows of the run's programs table (`programs.json`, written in pandas' split layout)."""
    if not any(artifact.path == PROGRAMS_TABLE for artifact in client.list_artifacts(run_id)):
        return []
    with tempfile.TemporaryDirectory() as scratch:
        table = json.loads(Path(client.download_artifacts(run_id, PROGRAMS_TABLE, scratch)).read_text())
    return [dict(zip(table["columns"], values)) for values in table["data"]]
