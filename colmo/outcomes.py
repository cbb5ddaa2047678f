"""A sample's outcome: settled at once (no program could be read from the answer, the static
check refused it, or its program is known), or its program tuned and scored in a program
thread of its own (`optimize_program`; the executor is shared). Either way the record is
stored before its future completes, so whatever waits on it sees it stored; a program whose
evaluation was cancelled (a second Ctrl-C) is stored `interrupted`, for a resumed run. A
`Batch` is the outcomes of one batch in flight.
"""

from __future__ import annotations

import concurrent.futures
import threading
from dataclasses import dataclass, field
from typing import Callable, Optional

import numpy as np

from colmo.answers import Reading
from colmo.config import SearchConfig
from colmo.database import ProgramDatabase
from colmo.evaluation import CANCELLED, Evaluator, Executor, ExecutorClosed
from colmo.intake import Unusable
from colmo.optimize import CandidateEvaluator, ProgramResult, optimize_program
from colmo.program import ParametricProgram
from colmo.record import DUPLICATE, FAILED, INTERRUPTED, UNUSABLE, Sample, SampleRecord
from colmo.sandbox.check import ForbiddenProgram
from colmo.store import ProgramStore


@dataclass
class Batch:
    """A batch in flight: its samples, each settled or evaluating in a program thread."""

    index: int
    generation_seconds: float
    started: float
    outcomes: list[concurrent.futures.Future] = field(default_factory=list)  # of SampleRecord

    def done(self) -> bool:
        return all(outcome.done() for outcome in self.outcomes)

    @property
    def entered(self) -> float:
        """When it entered the pipeline: its generation's start (`time.perf_counter()`)."""
        return self.started - self.generation_seconds


class SampleOutcomes:
    """The outcomes of one search's samples, evaluated on `executor` with `evaluator` (set once
    the starter's calibration made it) by `threads` program threads; a tuning stops at its next
    candidate once `must_stop()`; `observe` sees each program's result."""

    def __init__(
        self, cfg: SearchConfig, store: ProgramStore, executor: Executor, threads: int, must_stop: Callable[[], bool],
        observe: Callable[[ProgramResult], None] = lambda result: None,
    ):
        self.cfg = cfg
        self.observe = observe  # told every program's result (what its final scores cost: `colmo.timelimit`)
        self.store = store
        self.executor = executor
        self.evaluator: Optional[Evaluator] = None
        self.must_stop = must_stop
        self.threads = concurrent.futures.ThreadPoolExecutor(threads, thread_name_prefix="colmo-program")
        self._running = 0  # programs submitted whose record is not stored yet
        self._count_lock = threading.Lock()

    def optimize(self, program: ParametricProgram, sample: int) -> ProgramResult:
        """Tune and score `program`, with a seed of its own from the run's seed and `sample`."""
        seed = int(np.random.SeedSequence([self.cfg.seed, sample + 1]).generate_state(1)[0])
        evaluate = CandidateEvaluator(
            self.executor, self.evaluator, program.skeleton, label=f"sample {sample}", count_branches=self.cfg.database.shown_as_run,
        )
        result = optimize_program(program, evaluate, self.cfg.gfo, seed, stop=self.must_stop)
        self.observe(result)
        return result

    def submit(self, sample: Sample, program: Reading, database: ProgramDatabase) -> concurrent.futures.Future:
        """Start the evaluation of the sample's program (as `colmo.answers` read it) unless
        `database` knows it; a future of its stored record."""
        if isinstance(program, Unusable):
            return self._settled(SampleRecord.of(sample, UNUSABLE, failure=f"unusable output: {program}"))
        if isinstance(program, ForbiddenProgram):
            return self._settled(SampleRecord.of(sample, FAILED, failure=str(program)))
        if database.is_known(program.key):
            return self._settled(SampleRecord.of(sample, DUPLICATE, program))
        # Known from now on, so a batch generated before this one is integrated skips it too.
        database.mark_seen(program.key)
        with self._count_lock:
            self._running += 1
        return self.threads.submit(self._evaluate, sample, program)

    def running(self) -> int:
        """Programs being evaluated (tuned, or waiting for a program thread) now; thread-safe."""
        return self._running

    def shutdown(self) -> None:
        """Wait for the program threads (a stopping search has told them to stop)."""
        self.threads.shutdown(wait=True)

    def _evaluate(self, sample: Sample, program: ParametricProgram) -> SampleRecord:
        try:
            try:
                result: Optional[ProgramResult] = self.optimize(program, sample.index)
            except ExecutorClosed:
                result = None
            if result is None or result.failure == CANCELLED:
                return self._stored(SampleRecord.of(sample, INTERRUPTED, program))
            return self._stored(SampleRecord.of_result(sample, program, result))
        finally:
            with self._count_lock:
                self._running -= 1

    def _stored(self, record: SampleRecord) -> SampleRecord:
        self.store.add(record)
        return record

    def _settled(self, record: SampleRecord) -> concurrent.futures.Future:
        """A sample settled without evaluation, stored, as a completed future of its record."""
        done: concurrent.futures.Future = concurrent.futures.Future()
        done.set_result(self._stored(record))
        return done
