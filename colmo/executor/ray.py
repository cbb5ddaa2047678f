"""`executor=ray`: evaluations spread over a Ray cluster, one actor per CPU.

Each actor owns a one-worker `LocalExecutor`, so the sandbox rules (static check, OS
confinement, limits, per-evaluation processes, clean environment) hold on every node exactly
as locally, and each sandbox keeps its built simulators between requests. The shared
`Dispatcher` gives every actor a thread here that takes the next request as soon as its actor
is free; a request whose actor dies (its process killed, its node lost) is retried on a
replacement actor `executor.max_retries` times. Only plain data crosses the network.
"""

from __future__ import annotations

import dataclasses
import importlib.resources
import logging
import os
from pathlib import Path
from typing import Any, Optional

from colmo.config import ExecutorConfig, RayExecutorConfig
from colmo.errors import ConfigError, one_line
from colmo.evaluation import EvalRequest, Evaluation, WorkerLost
from colmo.executor.dispatch import EXECUTORS, Dispatcher
from colmo.executor.local import LocalExecutor
from colmo.registry import Library

log = logging.getLogger("colmo.executor")

_STARTUP_NOTICE_S = 60.0  # say why a start takes this long (a cluster short of CPUs)


class _EvaluationActor:
    """Runs in a Ray worker process (made a Ray actor class by `RayExecutor`)."""

    def __init__(self, memory_mb: int, max_retries: int):
        self.executor = LocalExecutor(1, memory_mb, max_retries)

    def pid(self) -> int:
        """The actor's process id; answering it also proves the actor is up."""
        return os.getpid()

    def evaluate(self, request: EvalRequest) -> Evaluation:
        return self.executor.evaluate([request])[0]

    def close(self) -> None:
        self.executor.close()


@EXECUTORS.register("ray")
class RayExecutor(Dispatcher):
    """Evaluations on the Ray cluster at `cfg.address`, one actor per CPU (or `cfg.workers`);
    in a process already connected to Ray, on that cluster."""

    options = RayExecutorConfig
    library = Library("ray", "Ray", "colmo[ray]")

    def __init__(self, cfg: ExecutorConfig, max_workers: Optional[int] = None):
        ray = self.library.load("executor=ray")
        self._ray = ray
        self._owns_ray = not ray.is_initialized()
        if self._owns_ray:
            _init_ray(ray, cfg)
        workers = cfg.workers or int(ray.cluster_resources().get("CPU", 0))
        if workers < 1:
            self._shutdown_ray()
            raise ConfigError("executor=ray: the Ray cluster has no CPUs yet; set executor.workers to the number of actors to start")
        super().__init__(min(workers, max_workers) if max_workers else workers, cfg.max_retries)
        self._lost_errors = (ray.exceptions.RayActorError, ray.exceptions.WorkerCrashedError, ray.exceptions.NodeDiedError)
        # max_restarts=0: a dead actor is replaced here, so that the retry count is per request.
        actor_class = ray.remote(num_cpus=1, max_restarts=0)(_EvaluationActor)
        self._new_actor = lambda: actor_class.remote(cfg.memory_mb, cfg.max_retries)
        self._actors: list[Any] = [self._new_actor() for _ in range(self.n_workers)]
        self._pids: list[Optional[int]] = [None] * self.n_workers
        try:
            # Wait for every actor now, so that a cluster where colmo cannot run fails at once.
            started = [actor.pid.remote() for actor in self._actors]
            if ray.wait(started, num_returns=len(started), timeout=_STARTUP_NOTICE_S)[1]:
                log.warning("waiting for %d Ray actors to start: the cluster has %s CPUs free", self.n_workers, ray.available_resources().get("CPU", 0))
            self._pids[:] = ray.get(started)
        except ray.exceptions.RayError as error:
            self._stop_actors(graceful=False)
            self._shutdown_ray()
            raise ConfigError(f"executor=ray: the evaluation actors did not start: {one_line(error)}") from None
        self._start_dispatching()

    @classmethod
    def from_config(cls, cfg: ExecutorConfig, max_workers: Optional[int] = None) -> "RayExecutor":
        return cls(cfg, max_workers)

    def worker_pids(self) -> list[int]:
        """Process ids of the live actors (on their nodes)."""
        return [pid for pid in self._pids if pid is not None]

    def _open(self, slot: int) -> None:
        """A replacement actor, waited for until it runs. While it waits for a free CPU (a node
        was lost), this slot holds no request: the other actors take the work."""
        with self._lock:
            if self.closed and self._cancelled:
                raise RuntimeError("the executor is closing")
            actor = self._actors[slot] = self._new_actor()
        try:
            self._pids[slot] = self._ray.get(actor.pid.remote())
        except self._ray.exceptions.RayError as error:
            self._actors[slot] = None
            raise RuntimeError(f"a replacement Ray actor did not start: {one_line(error)}") from None

    def _run(self, slot: int, request: EvalRequest) -> Evaluation:
        try:
            return self._ray.get(self._actors[slot].evaluate.remote(_portable(request)))
        except self._lost_errors as error:
            raise WorkerLost(one_line(error).rstrip(".")) from None

    def _discard(self, slot: int) -> None:
        # Killed too, in case it is only unreachable: it would hold a CPU the replacement needs.
        actor, self._actors[slot], self._pids[slot] = self._actors[slot], None, None
        if actor is not None:
            self._ray.kill(actor, no_restart=True)

    def _is_open(self, slot: int) -> bool:
        return self._actors[slot] is not None

    def close(self, cancel: bool = False) -> None:
        """Stop the actors (see `Dispatcher.close`); then disconnect from Ray, and stop the Ray
        instance if this executor started it."""
        if not cancel:
            with self._lock:
                self.closed = True
            self._jobs.join()
            self._stop_actors(graceful=True)  # closing the pools first ends each sandbox cleanly
        super().close(cancel)
        self._shutdown_ray()

    def _stop_actors(self, graceful: bool) -> None:
        actors = [actor for actor in self._actors if actor is not None]
        if graceful and actors:
            # A dead actor's error is moot.
            self._ray.wait([actor.close.remote() for actor in actors], num_returns=len(actors), timeout=30)
        for slot in range(len(self._actors)):
            self._discard(slot)

    def _shutdown_ray(self) -> None:
        if self._owns_ray:
            self._ray.shutdown()


def _init_ray(ray, cfg: ExecutorConfig) -> None:
    """Connect to the cluster at `cfg.address`, or start a local instance when there is none."""
    quiet: dict[str, Any] = dict(logging_level=logging.ERROR, log_to_driver=False)
    if not cfg.address:
        # Ray runs workers at nice 15, below everything else here; a local instance is this
        # machine's evaluator, as the local pool is, so it gets the same priority (Ray's job
        # manager does the same for job drivers).
        os.environ.setdefault("RAY_worker_niceness", "0")
        ray.init(address="local", num_cpus=cfg.n_workers, include_dashboard=False, **quiet)
        return
    try:
        ray.init(address=cfg.address, **quiet)
    except (ConnectionError, ValueError) as error:
        raise ConfigError(f"executor=ray: cannot reach Ray at executor.address={cfg.address}: {one_line(error)}") from None


_BUNDLED_SPECS = Path(str(importlib.resources.files("colmo.specs"))).resolve()


def _portable(request: EvalRequest) -> EvalRequest:
    """The request with a bundled spec named by file name rather than by this machine's path,
    so that a node with colmo installed elsewhere finds it; other spec files must be at the
    same path on every node (a shared file system)."""
    path = Path(request.spec)
    if path.parent == _BUNDLED_SPECS:
        return dataclasses.replace(request, spec=path.name)
    return request
