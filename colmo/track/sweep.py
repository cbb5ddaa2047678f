"""MLflow parent runs of Hydra sweeps.

Every job of a `-m` sweep is a child run (tag `mlflow.parentRunId`) of one parent run
per sweep and experiment, named `<experiment>-sweep-<HHMMSS>`. Whichever job comes first creates
the parent; the others find it by its tag `colmo.sweep` (a hash of the absolute
`hydra.sweep.dir`), all under an exclusive file lock in the sweep directory, so this holds for
any launcher (basic, joblib, submitit) and any tracking store. The parent holds the sweep's
overrides (from Hydra's `multirun.yaml`) and, after each job, the best `best_score` and
`best_heldout_score` over its children and their count (`runs`); its status is RUNNING while a
child runs, else FAILED or KILLED if a child did, else FINISHED (between two jobs of the basic
launcher it is briefly FINISHED). At the sweep's end it receives the comparison the sweep
printed (`record_comparison`): `comparison.txt`, each setting's mean and difference with its
interval as the tag `colmo.comparison`, and colmo-report's report of the sweep (`report/`:
`report.md` with Table I and the comparison tables, the best-so-far figures).
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Optional

from mlflow import MlflowClient
from mlflow.utils.mlflow_tags import MLFLOW_PARENT_RUN_ID
from mlflow.utils.validation import MAX_TAG_VAL_LENGTH

from colmo.track.backend import FAILED, FINISHED, KILLED, RUNNING, connect, default_tracking_uri, file_lock, log_metrics, retry_locked

SWEEP_TAG = "colmo.sweep"
SWEEP_LOCK = ".mlflow_parent.lock"


def sweep_id(sweep_dir: Path) -> str:
    """The id of the sweep writing into `sweep_dir` (absolute): the MLflow tag `colmo.sweep` of
    its parent run, and a name `colmo-report sweep=` accepts."""
    return hashlib.sha1(str(sweep_dir).encode()).hexdigest()[:16]


def sweep_parent(client: MlflowClient, experiment_id: str, sweep_dir: Path, name: str, tags: dict[str, str]) -> str:
    """The id of the parent run of the sweep writing into `sweep_dir`, in `experiment_id`: made
    by the first job that asks, found by the others (under a lock in the sweep directory)."""
    tag = sweep_id(sweep_dir)
    with file_lock(sweep_dir / SWEEP_LOCK):
        found = retry_locked(client.search_runs, [experiment_id], f"tags.`{SWEEP_TAG}` = '{tag}'", max_results=1)
        if found:
            parent = found[0].info
            if parent.status != RUNNING:  # a job of the basic launcher after the one before ended
                retry_locked(client.update_run, parent.run_id, status=RUNNING)
            return parent.run_id
        tags = {**tags, SWEEP_TAG: tag, "colmo.sweep_dir": str(sweep_dir)}
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
    with file_lock(sweep_dir / SWEEP_LOCK):
        children = retry_locked(client.search_runs, [experiment_id], f"tags.`{MLFLOW_PARENT_RUN_ID}` = '{parent_id}'", max_results=10000)
        statuses = [child.info.status for child in children]
        best = lambda key: max((c.data.metrics[key] for c in children if key in c.data.metrics), default=None)  # noqa: E731
        values = {"best_score": best("best_score"), "best_heldout_score": best("best_heldout_score"), "runs": len(children)}
        log_metrics(client, parent_id, values, len(children) - statuses.count(RUNNING))
        if RUNNING in statuses:
            return
        status = FAILED if FAILED in statuses else KILLED if KILLED in statuses else FINISHED
        retry_locked(client.set_terminated, parent_id, status)


COMPARISON_FILE = "comparison.txt"
COMPARISON_TAG = "colmo.comparison"
REPORT_ARTIFACTS = "report"


def record_comparison(
    uri: Optional[str], launch_dir: Path, experiments: list[str], sweep_dir: Path, lines: list[str], report: Optional[Path] = None,
) -> None:
    """The end-of-sweep comparison (`colmo.sweep_comparison.comparison_lines`) in the sweep's
    parent run in each of `experiments`: the whole text as `comparison.txt`, its lines of
    settings compared (each one's mean over seeds, its difference to the first with the interval)
    as the tag `colmo.comparison`, which the run list can show, so that one page tells the winner,
    and the directory `report` (colmo-report's Table I, comparison tables and figures) as the
    artifacts `report/`."""
    client = connect(uri or default_tracking_uri(launch_dir))
    ids = [experiment.experiment_id for name in experiments if (experiment := client.get_experiment_by_name(name)) is not None]
    parents = retry_locked(client.search_runs, ids, f"tags.`{SWEEP_TAG}` = '{sweep_id(sweep_dir)}'") if ids else []
    start = next((i for i, line in enumerate(lines) if line.strip().startswith("best score by setting")), None)
    settings = "\n".join(line.strip() for line in lines[start:] if not line.startswith("report:")) if start is not None else ""
    for parent in parents:
        client.log_text(parent.info.run_id, "\n".join(lines) + "\n", COMPARISON_FILE)
        if settings:
            retry_locked(client.set_tag, parent.info.run_id, COMPARISON_TAG, settings[:MAX_TAG_VAL_LENGTH])
        if report is not None:
            client.log_artifacts(parent.info.run_id, str(report), REPORT_ARTIFACTS)
