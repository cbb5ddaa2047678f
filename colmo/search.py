"""The search loop (paper Fig. 1 and Fig. 6): generate, read, evaluate and optimize in sandboxed
workers, store, and feed the best programs back into prompts.

    starter ─► database ─► prompt ─► generator ─► intake ─► optimize_program ─► store ─► database ...

Generation and evaluation overlap: up to `search.queue_size` batches are in flight, and a new
batch is generated while the workers evaluate the previous ones; each program of a batch is
tuned in a thread of its own (the executor is shared). Batch `k` is always generated from the
database after batches `0 .. k - queue_size` have been integrated, in order, so a run is a
deterministic function of its seed whatever the timing. A batch is written to the store as
`pending` as soon as it is generated, and each sample's row is replaced by its outcome as soon
as that is known: the store's sample numbers never have a gap, and a resumed run evaluates
what was generated but not evaluated. With `search.steady_state` each idle worker gets a child
of its own, drawn when it frees: which programs are in when a prompt is drawn depends on timing.

A duplicate answer (by structure with GFO, by code and constants with `gfo=none`) is generated
again up to `search.duplicate_retries` times (`colmo.answers`: a chat model is told what it
copied, or why its answer cannot be used); `max_samples` and the counters count model calls,
the regenerations included, so that samples mean model calls.

With `search.fill=mutate` the workers do not wait for a slow model: while its call is in flight,
the batches that are in are integrated and the embedded mutation generator (the filler) gives
idle workers batches of its own, from the same database, so that the model sees what mutation
found and mutation works on what the model wrote. The mix depends on timing, so such a run is no
longer a deterministic function of its seed. With `search.model_share=by_yield` the model pauses
after each call for as long as its yield against the filler's says (`colmo.model_share`), and the
filler has the workers and the cores meanwhile.

Stopping: `search.max_samples`, `search.stop_at_score`, and `search.max_seconds`, a wall-clock
limit of the whole run from its `started` (the job's start: `colmo.timelimit.job_start`), with the search's own deadline before it
(`colmo.timelimit`: the finish's time and the programs in flight left over). At the search's
deadline a generation in flight is abandoned and programs in flight stop tuning at their next
candidate, their best so far scored and stored (`cut_short`). Ctrl-C and SIGTERM do the same; a
second one cancels the evaluations in flight, whose samples are stored as `interrupted` and
evaluated when the run is resumed. Nothing evaluated is ever lost.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import dataclasses
import logging
import threading
import time
from collections import deque
from pathlib import Path
from typing import Callable, Optional

from colmo.answers import AnswerReader
from colmo.config import SearchConfig
from colmo.database import ProgramDatabase, StoredProgram
from colmo.errors import RunError
from colmo.evaluation import Evaluator, Executor, ExecutorClosed
from colmo.executor import make_executor
from colmo.finish import BestPrograms, finish
from colmo.generate import Generation, Generator
from colmo.heldout import training_evaluator
from colmo.ledger import Ledger
from colmo.load import LoadMeter
from colmo.model_share import ModelShare
from colmo.optimize.methods import tunes_constants
from colmo.outcomes import Batch, SampleOutcomes
from colmo.program import STRUCTURE_KEY_VERSION, parametrize
from colmo.record import FINISHED, PENDING, BatchReport, Counters, Elapsed, Sample, SampleRecord, SearchObserver, Summary, Totals, generator_label
from colmo.sampler import POLL_S, Sampler
from colmo.signals import stop_signals
from colmo.specs import Spec, load_task_spec
from colmo.store import StoreError, open_run, run_settings, write_outputs
from colmo.timelimit import TimeBudget, program_slots, programs_at_once

log = logging.getLogger("colmo.search")

STARTER_SAMPLE = -1


class Search:
    """One search run into `run_dir` (or the run `cfg.resume` names). `executor` and `generator` are built from the config
    unless given (a test, a notebook, a benchmark); `started`: when the run's time limit began (default: now)."""

    def __init__(
        self, cfg: SearchConfig, run_dir: Path, observers: tuple[SearchObserver, ...] = (),
        executor: Optional[Executor] = None, generator: Optional[Generator] = None, started: Optional[float] = None,
    ):
        self.cfg = cfg
        self.observers = observers
        self.spec: Spec = load_task_spec(cfg.task.spec)
        self.run_dir = Path(cfg.resume).expanduser().resolve() if cfg.resume else run_dir
        self.store, self.lock = open_run(self.run_dir, run_settings(cfg), resume=bool(cfg.resume))
        self.earlier = self.store.elapsed()  # a resumed run's time so far, to add this process's to
        self.executor = executor or make_executor(cfg.executor)
        self.in_flight: deque[Batch] = deque()
        self.counters = Counters()
        self.next_sample = self.next_batch = self.in_flight_samples = self.resumed_samples = 0  # resumed: model calls settled earlier
        self.generation_seconds = 0.0
        self.model_share = ModelShare(cfg.search.model_share, cfg.search.min_model_share)
        self.stop_reason = ""
        self.reader = AnswerReader(self.spec.allowed_imports, cfg.database.max_nodes, tunes_constants(cfg.gfo), max_constants=cfg.database.max_constants)
        if self.store.key_version() != STRUCTURE_KEY_VERSION:  # a new store, or one an older colmo wrote
            rekeyed = self.store.rekey(lambda record: self.reader.key(record.skeleton, record.initial_params or ()), STRUCTURE_KEY_VERSION)
            if rekeyed:
                log.info("%s: the keys of %d samples computed again (its structure keys were of an older colmo)", self.store.path, rekeyed)
        self.sampler = Sampler(cfg, self.spec, self.reader, generator)
        self.stopping = threading.Event()  # programs in flight stop tuning at their next candidate
        self.outcomes = SampleOutcomes(
            cfg, self.store, self.executor, programs_at_once(cfg, self.executor.n_workers), self._tuning_must_stop,
            observe=lambda result: self.budget.observe(result),
        )
        self.load = LoadMeter()
        self.budget = TimeBudget(cfg.search.max_seconds, self.outcomes.running, started=started, tuned=tunes_constants(cfg.gfo), spent=self.earlier.seconds)
        self.evaluator: Optional[Evaluator] = None
        self.database: Optional[ProgramDatabase] = None
        self.ledger: Optional[Ledger] = None

    # -- the run, top to bottom --------------------------------------------------------------

    def run(self) -> Summary:
        with stop_signals(self._on_signal):
            return self._run()

    def _run(self) -> Summary:
        try:
            try:
                if not self.sampler.needs_evaluator():  # a generator that cannot start ends the run before any work
                    self.sampler.start(None)
                self.evaluator = self.outcomes.evaluator = training_evaluator(self.spec, self.cfg.task, self.cfg.executor, self.executor, self.cfg.seed)
                starter = self._starter()
                self.database = ProgramDatabase(self.cfg.database, starter, self.cfg.seed)
                self.budget.plan(self.cfg, self.evaluator.calibration, self.program_seconds, self.executor)
                self.ledger = Ledger(self.database, self.counters)
                to_evaluate = self._replay(starter.key)
                self.sampler.start(self.evaluator)
                self.budget.search_starts()
                self._loop(to_evaluate)
            except (KeyboardInterrupt, ExecutorClosed):  # a signal before the handlers were in place, or a second one
                self.stop_reason = self.stop_reason or "interrupted"
            except StoreError as error:
                self.stop_reason = f"store failed: {error}"
                log.error("%s", self.stop_reason)
            finally:
                self._stop_programs()
                self.budget.search_stops()
            best = BestPrograms()
            if self.database is not None and self.stop_reason in FINISHED:  # a stopped run finishes when resumed
                best = finish(
                    self.cfg, self.store, self.executor, self.evaluator, self.run_dir,
                    until=self.budget.finish_by(), referee=self.budget.finish_referee_cost,
                    observation_names=self.spec.observation_names, observation_bounds=self.spec.observation_bounds,
                )
            best_program = self.database.best if self.database else None
            summary = best.summary(
                self.cfg.task.name, best_program, self.ledger.best_so_far if self.ledger else (), self.stop_reason, self.run_dir,
                self.totals(), *self.budget.phases(), by_generator=self.counters.by_generator,
            )
            write_outputs(summary, self.run_dir)
            for observer in self.observers:
                observer.on_finish(summary)
        finally:
            self._close()
        return summary

    def _loop(self, resumed: list[SampleRecord]) -> None:
        in_flight = self.in_flight
        if resumed:
            in_flight.append(self._reevaluate(resumed))
        steady = self.cfg.search.steady_state
        while True:
            if steady and self._model_may_call():
                self._feed_idle_workers(self.sampler.generator, self._batch_size, programs_at_once(self.cfg, self.executor.n_workers))
            while not steady and self._model_may_call() and len(in_flight) < self.cfg.search.queue_size and self._samples_left() > 0:
                batch = self._generate(self.sampler.generator, self._batch_size(self.cfg.llm.batch_size))
                if batch is None:
                    break
                in_flight.append(batch)
            if not in_flight:
                self.stop_reason = self.stop_reason or "max_samples"
                return
            if steady:
                self._wait_for_a_program()
                self._integrate_done()
            else:
                self._integrate(in_flight.popleft())
                self._check_limits()

    # -- set-up and resume -----------------------------------------------------------------------

    def _starter(self) -> StoredProgram:
        starter = next((r for r in self.store.records() if r.sample == STARTER_SAMPLE), None)
        if starter is None:
            program = self.reader.identified(parametrize(self.spec.starter_code))
            sample = Sample(STARTER_SAMPLE, -1, -1, (), Generation(self.spec.starter_code, "spec"))
            starter = SampleRecord.of_result(sample, program, self.outcomes.optimize(program, STARTER_SAMPLE))
            if starter.failure:
                raise RunError(f"the starter policy in {self.spec.path} fails: {starter.failure}")
            self.store.add(starter)
        # One program's tuning, alone on the workers; unknown (0) from a starter with nothing to tune.
        self.program_seconds = starter.evaluation_seconds if starter.n_params or not tunes_constants(self.cfg.gfo) else 0.0
        return StoredProgram(starter.key, starter.code, starter.score, 0, STARTER_SAMPLE, starter.nodes)

    def _replay(self, starter_key: str) -> list[SampleRecord]:
        """Rebuild the ledger from the store of an earlier run; the samples it left pending or
        interrupted, to evaluate first."""
        replayed = self.ledger.replay((r for r in self.store.records() if r.sample != STARTER_SAMPLE), starter_key)
        self.next_sample, self.next_batch = replayed.next_sample, replayed.next_batch
        self.resumed_samples = self.counters.samples
        if self.counters.samples or replayed.to_evaluate:
            log.info(
                "resumed %s: %d samples, best %.2f, %d to evaluate again",
                self.run_dir, self.counters.samples, self.database.best.score, len(replayed.to_evaluate),
            )
        return replayed.to_evaluate

    # -- generation ------------------------------------------------------------------------------

    def _samples_left(self) -> int:
        return self.cfg.search.max_samples - self.counters.samples - self.in_flight_samples

    def _generate(self, generator: Generator, n: int) -> Optional[Batch]:
        """Generate the next batch of `n` samples with `generator` and start evaluating it; None
        if the search is stopping."""
        if not n:
            return None
        started = time.perf_counter()
        answers = self.sampler.answers(generator, self.database, n, self._samples_left() - n, self._abandon_generation)
        if answers is None:
            self.stop_reason = self.stop_reason or self.sampler.failure
            return None
        seconds = time.perf_counter() - started
        self.generation_seconds += seconds
        batch = Batch(self.next_batch, seconds, time.perf_counter())
        samples = [
            Sample(self.next_sample + i, batch.index, answer.prompt.island, tuple(answer.prompt.parent_keys), answer.generation)
            for i, answer in enumerate(answers)
        ]
        # Stored before any is evaluated: a full disk stops the search here, no gap in the sample numbers; a stopped run evaluates them on resume.
        self.store.add(*(SampleRecord.of(sample, PENDING) for sample in samples))
        self.next_batch += 1
        self.next_sample += len(samples)
        for sample, answer in zip(samples, answers):
            batch.outcomes.append(self.outcomes.submit(sample, answer.reading, self.database))
        calls = sum(sample.generation.calls for sample in samples)
        self.in_flight_samples += calls
        label = generator_label(samples[0].generation.generator) if samples else ""
        if generator is self.sampler.generator:  # duplicates and failures settle at once: the others are tuned
            self.budget.follow_generation(self._samples_left(), calls, seconds, sum(not outcome.done() for outcome in batch.outcomes))
            self.model_share.called(generator, label, seconds, self.sampler.filler, self.counters.by_generator)
        elif label:
            self.model_share.filler_label = label
        return batch

    def _model_may_call(self) -> bool:
        """Whether the model may be called now: once its pause is over, the filler filling the
        workers meanwhile; False if the search is stopping."""
        while not self._stop_requested() and self.model_share.paused():
            self._fill()
            self._wait_for_a_program()
        return not self._stop_requested()

    def _wait_for_a_program(self) -> None:
        """Until a program in flight is in, or `POLL_S` has passed."""
        unsettled = [outcome for batch in self.in_flight for outcome in batch.outcomes if not outcome.done()]
        if unsettled:
            concurrent.futures.wait(unsettled, timeout=POLL_S, return_when=concurrent.futures.FIRST_COMPLETED)
        else:
            time.sleep(POLL_S)

    def _abandon_generation(self, programs: int) -> bool:
        """Asked while the generator's call is in flight: whether to abandon it (the search is
        stopping, or the time left can no longer take its `programs`); meanwhile the filler fills."""
        if self._stop_requested() or not self.budget.can_start(programs):
            self.stop_reason = self.stop_reason or "max_seconds"
            return True
        self._fill()
        return False

    def _reevaluate(self, records: list[SampleRecord]) -> Batch:
        """The pending and interrupted samples of a resumed run, as a batch of their own."""
        batch = Batch(records[0].batch, 0.0, time.perf_counter())
        for sample in (record.as_sample() for record in records):
            batch.outcomes.append(self.outcomes.submit(sample, self.reader.read(sample.generation), self.database))
        self.in_flight_samples += sum(record.model_calls for record in records)
        return batch

    def _fill(self) -> None:
        """Integrate the batches that are in, and give idle workers a batch of the filler's."""
        if self.sampler.filler is not None:
            self._feed_idle_workers(self.sampler.filler, self._programs_that_fit, program_slots(self.cfg, self.executor.n_workers))

    def _feed_idle_workers(self, generator: Generator, batch_size: Callable[[int], int], slots: int) -> None:
        """Integrate the batches that are in, in order, and keep `slots` programs in flight: a child of `generator`'s for
        each one missing, drawn from the database as it is now, as many as `batch_size(free)` allows."""
        self._integrate_done()
        free = slots - self.outcomes.running()
        if free > 0 and not self._stop_requested():
            batch = self._generate(generator, batch_size(free))
            if batch is not None:
                self.in_flight.append(batch)

    # -- integration ----------------------------------------------------------------------------

    def _integrate_done(self) -> None:
        """Integrate the batches in flight that are in, in order."""
        while self.in_flight and self.in_flight[0].done():
            self._integrate(self.in_flight.popleft())
            self._check_limits()

    def _integrate(self, batch: Batch) -> None:
        while not concurrent.futures.wait(batch.outcomes, timeout=POLL_S).not_done == set():
            self._stop_requested()  # the deadline stops the programs in flight at their next candidate
        records = [outcome.result() for outcome in batch.outcomes]  # stored; an exception here is a bug or a full disk
        for record in records:
            self.ledger.settle(record)
        self.in_flight_samples -= sum(record.model_calls for record in records)
        reset = self.ledger.end_batch()
        if reset:
            log.info("reset islands %s", reset)
        report = self._report(batch)
        pipeline = [(len(b.outcomes), b.entered) for b in self.in_flight]
        self.budget.follow_samples(report, self.resumed_samples, self.cfg.search.max_samples, (len(records), batch.entered), pipeline)
        self.store.set_elapsed(self.elapsed())  # a run killed later resumes with its time up to here
        log.info(
            "batch %d: samples %d, programs evaluated %d, best %.2f, gen %.1f s, eval %.1f s, evals/s %.1f, load %.1f",
            batch.index, report.samples, report.programs_evaluated, report.best_score,
            report.generation_seconds, report.evaluation_seconds, report.evaluations_per_second, report.load,
        )
        for observer in self.observers:
            observer.on_batch(report, records)

    # -- stopping ---------------------------------------------------------------------------------

    def _tuning_must_stop(self) -> bool:
        """Past the deadline or once interrupted (not when the generator fails), at the next candidate."""
        return self.stopping.is_set() or self.budget.past_deadline()

    def _stop_requested(self) -> bool:
        if self.budget.past_deadline() and not self.stopping.is_set():
            self.stop_reason = self.stop_reason or "max_seconds"
            self.stopping.set()
            log.info("search deadline: %d programs in flight stop tuning and score their best constants", self.outcomes.running())
        return bool(self.stop_reason)

    def _programs_that_fit(self, most: int) -> int:
        """`most`, or fewer if fewer samples are left or the time left can tune and drain fewer programs."""
        return self.budget.programs_that_fit(min(most, self._samples_left()))

    def _batch_size(self, most: int) -> int:
        """The generator's next batch; 0 while samples are left ends the generation, for lack of time."""
        size = self._programs_that_fit(most)
        if not size and self._samples_left() > 0:
            self.stop_reason = self.stop_reason or "max_seconds"
        return size

    def _check_limits(self) -> None:
        limit = self.cfg.search.stop_at_score
        if limit is not None and self.database.best.score >= limit:
            self.stop_reason = self.stop_reason or "stop_at_score"
        if self.counters.samples >= self.cfg.search.max_samples:
            self.stop_reason = self.stop_reason or "max_samples"
        self._stop_requested()

    def _on_signal(self, signum: int) -> None:
        if not self.stopping.is_set():
            self.stop_reason = self.stop_reason or "interrupted"
            self.stopping.set()
            log.warning("stopping: the programs in flight finish with their best constants so far (again to stop at once)")
        else:
            log.warning("stopping at once: the programs in flight are stored as interrupted")
            threading.Thread(target=self.executor.close, kwargs={"cancel": True}, daemon=True).start()

    def _stop_programs(self) -> None:
        self.stopping.set()
        self.sampler.stop()
        self.outcomes.shutdown()

    def _close(self) -> None:
        with contextlib.suppress(StoreError):  # a store that failed: the summary has the run's time
            self.store.set_elapsed(self.elapsed())
        self.sampler.close()
        if not self.executor.closed:
            self.executor.close()
        self.store.close()
        self.lock.release()

    # -- reports ---------------------------------------------------------------------------------

    def elapsed(self) -> Elapsed:
        """The run's time: its earlier processes' (a resumed run) and this one's."""
        seconds = self.budget.elapsed()
        return self.earlier.plus(Elapsed(seconds, self.generation_seconds, self.executor.busy_seconds, self.load.load_seconds(seconds)))

    def totals(self) -> Totals:
        """What the search has done so far, as the progress display, each batch report and the summary say it."""
        return self.counters.totals(self.elapsed(), self.executor.n_workers)

    def _report(self, batch: Batch) -> BatchReport:
        return BatchReport(
            batch=batch.index, best_score=self.database.best.score, best_per_island=tuple(self.database.best_per_island),
            generation_seconds=batch.generation_seconds, evaluation_seconds=time.perf_counter() - batch.started,
            queue_depth=self.next_batch - batch.index - 1, **dataclasses.asdict(self.totals()),
        )
