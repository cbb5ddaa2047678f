"""`executor=local`: sandboxed worker processes on this machine, one per core by default."""

from __future__ import annotations

from typing import Optional

from colmo.config import ExecutorConfig
from colmo.evaluation import EvalRequest, Evaluation
from colmo.executor.dispatch import EXECUTORS, Dispatcher
from colmo.sandbox.process import SandboxProcess


@EXECUTORS.register("local")
class LocalExecutor(Dispatcher):
    """`workers` sandbox worker processes (`colmo.sandbox.worker`), each started lazily by the
    thread that uses it (the worker's parent-death signal follows that thread, which lives as
    long as the executor) and restarted after a loss."""

    def __init__(self, workers: int, memory_mb: int = 4096, max_retries: int = 2):
        super().__init__(workers, max_retries)
        self.memory_mb = memory_mb
        self._processes: list[Optional[SandboxProcess]] = [None] * workers
        self._start_dispatching()

    @classmethod
    def from_config(cls, cfg: ExecutorConfig, max_workers: Optional[int] = None) -> "LocalExecutor":
        return cls(min(cfg.n_workers, max_workers) if max_workers else cfg.n_workers, cfg.memory_mb, cfg.max_retries)

    def worker_pids(self) -> list[int]:
        """Process ids of the running worker processes."""
        return [process.pid for process in self._processes if process is not None and process.alive()]

    def _open(self, slot: int) -> None:
        self._discard(slot)  # a worker that died by itself
        self._processes[slot] = SandboxProcess(self.memory_mb)

    def _run(self, slot: int, request: EvalRequest) -> Evaluation:
        return self._processes[slot].evaluate(request)

    def _discard(self, slot: int) -> None:
        process, self._processes[slot] = self._processes[slot], None
        if process is not None:
            process.kill()

    def _is_open(self, slot: int) -> bool:
        process = self._processes[slot]
        return process is not None and process.alive()

    def __enter__(self) -> "LocalExecutor":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
