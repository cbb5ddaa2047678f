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
what was generated but not evaluated.

A duplicate answer (a program evaluated before, by structure with GFO, by code and constants
with `gfo=none`: `colmo.database.identity`) is generated again from another selection, up to
`search.duplicate_retries` times, before it is recorded as a duplicate; `max_samples` and the
counters count model calls, the regenerations included, so that samples mean model calls.

Stopping: `search.max_samples`, `search.stop_at_score`, and `search.max_seconds`, a wall-clock
limit of the whole run from the start of the process: the search stops early enough to leave
the programs in flight their final scores and the finish its held-out scores, simplification
and video (`colmo.finish.plan_finish`, from the starter's calibration), and says before the first
batch how long the run will take and which limit binds. At the search's deadline a generation in flight is abandoned and programs in flight stop tuning
at their next candidate, their best so far scored and stored (`cut_short`). Ctrl-C and SIGTERM
do the same; a second one cancels the evaluations in flight, whose samples are stored as
`interrupted` and evaluated when the run is resumed. Nothing evaluated is ever lost.
"""

from __future__ import annotations

import concurrent.futures
import dataclasses
import logging
import os
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional, Union

import numpy as np

from colmo.finish import FINISH_SHARE, SAFETY, BestPrograms, finish, plan_finish
from colmo.config import SearchConfig
from colmo.database import ProgramDatabase, StoredProgram, identity
from colmo.environments.perturb import with_perturbation
from colmo.errors import RunError
from colmo.evaluation import CANCELLED, Evaluator, Executor, ExecutorClosed
from colmo.executor import make_executor
from colmo.generate import GENERATORS, Generation, Generator, GeneratorError, make_generator
from colmo.generate.probe import ProgramProbe
from colmo.intake import Unusable, read_program
from colmo.optimize import CandidateEvaluator, optimize_program
from colmo.optimize.tune import calibrated
from colmo.program import ParametricProgram, parametrize
from colmo.progress import duration
from colmo.prompt import Prompt, build_prompt
from colmo.record import (
    DUPLICATE,
    FAILED,
    FINISHED,
    INTERRUPTED,
    PENDING,
    TO_EVALUATE_AGAIN,
    UNUSABLE,
    BatchReport,
    Counters,
    Sample,
    SampleRecord,
    SearchObserver,
    Summary,
    busy_fractions,
)
from colmo.sandbox.check import ForbiddenProgram
from colmo.signals import stop_signals
from colmo.specs import Spec, load_task_spec
from colmo.store import StoreError, open_run, run_settings, write_outputs
from colmo.rollout import episode_seeds

log = logging.getLogger("colmo.search")

STARTER_SAMPLE = -1
_POLL_S = 0.2  # how often waits check the deadline and interruptions
# The finish ends this long before the limit: writing the summary, closing the workers and leaving
# the process took up to 6.5 s on 2 loaded cores, which this and the 5 s a run may take past its limit cover.
_CLOSE_S = 1.5


# An answer's program, keyed as the run tells programs apart, or why no program could be read from it.
Reading = Union[ParametricProgram, Unusable, ForbiddenProgram]


@dataclass(frozen=True)
class _Answer:
    """A model's answer with the prompt it answered and its program as read, once."""

    prompt: Prompt
    generation: Generation
    reading: Reading


@dataclass
class _Batch:
    """A batch in flight: its samples, each settled or evaluating in a program thread."""

    index: int
    generation_seconds: float
    started: float
    outcomes: list[concurrent.futures.Future] = field(default_factory=list)  # of SampleRecord


class Search:
    """One search run into `run_dir` (or the run `cfg.resume` names). `executor` and
    `generator` are built from the config unless given (a test, a notebook, a benchmark)."""

    def __init__(
        self, cfg: SearchConfig, run_dir: Path, observers: tuple[SearchObserver, ...] = (),
        executor: Optional[Executor] = None, generator: Optional[Generator] = None,
    ):
        self.cfg = cfg
        self.observers = observers
        self.spec: Spec = load_task_spec(cfg.task.spec)
        self.run_dir = Path(cfg.resume).expanduser().resolve() if cfg.resume else run_dir
        self.store, self.lock = open_run(self.run_dir, run_settings(cfg), resume=bool(cfg.resume))
        self.executor = executor or make_executor(cfg.executor)
        self.generator = generator
        self.probe: Optional[ProgramProbe] = None
        self.counters = Counters()
        self.best_so_far: list[tuple[int, float]] = []
        self.next_sample = self.next_batch = self.in_flight_samples = 0
        self.generation_seconds = 0.0
        self.stop_reason = ""
        self.start = time.perf_counter()
        # The limit counts from the process's start (imports and Hydra included); the search's
        # own deadline comes earlier, once the calibration tells what the finish will cost.
        self.end = self.start - process_seconds() + cfg.search.max_seconds if cfg.search.max_seconds else float("inf")
        self.deadline = self.start + 0.5 * (self.end - self.start)  # the starter's tuning gets half the time at most
        self.episode_seconds = 0.0  # one referee episode of the starter: what the finish costs per episode
        self.estimated_seconds: Optional[float] = None  # the search by max_samples, before the first batch
        self.stopping = threading.Event()  # programs in flight stop tuning at their next candidate
        self.program_threads = concurrent.futures.ThreadPoolExecutor(cfg.llm.batch_size * cfg.search.queue_size, thread_name_prefix="colmo-program")
        self.generation_thread = concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="colmo-generate")
        self.seeds = episode_seeds(cfg.seed, cfg.task.episodes)
        self.evaluator: Optional[Evaluator] = None
        self.database: Optional[ProgramDatabase] = None

    # -- the run, top to bottom --------------------------------------------------------------

    def run(self) -> Summary:
        with stop_signals(self._on_signal):
            return self._run()

    def _run(self) -> Summary:
        try:
            try:
                if not self._wants_probe():  # a generator that cannot start ends the run before any work
                    self._start_generator()
                options = with_perturbation(self.cfg.task.env, self.cfg.task.perturb)  # training under task.perturb
                provisional = Evaluator.for_task(self.spec, options, self.seeds, self.cfg.executor.memory_mb)
                calibrating = time.perf_counter()
                self.evaluator = calibrated(self.executor, provisional, parametrize(self.spec.starter_code), self.cfg.executor.timeout_s)
                calibration = time.perf_counter() - calibrating
                self.database = ProgramDatabase(self.cfg.database, self._starter(), self.cfg.seed)
                self._budget(calibration)
                self.best_so_far = [(0, self.database.best.score)]
                to_evaluate = self._replay()
                self._start_generator()
                self._loop(to_evaluate)
            except (KeyboardInterrupt, ExecutorClosed):  # a signal before the handlers were in place, or a second one
                self.stop_reason = self.stop_reason or "interrupted"
            except StoreError as error:
                self.stop_reason = f"store failed: {error}"
                log.error("%s", self.stop_reason)
            finally:
                self._stop_programs()
            best = BestPrograms()
            if self.database is not None and self.stop_reason in FINISHED:  # a stopped run finishes when resumed
                best = finish(self.cfg, self.store, self.executor, self.evaluator, self.run_dir, until=self._finish_by(), episode_seconds=self.episode_seconds)
            summary = self._summary(best)
            write_outputs(summary, self.run_dir)
            for observer in self.observers:
                observer.on_finish(summary)
        finally:
            self._close()
        return summary

    def _loop(self, resumed: list[SampleRecord]) -> None:
        in_flight: deque[_Batch] = deque()
        if resumed:
            in_flight.append(self._reevaluate(resumed))
        while True:
            while not self.stop_reason and len(in_flight) < self.cfg.search.queue_size and self._samples_left() > 0:
                batch = self._generate()
                if batch is None:
                    break
                in_flight.append(batch)
            if not in_flight:
                self.stop_reason = self.stop_reason or "max_samples"
                return
            self._integrate(in_flight.popleft())
            self._check_limits()

    # -- set-up and resume -----------------------------------------------------------------------

    def _starter(self) -> StoredProgram:
        starter = next((r for r in self.store.records() if r.sample == STARTER_SAMPLE), None)
        if starter is None:
            program = self._identified(parametrize(self.spec.starter_code))
            sample = Sample(STARTER_SAMPLE, -1, -1, (), Generation(self.spec.starter_code, "spec"))
            starter = SampleRecord.of(sample, "", program, self._optimize(program, STARTER_SAMPLE))
            if starter.failure:
                raise RunError(f"the starter policy in {self.spec.path} fails: {starter.failure}")
            self.store.add(starter)
        self.program_seconds = starter.evaluation_seconds  # one program's tuning, alone on the workers
        return StoredProgram(starter.key, starter.code, starter.score, 0, STARTER_SAMPLE, starter.nodes)

    def _replay(self) -> list[SampleRecord]:
        """Rebuild the database and counters from the store of an earlier run; the samples it
        left pending or interrupted, to evaluate first."""
        batch, to_evaluate = None, []
        for record in self.store.records():
            if record.sample == STARTER_SAMPLE:
                continue
            if batch is not None and record.batch != batch:
                self.database.on_sample(self.counters.samples)
            batch = record.batch
            if record.status in TO_EVALUATE_AGAIN:
                to_evaluate.append(record)
            else:
                self._apply(record)
            self.next_sample, self.next_batch = record.sample + 1, record.batch + 1
        if batch is not None:
            self.database.on_sample(self.counters.samples)
        if self.counters.samples or to_evaluate:
            log.info("resumed %s: %d samples, best %.2f, %d to evaluate again", self.run_dir, self.counters.samples, self.database.best.score, len(to_evaluate))
        return to_evaluate

    def _wants_probe(self) -> bool:
        return self.generator is None and getattr(GENERATORS.get(self.cfg.llm.name), "wants_probe", False)

    def _start_generator(self) -> None:
        """The generator of `cfg.llm` (unless one was given); one that cannot start is a
        `RunError` (a server that does not answer, a model that does not load)."""
        if self.generator is not None:
            return
        self.probe = ProgramProbe(self.evaluator) if self._wants_probe() else None
        try:
            self.generator = make_generator(self.cfg.llm, self.cfg.seed, self.probe)
        except GeneratorError as error:
            raise RunError(f"llm={self.cfg.llm.name}: {error}") from None

    # -- generation ------------------------------------------------------------------------------

    def _samples_left(self) -> int:
        return self.cfg.search.max_samples - self.counters.samples - self.in_flight_samples

    def _prompt(self, retry: int = 0) -> Prompt:
        """A prompt from a new selection of the database; `retry`: the regeneration of a duplicate it is for."""
        prompt = build_prompt(self.spec.description, self.database.select(), constants_tuned=self.cfg.gfo.tunes_constants)
        return dataclasses.replace(prompt, retry=retry)

    def _generate(self) -> Optional[_Batch]:
        """Generate the next batch and start evaluating it; None if the search is stopping."""
        prompt = self._prompt()
        n = min(self.cfg.llm.batch_size, self._samples_left())
        started = time.perf_counter()
        generations = self._generated(prompt, n)
        if generations is None:
            return None
        answers = [_Answer(prompt, generation, self._read(generation)) for generation in generations]
        answers = self._regenerate_duplicates(answers, self._samples_left() - n)
        seconds = time.perf_counter() - started
        self.generation_seconds += seconds
        batch = _Batch(self.next_batch, seconds, time.perf_counter())
        samples = [
            Sample(self.next_sample + i, batch.index, answer.prompt.island, tuple(answer.prompt.parent_keys), answer.generation)
            for i, answer in enumerate(answers)
        ]
        # Stored before any is evaluated (a full disk stops the search here, with no gap in the
        # store's sample numbers); a run that stops before their outcomes land evaluates them on resume.
        self.store.add(*(SampleRecord.of(sample, PENDING) for sample in samples))
        self.next_batch += 1
        self.next_sample += len(samples)
        for sample, answer in zip(samples, answers):
            batch.outcomes.append(self._submit(sample, answer.reading))
        self.in_flight_samples += sum(sample.generation.calls for sample in samples)
        return batch

    def _generated(self, prompt: Prompt, n: int) -> Optional[list[Generation]]:
        """The generator's answers to `prompt`; None if the search is stopping or the generator failed."""
        generating = self.generation_thread.submit(self.generator.generate, prompt, n)
        while not generating.done():
            if self._stop_requested():
                generating.cancel()
                self.generator.cancel()
                return None
            concurrent.futures.wait([generating], timeout=_POLL_S)
        try:
            return generating.result()
        except GeneratorError as error:  # the batches in flight are still integrated
            self.stop_reason = f"generator failed: {error}"
            log.error("%s", self.stop_reason)
            return None

    def _regenerate_duplicates(self, answers: list[_Answer], calls_left: int) -> list[_Answer]:
        """`answers` with each duplicate generated again, from a new selection of the database (a
        fresh seed comes with every request, and a language model samples each retry hotter,
        `llm.retry_temperature_step`), up to `search.duplicate_retries` times and within
        `calls_left` model calls: a model's copy of a shown program would waste its turn. A
        regenerated answer carries the calls, tokens and seconds of the ones it replaces."""
        for retry in range(1, self.cfg.search.duplicate_retries + 1):
            repeated = self._duplicates(answers)[: max(calls_left, 0)]
            if not repeated:
                break
            prompt = self._prompt(retry)
            fresh = self._generated(prompt, len(repeated))
            if fresh is None:  # stopping: the answers so far are stored
                break
            calls_left -= len(fresh)
            for i, generation in zip(repeated, fresh):
                answers[i] = _Answer(prompt, generation.after(answers[i].generation), self._read(generation))
        return answers

    def _duplicates(self, answers: list[_Answer]) -> list[int]:
        """The positions in `answers` whose program is known, or the same as an earlier answer's."""
        keys: set[str] = set()
        repeated = []
        for i, answer in enumerate(answers):
            if not isinstance(answer.reading, ParametricProgram):
                continue
            key = answer.reading.key
            if self.database.is_known(key) or key in keys:
                repeated.append(i)
            keys.add(key)
        return repeated

    def _read(self, generation: Generation) -> Reading:
        """The program of an answer, keyed as this run tells programs apart, or why none could be
        read (read once per answer: extraction and the static check are the coordinator's work)."""
        try:
            return self._identified(read_program(generation.text, self.spec.allowed_imports, generation.prefix, self.cfg.database.max_nodes))
        except (Unusable, ForbiddenProgram) as error:
            return error

    def _identified(self, program: ParametricProgram) -> ParametricProgram:
        """With GFO, programs that differ only in constants are one; with gfo=none, each set of constants is a program."""
        return identity(program, by_structure=self.cfg.gfo.tunes_constants)

    def _reevaluate(self, records: list[SampleRecord]) -> _Batch:
        """The pending and interrupted samples of a resumed run, as a batch of their own."""
        batch = _Batch(records[0].batch, 0.0, time.perf_counter())
        for record in records:
            generation = Generation(
                record.raw, record.generator, record.prompt_tokens, record.completion_tokens, record.generation_seconds, record.prompt_prefix,
                record.model_calls,
            )
            sample = Sample(record.sample, record.batch, record.island, record.parent_keys, generation)
            batch.outcomes.append(self._submit(sample, self._read(generation)))
        self.in_flight_samples += sum(record.model_calls for record in records)
        return batch

    def _submit(self, sample: Sample, program: Reading) -> concurrent.futures.Future:
        """Start the evaluation of the sample's program (as `_read` read it); a future of its record."""
        if isinstance(program, Unusable):
            return self._settled(SampleRecord.of(sample, UNUSABLE, failure=f"unusable output: {program}"))
        if isinstance(program, ForbiddenProgram):
            return self._settled(SampleRecord.of(sample, FAILED, failure=str(program)))
        if self.database.is_known(program.key):
            return self._settled(SampleRecord.of(sample, DUPLICATE, program))
        # Known from now on, so a batch generated before this one is integrated skips it too.
        self.database.mark_seen(program.key)
        return self.program_threads.submit(self._evaluate, sample, program)

    # -- evaluation (in program threads) ---------------------------------------------------------

    def _optimize(self, program: ParametricProgram, sample: int):
        seed = int(np.random.SeedSequence([self.cfg.seed, sample + 1]).generate_state(1)[0])
        evaluate = CandidateEvaluator(self.executor, self.evaluator, program.skeleton)
        return optimize_program(program, evaluate, self.cfg.gfo, seed, stop=self._tuning_must_stop)

    def _evaluate(self, sample: Sample, program: ParametricProgram) -> SampleRecord:
        """Optimize and score one program, and store it; the record is stored before the future
        completes, so whatever waits on it sees it stored."""
        try:
            result = self._optimize(program, sample.index)
        except ExecutorClosed:
            result = None
        if result is None or result.failure == CANCELLED:
            return self._stored(SampleRecord.of(sample, INTERRUPTED, program))
        return self._stored(SampleRecord.of(sample, "", program, result))

    def _stored(self, record: SampleRecord) -> SampleRecord:
        self.store.add(record)
        return record

    def _settled(self, record: SampleRecord) -> concurrent.futures.Future:
        """A sample settled without evaluation, stored, as a completed future of its record."""
        done: concurrent.futures.Future = concurrent.futures.Future()
        done.set_result(self._stored(record))
        return done

    # -- integration ----------------------------------------------------------------------------

    def _integrate(self, batch: _Batch) -> None:
        while not concurrent.futures.wait(batch.outcomes, timeout=_POLL_S).not_done == set():
            self._stop_requested()  # the deadline stops the programs in flight at their next candidate
        records = [outcome.result() for outcome in batch.outcomes]  # stored; an exception here is a bug or a full disk
        for record in records:
            self._apply(record)
        self.in_flight_samples -= sum(record.model_calls for record in records)
        reset = self.database.on_sample(self.counters.samples)
        if reset:
            log.info("reset islands %s", reset)
        report = self._report(batch)
        log.info(
            "batch %d: samples %d, programs evaluated %d, best %.2f, gen %.1f s, eval %.1f s, evals/s %.1f",
            batch.index, report.samples, report.programs_evaluated, report.best_score,
            report.generation_seconds, report.evaluation_seconds, report.evaluations_per_second,
        )
        for observer in self.observers:
            observer.on_batch(report, records)

    def _apply(self, record: SampleRecord) -> None:
        """Count one settled sample and register it in the database, in sample order."""
        self.counters.count(record)
        if record.status == "evaluated":
            before = self.database.best.score
            self.database.register(StoredProgram(record.key, record.code, record.score, record.island, record.sample, record.nodes))
            if self.database.best.score > before:
                self.best_so_far.append((self.counters.samples, self.database.best.score))
        elif record.key and record.status != INTERRUPTED:
            self.database.mark_seen(record.key)

    # -- stopping ---------------------------------------------------------------------------------

    def _tuning_must_stop(self) -> bool:
        """Programs in flight stop tuning at their next candidate past the deadline, or once the
        search is interrupted (a generator that fails lets them finish)."""
        return self.stopping.is_set() or time.perf_counter() >= self.deadline

    def _stop_requested(self) -> bool:
        if time.perf_counter() >= self.deadline and not self.stop_reason:
            self.stop_reason = "max_seconds"
            self.stopping.set()
        return bool(self.stop_reason)

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

    def _budget(self, calibration: float) -> None:
        """The run's duration estimated from the starter's calibration (`calibration` seconds
        for its training episodes, fast path and referee) and tuning, the search's deadline set
        to leave the finish and the programs in flight their time, both said in one line."""
        cfg = self.cfg
        workers = self.executor.n_workers
        self.episode_seconds = calibration / len(self.seeds)
        in_parallel = max(1, min(cfg.llm.batch_size * cfg.search.queue_size, workers // cfg.gfo.workers))
        self.estimated_seconds = cfg.search.max_samples * self.program_seconds / in_parallel
        plan = plan_finish(cfg, self.episode_seconds, workers)
        limit = "max_samples"
        if cfg.search.max_seconds:
            # Past the deadline each program in flight ends its candidate, then scores its rounded
            # constants on the fast path and by the referee: three evaluations each, on shared workers.
            evaluation = self.program_seconds / (cfg.gfo.budget + 2 if cfg.gfo.tunes_constants else 1)
            in_flight = SAFETY * 3 * evaluation * max(1.0, cfg.llm.batch_size * cfg.search.queue_size / workers)
            left = self.end - time.perf_counter()
            limit = f"max_seconds={cfg.search.max_seconds:g}"
            plan = plan_finish(cfg, self.episode_seconds, workers, FINISH_SHARE * max(left, 0.0))
            # The search keeps a quarter of the time left at least: `finish` plans again with what it leaves.
            self.deadline = max(self.end - plan.seconds - in_flight, time.perf_counter() + 0.25 * max(left, 0.0))
            if self.deadline - time.perf_counter() >= self.estimated_seconds:
                limit = "max_samples"
        early = f" (search stops {duration(self.end - self.deadline)} early to finish)" if limit.startswith("max_seconds") else ""
        log.info(
            "estimated duration: search %s (%d samples x %.1f s, %d at a time, generation not included), finish %s; limit that binds: %s%s",
            duration(self.estimated_seconds), cfg.search.max_samples, self.program_seconds, in_parallel, duration(plan.seconds), limit, early,
        )

    def _finish_by(self) -> float:
        """When the work on the best programs must end (`time.monotonic()`): with a time limit,
        in time to write the summary and close the workers by its end."""
        if not self.cfg.search.max_seconds:
            return float("inf")
        return time.monotonic() + max(self.end - _CLOSE_S - time.perf_counter(), 0.0)

    def _stop_programs(self) -> None:
        self.stopping.set()
        self.generation_thread.shutdown(wait=False, cancel_futures=True)
        self.program_threads.shutdown(wait=True)

    def _close(self) -> None:
        for resource in (self.generator, self.probe):
            if resource is not None:
                resource.close()
        if not self.executor.closed:
            self.executor.close()
        self.store.close()
        self.lock.release()

    # -- reports ---------------------------------------------------------------------------------

    def _totals(self) -> dict:
        """What both reports say: the counters, rates, and busy fractions of the wall time so far."""
        wall = time.perf_counter() - self.start
        generator_busy, evaluator_busy = busy_fractions(self.generation_seconds, self.executor.busy_seconds, self.executor.n_workers, wall)
        return self.counters.totals() | dict(
            evaluations_per_second=self.counters.evaluations / wall if wall else 0.0,
            generator_busy=generator_busy, evaluator_busy=evaluator_busy, seconds=wall,
        )

    def _report(self, batch: _Batch) -> BatchReport:
        return BatchReport(
            batch=batch.index, best_score=self.database.best.score, best_per_island=tuple(self.database.best_per_island),
            generation_seconds=batch.generation_seconds, evaluation_seconds=time.perf_counter() - batch.started,
            queue_depth=self.next_batch - batch.index - 1, **self._totals(),
        )

    def _summary(self, programs: BestPrograms) -> Summary:
        best = self.database.best if self.database else None
        best_heldout = next((h["heldout_score"] for h in programs.heldout if best and h["key"] == best.key), None)
        return Summary(
            task=self.cfg.task.name, best_score=best.score if best else None, best_heldout_score=best_heldout,
            best_key=best.key if best else None, best_code=best.code if best else None,
            best_so_far=tuple(self.best_so_far), stop_reason=self.stop_reason, run_dir=str(self.run_dir),
            heldout=tuple(programs.heldout), media=programs.media, simplified=programs.simplified, **self._totals(),
        )


def process_seconds() -> float:
    """Seconds since this process started (Linux's /proc); 0 where that is not known."""
    try:
        ticks = int(Path("/proc/self/stat").read_text().rsplit(")", 1)[1].split()[19])
        return max(time.clock_gettime(time.CLOCK_BOOTTIME) - ticks / os.sysconf("SC_CLK_TCK"), 0.0)
    except (OSError, ValueError, IndexError, AttributeError):
        return 0.0

