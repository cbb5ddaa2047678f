"""Tracking runs in MLflow: one MLflow run per search or tuning (per Hydra job), a parent run per
`-m` sweep, with every program and score.

- `backend`: where runs go, opening the store safely from jobs that start together, experiments
  and colmo's view of their run list in the UI, metrics as logged (rounded);
- `sweep`: the parent run of a sweep, and its children's best scores;
- `programs`: every sample as a row of the table `programs.json` and of the page `programs.html`;
- `runs`: a job's run, what a search's run holds (`MlflowTracker`, the search's observer), and
  a `colmo-optimize` job's run;
- `resumed`: the run a resumed search goes on in, and what it holds read back.
"""

from colmo.track.backend import (
    CLASSIC_ML,
    EXPERIMENT_KIND_TAG,
    VIEW_TAG,
    browse_hint,
    connect,
    default_tracking_uri,
    open_experiment,
    retry_locked,
    sqlite_path,
)
from colmo.track.programs import PROGRAM_COLUMNS, PROGRAMS_PAGE, PROGRAMS_TABLE
from colmo.track.runs import (
    STOP_REASON_TAG,
    MlflowTracker,
    TrackedRun,
    draw_best_so_far,
    flatten,
    start_run,
    start_search_run,
    track_optimize,
)
from colmo.track.sweep import SWEEP_TAG

__all__ = [
    "CLASSIC_ML", "EXPERIMENT_KIND_TAG", "PROGRAM_COLUMNS", "PROGRAMS_PAGE", "PROGRAMS_TABLE", "STOP_REASON_TAG", "SWEEP_TAG",
    "VIEW_TAG", "MlflowTracker", "TrackedRun", "browse_hint", "connect", "default_tracking_uri", "draw_best_so_far", "flatten",
    "open_experiment", "retry_locked", "sqlite_path", "start_run", "start_search_run", "track_optimize",
]
