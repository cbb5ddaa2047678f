"""The dispatcher both executors share: a job queue served by one thread per worker slot, and
the registry `executor.name` picks from (`EXECUTORS`, filled where each executor is defined).

A slot is whatever evaluates one request at a time: a local sandbox process, a Ray actor.
Each slot's thread opens its worker (again after a loss), takes the next request as soon as it
is free, so work goes to whichever slot is idle, and adds the time it spent to the busy total.
A request whose worker is lost (its process killed, its node gone) goes back to the queue, at
most `max_retries` times, and the slot opens a fresh worker before it takes more work; after
that the request is recorded as a failed `Evaluation` (`lost worker: ...; it held sample 12`,
the request's `label`, or a hash of its program without one). A slot whose
worker cannot start keeps trying with backoff without holding a request; after
`_OPEN_FAILURES_BEFORE_FAILING` failures in a row it takes a request and, if its worker still
cannot start, fails it with the reason, so a broken installation ends in failures, not a hang.
"""

from __future__ import annotations

import abc
import concurrent.futures
import hashlib
import logging
import queue
import threading
import time
from dataclasses import dataclass
from typing import ClassVar, Optional, Sequence

from colmo.config import ExecutorConfig
from colmo.evaluation import CANCELLED, EvalRequest, Evaluation, ExecutorClosed, WorkerLost
from colmo.registry import Registry

log = logging.getLogger("colmo.executor")

_BACKOFF_S = (1.0, 60.0)  # first and longest wait between failed worker starts
_OPEN_FAILURES_BEFORE_FAILING = 3


@dataclass
class _Job:
    request: EvalRequest
    future: concurrent.futures.Future
    retries: int = 0


EXECUTORS: Registry[type["Dispatcher"]] = Registry("executor.name")


class Dispatcher(abc.ABC):
    """Evaluates requests on `n_workers` slots (module docstring). Subclasses say how a slot's
    worker starts, evaluates and stops, then call `_start_dispatching()`. An executor registers
    as `executor=<name>` (`@EXECUTORS.register`) and is built by `from_config`."""

    options: ClassVar[type[ExecutorConfig]] = ExecutorConfig  # the schema of its `executor` option

    @classmethod
    @abc.abstractmethod
    def from_config(cls, cfg: ExecutorConfig, max_workers: Optional[int] = None) -> "Dispatcher":
        """The executor `cfg` describes, with at most `max_workers` workers when given."""

    def __init__(self, n_workers: int, max_retries: int):
        self.n_workers = n_workers
        self.max_retries = max_retries
        self.closed = False
        self._cancelled = False
        self._lock = threading.Lock()
        self._jobs: queue.Queue[Optional[_Job]] = queue.Queue()
        self._busy = [0.0] * n_workers
        self.evaluations_done = 0  # requests answered (a progress display reads it)
        self.steps_done = 0  # control steps they simulated
        self._threads = [threading.Thread(target=self._dispatch, args=(i,), daemon=True, name=f"colmo-slot-{i}") for i in range(n_workers)]

    # -- what a subclass provides ---------------------------------------------------------------

    @abc.abstractmethod
    def _open(self, slot: int) -> None:
        """Start slot `slot`'s worker; raise (any exception) if it cannot start."""

    @abc.abstractmethod
    def _run(self, slot: int, request: EvalRequest) -> Evaluation:
        """Evaluate on the slot's worker; `WorkerLost` if the worker is gone."""

    @abc.abstractmethod
    def _discard(self, slot: int) -> None:
        """Stop the slot's worker (lost, or closing); it may be dead already."""

    @abc.abstractmethod
    def _is_open(self, slot: int) -> bool:
        """Whether the slot has a worker that is believed alive."""

    # -- the shared machinery ------------------------------------------------------------------

    def _start_dispatching(self) -> None:
        for thread in self._threads:
            thread.start()

    @property
    def busy_seconds(self) -> float:
        """Seconds the workers spent evaluating, summed over slots."""
        return sum(self._busy)

    def evaluate(self, requests: Sequence[EvalRequest]) -> list[Evaluation]:
        if self.closed:
            raise ExecutorClosed("the executor is closed")
        jobs = [_Job(request, concurrent.futures.Future()) for request in requests]
        for job in jobs:
            self._jobs.put(job)
        return [job.future.result() for job in jobs]

    def _dispatch(self, slot: int) -> None:
        failures = 0  # failed starts in a row
        while True:
            if not self.closed and not self._is_open(slot) and failures < _OPEN_FAILURES_BEFORE_FAILING:
                if self._try_open(slot) is not None:
                    failures += 1
                    time.sleep(min(_BACKOFF_S[0] * 2 ** (failures - 1), _BACKOFF_S[1]))
                    continue
                failures = 0
            job = self._jobs.get()
            if job is None:
                self._jobs.task_done()
                break
            reason = None if self._is_open(slot) else self._try_open(slot)
            if reason is not None:
                self._settle(job, Evaluation(failure=f"lost worker: {reason}"))
            elif not job.future.done():
                failures = 0
                self._serve(slot, job)
            self._jobs.task_done()
        if self._is_open(slot):
            self._discard(slot)

    def _try_open(self, slot: int) -> Optional[str]:
        """Start the slot's worker; None, or why it did not start."""
        try:
            self._open(slot)
            return None
        except Exception as error:  # noqa: BLE001 - any start failure is retried, then reported
            reason = f"cannot start a worker: {error}"
            log.warning("%s", reason)
            return reason

    def _serve(self, slot: int, job: _Job) -> None:
        start = time.perf_counter()
        try:
            evaluation = self._run(slot, job.request)
        except WorkerLost as error:
            self._discard(slot)
            self._retry_or_fail(job, str(error))
        except BaseException as error:  # the executor itself broke: the caller must hear of it
            job.future.set_exception(error)
        else:
            with self._lock:
                self.evaluations_done += 1
                self.steps_done += evaluation.steps
            job.future.set_result(evaluation)
        self._busy[slot] += time.perf_counter() - start

    def _retry_or_fail(self, job: _Job, reason: str) -> None:
        with self._lock:
            if self._cancelled:
                self._settle(job, Evaluation(failure=CANCELLED))
            elif job.retries < self.max_retries:
                job.retries += 1
                log.warning("a worker was lost (%s); retrying its request (retry %d of %d)", reason, job.retries, self.max_retries)
                self._jobs.put(job)  # before this job's task_done, so that close() waits for the retry
            else:
                held = job.request.label or f"program {hashlib.sha256(job.request.skeleton.encode()).hexdigest()[:12]}"
                self._settle(job, Evaluation(failure=f"lost worker: {reason}; it held {held}, after {job.retries} retries"))

    @staticmethod
    def _settle(job: _Job, evaluation: Evaluation) -> None:
        if not job.future.done():
            job.future.set_result(evaluation)

    def close(self, cancel: bool = False) -> None:
        """Stop: after the queued requests, or at once (`cancel`), queued requests cancelled and
        running ones abandoned with their workers."""
        with self._lock:
            self.closed = True
            self._cancelled = cancel
        if cancel:
            self._cancel_queued()
            for slot in range(self.n_workers):
                if self._is_open(slot):
                    self._discard(slot)  # its thread then sees a lost worker, and the cancellation
        else:
            self._jobs.join()
        for _ in self._threads:
            self._jobs.put(None)
        for thread in self._threads:
            thread.join()

    def _cancel_queued(self) -> None:
        while True:
            try:
                job = self._jobs.get_nowait()
            except queue.Empty:
                return
            self._jobs.task_done()
            if job is not None:
                job.future.set_result(Evaluation(failure=CANCELLED))
