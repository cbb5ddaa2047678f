"""The search loop (paper Fig. 1 and Fig. 6): generate, extract, parametrize, evaluate and
optimize in sandboxed workers, store, and feed the best programs back into prompts.

Generation and evaluation overlap: up to `search.queue_size` batches are in flight, and a new
batch is generated (in this thread) while the workers evaluate the previous ones. Batch `k`
is always generated from the database after batches `0 .. k - queue_size` have been
integrated, in order, so a run is a deterministic function of its seed whatever the timing.
Every sample is written to the program store as soon as its outcome is known.
"""

from __future__ import annotations

import concurrent.futures
import logging
import math
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
import json
from typing import Any, Optional, Protocol

import numpy as np

from colmo.config import ConfigError, SearchConfig
from colmo.database import ProgramDatabase, StoredProgram
from colmo.extract import ExtractionError, extract_policy
from colmo.generate import Generation, GeneratorError, make_generator
from colmo.optimize import ProgramResult, optimize_program
from colmo.program import ParametricProgram, ProgramError, parametrize
from colmo.prompt import Prompt, build_prompt
from colmo.executor import make_executor
from colmo.sandbox import ForbiddenProgram, ProgramProbe, batch_evaluator, check_program
from colmo.spec import Spec, load_task_spec
from colmo.store import STORE_FILE, ProgramStore, SampleRecord, open_for_resume
from colmo.task import episode_seeds

log = logging.getLogger("colmo.search")

STARTER_SAMPLE = -1
_PROBE_TIMEOUT_S = 30.0
SUMMARY_FILE = "summary.json"
BEST_POLICY_FILE = "best_policy.py"


class SearchObserver(Protocol):
    """Receives progress (a tracker, a progress line)."""

    def on_batch(self, report: dict[str, Any], records: list[SampleRecord]) -> None: ...

    def on_finish(self, summary: dict[str, Any]) -> None: ...


@dataclass
class _Pending:
    """One sample of a batch in flight: either already settled (duplicate, invalid) or evaluating."""

    record: SampleRecord
    program: Optional[ParametricProgram] = None
    future: Optional[concurrent.futures.Future] = None


@dataclass
class _Batch:
    index: int
    prompt: Prompt
    generation_seconds: float
    started: float
    pending: list[_Pending] = field(default_factory=list)


@dataclass
class Counters:
    samples: int = 0
    evaluated: int = 0
    duplicates: int = 0
    failures: int = 0
    invalid: int = 0
    evaluations: int = 0

    def count(self, record: SampleRecord) -> None:
        self.samples += 1
        if record.status == "evaluated":
            self.evaluated += 1
        elif record.status == "failed":
            self.failures += 1
        elif record.status == "duplicate":
            self.duplicates += 1
        else:
            self.invalid += 1
        self.evaluations += record.evaluations or 0


def _record(sample: int, batch: int, island: int, parents: list[str], generation: Generation) -> SampleRecord:
    """A sample's row before its outcome is known."""
    return SampleRecord(
        sample=sample, batch=batch, status="invalid", island=island, parent_keys=parents,
        generator=generation.generator, raw=generation.text, generation_seconds=generation.seconds,
        prompt_tokens=generation.prompt_tokens, completion_tokens=generation.completion_tokens,
    )


def _describe_program(record: SampleRecord, program: ParametricProgram) -> None:
    record.key, record.skeleton, record.initial_params = program.key, program.skeleton, list(program.values)


def _program_seed(seed: int, sample: int) -> int:
    return int(np.random.SeedSequence([seed, sample + 1]).generate_state(1)[0])


class Search:
    def __init__(self, cfg: SearchConfig, run_dir: Path, observers: tuple[SearchObserver, ...] = ()):
        self.cfg = cfg
        self.observers = observers
        self.spec: Spec = load_task_spec(cfg.task.spec)
        self.run_dir = Path(cfg.resume).expanduser().resolve() if cfg.resume else run_dir
        self.store = self._open_store()
        self.seeds = episode_seeds(cfg.seed, cfg.task.episodes)
        self.counters = Counters()
        self.best_so_far: list[list[float]] = []
        self.next_sample = 0
        self.next_batch = 0
        self.in_flight_samples = 0
        self.generation_seconds = 0.0
        self.stop_reason = ""
        self.pool = make_executor(cfg.executor)
        in_flight_programs = cfg.llm.batch_size * cfg.search.queue_size
        self.program_threads = concurrent.futures.ThreadPoolExecutor(in_flight_programs, thread_name_prefix="colmo-program")
        self.generator = None
        self.probe: ProgramProbe | None = None
        self.start = time.perf_counter()
        self.database: ProgramDatabase | None = None

    # -- set-up and resume ------------------------------------------------------------------

    def _open_store(self) -> ProgramStore:
        if self.cfg.resume:
            return open_for_resume(self.run_dir, self.cfg.task.name)
        self.run_dir.mkdir(parents=True, exist_ok=True)
        store = ProgramStore(self.run_dir / STORE_FILE)
        store.set_meta(task=self.cfg.task.name, spec=str(self.spec.path), seed=self.cfg.seed)
        return store

    def _evaluate_starter(self) -> StoredProgram:
        records = [r for r in self.store.records() if r.sample == STARTER_SAMPLE]
        if records:
            starter = records[0]
        else:
            program = parametrize(self.spec.starter_code)
            result = self._optimize(program, STARTER_SAMPLE)
            if result.failure:
                raise ConfigError(f"the starter policy in {self.spec.path} fails: {result.failure}")
            starter = _record(STARTER_SAMPLE, -1, -1, [], Generation(self.spec.starter_code, "spec"))
            _describe_program(starter, program)
            self._settle(starter, program, result)
            self.store.add(starter)
        return StoredProgram(starter.key, starter.code, starter.score, 0, STARTER_SAMPLE)

    def _replay(self) -> None:
        """Rebuild the database and counters from the store of an earlier run."""
        batch = None
        for record in self.store.records():
            if record.sample == STARTER_SAMPLE:
                continue
            if batch is not None and record.batch != batch:
                self.database.on_sample(self.counters.samples)
            batch = record.batch
            self._apply(record)
            self.next_sample = record.sample + 1
            self.next_batch = record.batch + 1
        if batch is not None:
            self.database.on_sample(self.counters.samples)
        if self.counters.samples:
            log.info("resumed %s: %d samples, best %.2f", self.run_dir, self.counters.samples, self.database.best.score)

    # -- the loop ----------------------------------------------------------------------------

    def run(self) -> dict[str, Any]:
        try:
            starter = self._evaluate_starter()
            self.database = ProgramDatabase(self.cfg.database, starter, self.cfg.seed)
            self.best_so_far = [[0, starter.score]]
            self._replay()
            self.probe = ProgramProbe(
                self.spec, self.cfg.task.env, self.seeds[0], min(self.cfg.executor.timeout_s, _PROBE_TIMEOUT_S),
                self.cfg.executor.memory_mb,
            ) if self.cfg.llm.name == "mutate" else None
            self.generator = make_generator(self.cfg.llm, self.cfg.seed, self.probe)
            self._loop()
        except KeyboardInterrupt:
            self.stop_reason = "interrupted"
            self.pool.close(cancel=True)
            self.program_threads.shutdown(wait=False, cancel_futures=True)
        finally:
            if not self.pool.closed:
                self.pool.close()
            self.program_threads.shutdown(wait=False, cancel_futures=True)
            if self.generator is not None:
                self.generator.close()
            if self.probe is not None:
                self.probe.close()
        summary = self.summary()
        write_outputs(summary, self.run_dir)
        for observer in self.observers:
            observer.on_finish(summary)
        self.store.close()
        return summary

    def _loop(self) -> None:
        in_flight: deque[_Batch] = deque()
        while True:
            while not self.stop_reason and len(in_flight) < self.cfg.search.queue_size and self._samples_left() > 0:
                batch = self._generate()
                if batch is not None:
                    in_flight.append(batch)
            if not in_flight:
                self.stop_reason = self.stop_reason or "max_samples"
                return
            self._integrate(in_flight.popleft())
            self._check_stop()

    def _samples_left(self) -> int:
        return self.cfg.search.max_samples - self.counters.samples - self.in_flight_samples

    def _check_stop(self) -> None:
        limits = self.cfg.search
        if limits.target_score is not None and self.database.best.score >= limits.target_score:
            self.stop_reason = self.stop_reason or "target_score"
        if limits.max_seconds and time.perf_counter() - self.start >= limits.max_seconds:
            self.stop_reason = self.stop_reason or "max_seconds"
        if self.counters.samples >= limits.max_samples:
            self.stop_reason = self.stop_reason or "max_samples"

    def _generate(self) -> Optional[_Batch]:
        selection = self.database.select()
        prompt = build_prompt(self.spec.description, selection)
        n = min(self.cfg.llm.batch_size, self._samples_left())
        started = time.perf_counter()
        try:
            generations = self.generator.generate(prompt, n)
        except GeneratorError as error:
            log.error("generator stopped: %s", error)
            self.stop_reason = f"generator failed: {error}"
            return None
        seconds = time.perf_counter() - started
        self.generation_seconds += seconds
        batch = _Batch(self.next_batch, prompt, seconds, time.perf_counter())
        self.next_batch += 1
        for generation in generations:
            record = _record(self.next_sample, batch.index, prompt.island, list(prompt.parent_keys), generation)
            self.next_sample += 1
            self.in_flight_samples += 1
            batch.pending.append(self._submit(record, generation))
        return batch

    def _submit(self, record: SampleRecord, generation: Generation) -> _Pending:
        try:
            program = parametrize(extract_policy(generation.text))
        except (ExtractionError, ProgramError) as error:
            record.failure = f"unusable output: {error}"
            return self._settled(record)
        _describe_program(record, program)
        if self.database.is_known(program.key):
            record.status = "duplicate"
            return self._settled(record)
        # Known from now on, so a batch generated before this one is integrated skips it too.
        self.database.mark_seen(program.key)
        try:
            check_program(program.skeleton, self.spec.allowed_imports)
        except ForbiddenProgram as error:
            record.status, record.failure = "failed", str(error)
            return self._settled(record)
        return _Pending(record, program, self.program_threads.submit(self._evaluate, record, program))

    def _settled(self, record: SampleRecord) -> _Pending:
        self.store.add(record)
        return _Pending(record)

    def _optimize(self, program: ParametricProgram, sample: int) -> ProgramResult:
        evaluate = batch_evaluator(self.pool, self.spec, self.cfg.task.env, self.seeds, program.skeleton)
        return optimize_program(program, evaluate, self.cfg.gfo, _program_seed(self.cfg.seed, sample))

    def _evaluate(self, record: SampleRecord, program: ParametricProgram) -> None:
        """Optimize and score one program, and store it, before its future completes: whatever
        waits on the future then sees the settled record."""
        self._settle(record, program, self._optimize(program, record.sample))
        self.store.add(record)

    @staticmethod
    def _settle(record: SampleRecord, program: ParametricProgram, result: ProgramResult) -> None:
        record.status = "failed" if result.failure else "evaluated"
        record.code, record.params = result.code, list(result.params)
        record.initial_score = result.initial.score if math.isfinite(result.initial.score) else None
        record.score = result.score if math.isfinite(result.score) else None
        record.returns, record.evaluations = list(result.evaluation.returns), result.evaluations
        record.failure, record.evaluation_seconds = result.failure, result.seconds

    def _integrate(self, batch: _Batch) -> None:
        for pending in batch.pending:
            if pending.future is not None:
                pending.future.result()  # settled and stored; an exception here is a bug
            self._apply(pending.record)
        self.in_flight_samples -= len(batch.pending)
        reset = self.database.on_sample(self.counters.samples)
        if reset:
            log.info("reset islands %s", reset)
        report = self._report(batch)
        log.info(
            "batch %d: samples %d, best %.2f, gen %.1f s, eval %.1f s, evals/s %.1f",
            batch.index, report["samples"], report["best_score"], report["generation_seconds"],
            report["evaluation_seconds"], report["evaluations_per_second"],
        )
        for observer in self.observers:
            observer.on_batch(report, [p.record for p in batch.pending])

    def _apply(self, record: SampleRecord) -> None:
        """Count one settled sample and register it in the database, in sample order."""
        self.counters.count(record)
        if record.status == "evaluated":
            before = self.database.best.score
            self.database.register(StoredProgram(record.key, record.code, record.score, record.island, record.sample))
            if self.database.best.score > before:
                self.best_so_far.append([self.counters.samples, self.database.best.score])
        elif record.key:
            self.database.mark_seen(record.key)

    def _report(self, batch: _Batch) -> dict[str, Any]:
        wall = time.perf_counter() - self.start
        return {
            "batch": batch.index,
            "samples": self.counters.samples,
            "best_score": self.database.best.score,
            "best_per_island": list(self.database.best_per_island),
            "programs_evaluated": self.counters.evaluated,
            "duplicates": self.counters.duplicates,
            "failures": self.counters.failures + self.counters.invalid,
            "generation_seconds": batch.generation_seconds,
            "evaluation_seconds": time.perf_counter() - batch.started,
            "queue_depth": self.next_batch - batch.index - 1,
            "evaluations_per_second": self.counters.evaluations / wall,
            **self._busy_fractions(wall),
        }

    def _busy_fractions(self, wall: float) -> dict[str, float]:
        """Fractions of the wall time the generator, and the evaluation workers, were busy."""
        if not wall:
            return {"generator_busy": 0.0, "evaluator_busy": 0.0}
        return {
            "generator_busy": self.generation_seconds / wall,
            "evaluator_busy": self.pool.busy_seconds / (wall * self.pool.n_workers),
        }

    def summary(self) -> dict[str, Any]:
        wall = time.perf_counter() - self.start
        best = self.database.best if self.database else None
        return {
            "task": self.cfg.task.name,
            "best_score": best.score if best else None,
            "best_key": best.key if best else None,
            "best_code": best.code if best else None,
            "samples": self.counters.samples,
            "programs_evaluated": self.counters.evaluated,
            "duplicates_skipped": self.counters.duplicates,
            "failures": self.counters.failures + self.counters.invalid,
            "unusable_outputs": self.counters.invalid,
            "evaluations": self.counters.evaluations,
            "seconds": round(wall, 3),
            **{name: round(value, 4) for name, value in self._busy_fractions(wall).items()},
            "best_so_far": self.best_so_far,
            "stop_reason": self.stop_reason,
            "run_dir": str(self.run_dir),
        }


def write_outputs(summary: dict[str, Any], run_dir: Path) -> None:
    """`summary.json` and the best policy as a readable `.py` file, in the run directory."""
    (run_dir / SUMMARY_FILE).write_text(json.dumps(summary, indent=2))
    if summary["best_code"]:
        header = f"# colmo best policy for {summary['task']}: score {summary['best_score']:.2f} after {summary['samples']} samples\n"
        (run_dir / BEST_POLICY_FILE).write_text(header + summary["best_code"])
