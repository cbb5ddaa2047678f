"""Executors: where candidate evaluations run, chosen by the `executor` config group.

`local` is a pool of sandboxed worker processes on this machine (`colmo.sandbox.WorkerPool`).
Every executor takes plain-data `EvalRequest`s and returns `Evaluation`s in request order.
"""

from __future__ import annotations

from typing import Optional

from colmo.config import ConfigError, ExecutorConfig
from colmo.sandbox import Executor, WorkerPool


def make_executor(cfg: ExecutorConfig, max_workers: Optional[int] = None) -> Executor:
    """The executor `cfg` names, with at most `max_workers` workers when given."""
    workers = min(cfg.n_workers, max_workers) if max_workers else cfg.n_workers
    if cfg.name == "local":
        return WorkerPool(workers, cfg.timeout_s, cfg.memory_mb)
    raise ConfigError(f"executor={cfg.name} is not available in this build")
