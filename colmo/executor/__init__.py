"""Executors: where candidate evaluations run, chosen by the `executor` config group.

Both share one `Dispatcher` (`dispatch`): a job queue served by a thread per worker slot, with
retries when a worker is lost. `local` slots are sandbox worker processes on this machine
(`colmo.sandbox`); `ray` slots are Ray actors, each owning one such process on its node. Every
executor registers in `EXECUTORS` where it is defined, takes plain-data `EvalRequest`s and
returns `Evaluation`s in request order; evaluation is deterministic, so results do not depend
on the executor.
"""

from __future__ import annotations

from typing import Optional

from colmo.config import ExecutorConfig
from colmo.evaluation import Executor
from colmo.executor import ray  # noqa: F401 - it registers; it imports Ray only when one starts
from colmo.executor.dispatch import EXECUTORS
from colmo.executor.local import LocalExecutor

__all__ = ["EXECUTORS", "LocalExecutor", "make_executor"]


def make_executor(cfg: ExecutorConfig, max_workers: Optional[int] = None) -> Executor:
    """The executor `cfg.name` names, with at most `max_workers` workers when given."""
    return EXECUTORS.chosen(cfg.name).from_config(cfg, max_workers)
