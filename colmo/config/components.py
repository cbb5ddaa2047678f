"""The schemas of the config groups that pick a component by name, one schema per kind of option:
the gradient-free optimizer (`gfo`, `gfo=bo`), the executor (`executor`, `executor=ray`) and
the run tracker (`tracker`, `tracker=mlflow`)."""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Optional

from colmo.config.fields import above, at_least, check_component, component, option, require


@dataclass
class GFOConfig:
    """The gradient-free optimizer that tunes each program's constants."""

    method: str = component("oneplusone", "the method the gfo option runs", "colmo.optimize.methods:METHODS")
    budget: int = option(100, "evaluations per program, its own constants included")
    workers: int = option(1, "candidates evaluated at a time, where the method allows it")
    relative_step: float = option(0.3, "initial step of each constant, relative to its magnitude")
    min_step: float = option(0.1, "floor of the initial step, for constants near 0")
    racing: Optional[bool] = option(
        None, "stop a candidate's episodes once a paired test on the same seeds says it very likely cannot beat the best "
        "(colmo.racing.Race); null: on for the comparison-based methods (the ES, CMA-ES and DE)",
    )
    racing_min_episodes: int = option(2, "episodes a candidate always runs before racing may stop it (at least 2: the test needs a spread)")
    racing_margin: float = option(0.002, "racing also stops a candidate unlikely to beat the best by more than this fraction of its return")

    def __post_init__(self) -> None:
        check_component(self, "method")
        at_least(self, "gfo", budget=1, workers=1, racing_min_episodes=2, racing_margin=0)
        above(self, "gfo", relative_step=0, min_step=0)


@dataclass
class BOConfig(GFOConfig):
    """Optuna's Bayesian optimization."""

    method: str = "bo"
    sampler: str = option("tpe", "tpe, or gp (needs PyTorch)")
    search_range: float = option(3.0, "each constant is searched within this many initial steps of its value")

    def __post_init__(self) -> None:
        super().__post_init__()
        require(self.sampler in ("tpe", "gp"), f"gfo.sampler must be tpe or gp, got {self.sampler!r}")
        above(self, "gfo", search_range=0)


@dataclass
class ExecutorConfig:
    """Where evaluations run: sandboxed worker processes on this machine."""

    name: str = component("local", "the executor the executor option runs", "colmo.executor:EXECUTORS")
    workers: int = option(0, "worker processes; 0: one per core this process may use")
    timeout_s: Optional[float] = option(None, "wall-clock limit per evaluation; null: derived from the task (30 x the starter's time, at least 10 s)")
    memory_mb: int = option(4096, "address-space limit of each worker and of each program's process")
    max_retries: int = option(2, "an evaluation whose worker dies is retried this often, then recorded as failed")

    def __post_init__(self) -> None:
        check_component(self, "name")
        at_least(self, "executor", max_retries=0, memory_mb=256)
        require(self.workers >= 0, f"executor.workers must be >= 0 (0 = all cores), got {self.workers}")
        require(self.timeout_s is None or self.timeout_s > 0, f"executor.timeout_s must be > 0, got {self.timeout_s}")

    @property
    def n_workers(self) -> int:
        # The cores this process may use (a SLURM allocation), not all the node's cores.
        return self.workers or len(os.sched_getaffinity(0)) or 1


@dataclass
class RayExecutorConfig(ExecutorConfig):
    """Evaluations on a Ray cluster: one actor per CPU, each with one sandboxed worker."""

    name: str = "ray"
    address: Optional[str] = option(None, "null: a private local Ray instance; auto: the cluster this machine joined; ray://host:10001: Ray Client")



@dataclass
class TrackerConfig:
    """Run tracking (`colmo.trackers`): `tracker=none` keeps only the run directory."""

    name: str = component("none", "the tracker the tracker option runs", "colmo.trackers:TRACKERS")

    def __post_init__(self) -> None:
        check_component(self, "name")


@dataclass
class MlflowConfig(TrackerConfig):
    """MLflow tracking: one run per search, a parent run per sweep."""

    name: str = "mlflow"
    tracking_uri: Optional[str] = option(None, "null: sqlite:///mlruns.db in the launch directory; or http://host:5000, postgresql://...")
    experiment: Optional[str] = option(None, "null: the task name")
    run_name: Optional[str] = option(None, "null: <task>-<gfo>-<llm>-s<seed>-<HHMMSS>, and -j<job number> in a sweep")

