"""Run trackers, the registry `tracker.name` picks from: `none` (the run directory is the whole
record) and `mlflow` (`colmo.track`). A tracker follows a search as its observers and records a
finished `colmo-optimize` job; `make_tracker(cfg.tracker)` builds the one the config names.

The registry lives here, not in `colmo.track`, because names are checked before Hydra starts
(`colmo.config`) and MLflow takes seconds to import: `mlflow` imports it only once a run starts.
"""

from __future__ import annotations

import abc
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, Optional, Sequence

from colmo.config import MlflowConfig, TrackerConfig
from colmo.registry import Registry

if TYPE_CHECKING:
    from colmo.config import OptimizeConfig, SearchConfig
    from colmo.record import SearchObserver


class Tracker(abc.ABC):
    """Where a run is recorded besides its run directory. Trackers register as `tracker=<name>`
    (`@TRACKERS.register`) and are built as `cls()`; call them inside the Hydra app."""

    options: ClassVar[type[TrackerConfig]] = TrackerConfig  # the schema of its `tracker` option

    @abc.abstractmethod
    def search_observers(self, cfg: SearchConfig, run_dir: Path) -> tuple[SearchObserver, ...]:
        """The observers that record the search writing into `run_dir`."""

    @abc.abstractmethod
    def record_optimize(self, cfg: OptimizeConfig, result: dict[str, Any], files: Sequence[Path], started: float) -> Optional[str]:
        """Record a finished `colmo-optimize` job (its `result.json` fields, the `files` it
        wrote, its start in epoch seconds); a line saying where it went, if anywhere."""


TRACKERS: Registry[type[Tracker]] = Registry("tracker.name")


@TRACKERS.register("none")
class NoTracker(Tracker):
    """No tracking: the run directory (programs.db, summary.json, best_policy.py) is the record."""

    def search_observers(self, cfg: SearchConfig, run_dir: Path) -> tuple[SearchObserver, ...]:
        return ()

    def record_optimize(self, cfg: OptimizeConfig, result: dict[str, Any], files: Sequence[Path], started: float) -> Optional[str]:
        return None


@TRACKERS.register("mlflow")
class MlflowTracking(Tracker):
    """One MLflow run per search or tuning job, a parent run per sweep (`colmo.track`)."""

    options = MlflowConfig

    def search_observers(self, cfg: SearchConfig, run_dir: Path) -> tuple[SearchObserver, ...]:
        from colmo.track import start_search_run

        return (start_search_run(cfg, run_dir),)

    def record_optimize(self, cfg: OptimizeConfig, result: dict[str, Any], files: Sequence[Path], started: float) -> Optional[str]:
        from colmo.track import track_optimize

        run_id = track_optimize(cfg, result, files, started)
        return f"MLflow run {run_id} (experiment {cfg.tracker.experiment or cfg.task.name})"


def make_tracker(cfg: TrackerConfig) -> Tracker:
    """The tracker `cfg.name` names."""
    return TRACKERS.chosen(cfg.name)()
