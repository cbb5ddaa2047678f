"""Executors: where candidate evaluations run, chosen by the `executor` config group.

Both share one `Dispatcher` (`dispatch`): a job queue served by a thread per worker slot, with
retries when a worker is lost. `local` slots are sandbox worker processes on this machine
(`colmo.sandbox`); `ray` slots are Ray actors, each owning one such process on its node. Every
executor takes plain-data `EvalRequest`s and returns `Evaluation`s in request order;
evaluation is deterministic, so results do not depend on the executor.
"""

from __future__ import annotations

from typing import Optional

from colmo.config import ExecutorConfig
from colmo.evaluation import Executor
from colmo.executor.local import LocalExecutor

__all__ = ["LocalExecutor", "make_executor"]


def make_executor(cfg: ExecutorConfig, max_workers: Optional[int] = None) -> Executor:
    """The executor `cfg.name` names, with at most `max_workers` workers when given."""
    if cfg.name == "ray":
        from colmo.executor.ray import RayExecutor  # imports Ray only when asked for

        return RayExecutor(cfg, max_workers)
    workers = min(cfg.n_workers, max_workers) if max_workers else cfg.n_workers
    return LocalExecutor(workers, cfg.memory_mb, cfg.max_retries)
