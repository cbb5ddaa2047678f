"""Executors: where candidate evaluations run, chosen by the `executor` config group.

`local` is a pool of sandboxed worker processes on this machine (`colmo.sandbox.WorkerPool`).
`ray` spreads the same work over a Ray cluster: one actor per CPU, each owning a one-process
`WorkerPool`, so the sandbox rules (static check, limits, timeout, clean environment) hold on
every node exactly as locally, and each sandbox keeps its built simulators and compiled
programs between requests. Every executor takes plain-data `EvalRequest`s and returns
`Evaluation`s in request order; evaluation is deterministic, so results do not depend on it.
"""

from __future__ import annotations

import concurrent.futures
import dataclasses
import importlib.resources
import logging
import os
import queue
import threading
import time
from pathlib import Path
from typing import Any, Optional, Sequence

from colmo.config import ConfigError, ExecutorConfig, one_line
from colmo.sandbox import EvalRequest, Executor, WorkerPool, drain
from colmo.task import Evaluation

log = logging.getLogger("colmo.executor")

_STARTUP_NOTICE_S = 60.0  # say why a start takes this long (a cluster short of CPUs)
_REPLACEMENT_BACKOFF_S = (1.0, 60.0)  # first and longest wait between failed actor starts


def make_executor(cfg: ExecutorConfig, max_workers: Optional[int] = None) -> Executor:
    """The executor `cfg` names, with at most `max_workers` workers when given."""
    if cfg.name == "local":
        workers = min(cfg.n_workers, max_workers) if max_workers else cfg.n_workers
        return WorkerPool(workers, cfg.timeout_s, cfg.memory_mb)
    if cfg.name == "ray":
        return RayExecutor(cfg, max_workers)
    raise ConfigError(f"executor={cfg.name} is not available in this build")


class _EvaluationActor:
    """Runs in a Ray worker process (made a Ray actor class by `RayExecutor`)."""

    def __init__(self, timeout_s: float, memory_mb: int):
        self.pool = WorkerPool(1, timeout_s, memory_mb)

    def pid(self) -> int:
        """The actor's process id; answering it also proves the actor is up."""
        return os.getpid()

    def evaluate(self, request: EvalRequest) -> tuple[Evaluation, float]:
        """The evaluation, and the seconds this actor spent on it."""
        start = time.perf_counter()
        evaluation = self.pool.evaluate([request])[0]
        return evaluation, time.perf_counter() - start

    def close(self) -> None:
        self.pool.close()


@dataclasses.dataclass
class _Job:
    request: EvalRequest
    future: concurrent.futures.Future
    retries: int = 0


class RayExecutor:
    """Evaluations on the Ray cluster at `cfg.address`, one actor per CPU (or `cfg.workers`);
    in a process already connected to Ray, on that cluster.

    Each actor has a dispatcher thread here that takes the next request from a shared queue
    as soon as its actor is free, so work goes to whichever actor is idle. A request whose
    actor dies (its process killed, its node lost) goes back to the queue, at most
    `cfg.max_retries` times, and the dispatcher starts a replacement actor before taking
    more work; after that the request is recorded as a failed `Evaluation`.
    """

    def __init__(self, cfg: ExecutorConfig, max_workers: Optional[int] = None):
        ray = _import_ray()
        self._ray = ray
        self._owns_ray = not ray.is_initialized()
        if self._owns_ray:
            _init_ray(ray, cfg)
        workers = cfg.workers or int(ray.cluster_resources().get("CPU", 0))
        if workers < 1:
            self._shutdown_ray()
            raise ConfigError("executor=ray: the Ray cluster has no CPUs yet; set executor.workers to the number of actors to start")
        self.n_workers = min(workers, max_workers) if max_workers else workers
        self.max_retries = cfg.max_retries
        self.closed = False
        self._cancelled = False
        self._stopping = False  # no more actors may start
        self._lock = threading.Lock()
        self._lost_errors = (ray.exceptions.RayActorError, ray.exceptions.WorkerCrashedError, ray.exceptions.NodeDiedError)
        # max_restarts=0: a dead actor is replaced here, so that the retry count is per request.
        actor_class = ray.remote(num_cpus=1, max_restarts=0)(_EvaluationActor)
        self._new_actor = lambda: actor_class.remote(cfg.timeout_s, cfg.memory_mb)
        self._actors: list[Any] = [self._new_actor() for _ in range(self.n_workers)]
        try:
            # Wait for every actor now, so that a cluster where colmo cannot run fails at once.
            started = [actor.pid.remote() for actor in self._actors]
            if ray.wait(started, num_returns=len(started), timeout=_STARTUP_NOTICE_S)[1]:
                log.warning("waiting for %d Ray actors to start: the cluster has %s CPUs free", self.n_workers, ray.available_resources().get("CPU", 0))
            self._pids: list[Optional[int]] = ray.get(started)
        except ray.exceptions.RayError as error:
            self._stop_actors(graceful=False)
            self._shutdown_ray()
            raise ConfigError(f"executor=ray: the evaluation actors did not start: {one_line(error)}") from None
        self._busy = [0.0] * self.n_workers
        self.jobs: queue.Queue[Optional[_Job]] = queue.Queue()
        self.threads = [
            threading.Thread(target=self._dispatch, args=(index,), daemon=True, name=f"colmo-ray-{index}")
            for index in range(self.n_workers)
        ]
        for thread in self.threads:
            thread.start()

    @property
    def busy_seconds(self) -> float:
        """Seconds the actors spent evaluating, summed over actors."""
        return sum(self._busy)

    def worker_pids(self) -> list[int]:
        """Process ids of the live actors (on their nodes)."""
        return [pid for pid in self._pids if pid is not None]

    def evaluate(self, requests: Sequence[EvalRequest]) -> list[Evaluation]:
        if self.closed:
            raise RuntimeError("the Ray executor is closed")
        jobs = [_Job(_portable(request), concurrent.futures.Future()) for request in requests]
        for job in jobs:
            self.jobs.put(job)
        return [job.future.result() for job in jobs]

    def _dispatch(self, index: int) -> None:
        while True:
            if self._actors[index] is None and not self._replace_actor(index):
                return
            job = self.jobs.get()
            if job is None:
                self.jobs.task_done()
                return
            self._run(index, job)
            self.jobs.task_done()

    def _run(self, index: int, job: _Job) -> None:
        if job.retries == 0 and not job.future.set_running_or_notify_cancel():
            return
        try:
            evaluation, seconds = self._ray.get(self._actors[index].evaluate.remote(job.request))
        except self._lost_errors as error:
            # Killed too, in case it is only unreachable: it would hold a CPU the replacement needs.
            self._ray.kill(self._actors[index], no_restart=True)
            self._actors[index], self._pids[index] = None, None
            self._retry_or_fail(job, error)
        except BaseException as error:  # the actor itself broke (no sandbox starts there): the caller must hear of it
            job.future.set_exception(error)
        else:
            self._busy[index] += seconds
            job.future.set_result(evaluation)

    def _retry_or_fail(self, job: _Job, error: BaseException) -> None:
        reason = one_line(error).rstrip(".")
        with self._lock:
            if self._cancelled:
                job.future.set_result(Evaluation(failure="cancelled: the executor was closed"))
            elif job.retries < self.max_retries:
                job.retries += 1
                log.warning("a Ray actor was lost (%s); retrying its request (retry %d of %d)", reason, job.retries, self.max_retries)
                self.jobs.put(job)  # before this job's task_done, so that close() waits for the retry
            else:
                job.future.set_result(Evaluation(failure=f"lost worker: {reason} after {job.retries} retries"))

    def _replace_actor(self, index: int) -> bool:
        """Start a new actor for dispatcher `index` and wait until it runs; False once closing.

        While a replacement waits for a free CPU (a node was lost), this dispatcher holds no
        request: the other actors take the work."""
        backoff, longest = _REPLACEMENT_BACKOFF_S
        while True:
            with self._lock:
                if self._stopping:
                    return False
                actor = self._actors[index] = self._new_actor()
            try:
                self._pids[index] = self._ray.get(actor.pid.remote())
                return True
            except self._ray.exceptions.RayError as error:
                self._actors[index] = None
                if self._stopping:  # close() killed it
                    return False
                log.warning("a replacement Ray actor did not start (%s); trying again in %g s", one_line(error), backoff)
                time.sleep(backoff)
                backoff = min(2 * backoff, longest)

    def close(self, cancel: bool = False) -> None:
        """Stop the actors: after the queued requests, or at once (`cancel`); then disconnect
        from Ray, and stop the Ray instance if this executor started it."""
        with self._lock:
            self.closed = True
            self._cancelled = cancel
        if cancel:
            self._cancel_queued()
        else:
            self.jobs.join()
        for _ in self.threads:
            self.jobs.put(None)
        self._stop_actors(graceful=not cancel)  # also wakes dispatchers waiting on an actor
        for thread in self.threads:
            thread.join()
        self._shutdown_ray()

    def _cancel_queued(self) -> None:
        for job in drain(self.jobs):
            if not job.future.cancel():  # a retry: its caller already waits
                job.future.set_result(Evaluation(failure="cancelled: the executor was closed"))

    def _stop_actors(self, graceful: bool) -> None:
        with self._lock:
            self._stopping = True
            actors = [actor for actor in self._actors if actor is not None]
        if graceful and actors:
            # Closing the pools first ends each sandbox process cleanly; a dead actor's error is moot.
            self._ray.wait([actor.close.remote() for actor in actors], num_returns=len(actors), timeout=30)
        for actor in actors:
            self._ray.kill(actor, no_restart=True)

    def _shutdown_ray(self) -> None:
        if self._owns_ray:
            self._ray.shutdown()


def _import_ray():
    try:
        import ray
    except ImportError:
        raise ConfigError("executor=ray needs Ray: pip install 'colmo[ray]'") from None
    return ray


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
