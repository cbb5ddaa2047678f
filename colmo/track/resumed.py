"""A resumed search's MLflow run: the run the search's earlier processes logged into, found by
its run directory (the tag `colmo.run_dir`), and what it already holds read back (the programs
table and the best-so-far curves), so that the resumed process goes on in the same run instead
of starting a second one with half the history."""

from __future__ import annotations

import json
import math
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional

from mlflow import MlflowClient
from mlflow.entities import Run

from colmo.track.backend import retry_locked
from colmo.track.programs import PROGRAMS_TABLE

RUN_DIR_TAG = "colmo.run_dir"
_ISLAND_METRIC = "best_score_island_"


def earlier_run(client: MlflowClient, experiment_id: str, run_dir: str) -> Optional[Run]:
    """The newest search run of `experiment_id` that wrote into `run_dir`; None if there is none."""
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
