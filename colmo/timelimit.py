"""A search's time: the limit `search.max_seconds`, counted from the start of the run's job (a
single run's process, imports and Hydra included; each job of a `-m` sweep from its own start,
whichever launcher runs it: `job_start`), less what a resumed run's earlier processes took; the search's own deadline, early enough to leave the programs in
flight their final scores and the finish its held-out scores, simplification and video
(`colmo.finish_plan.plan_finish`, from the starter's calibration); and the run's estimated
duration, said in one line before the first batch with the limit that binds, from the starter's
tuning, then again once samples settle, from the time they took (`follow_samples`: generation,
tuning and waiting included), and whenever that estimate moves by more than 30%.

The deadline depends on how many programs are being tuned: each one in flight at the deadline
still ends its candidate and scores its rounded constants on the fast path and by the referee.
So the reserve is for the programs actually in flight, not for a full queue, and a batch is only
generated (its generation abandoned otherwise) while the run can still drain it
(`can_start`): near the end the queue empties instead of the whole run stopping a full queue's
drain early.

What the drain and the finish cost is measured on the programs themselves: each program's
final scores (`observe`: the worker seconds of its rounded constants' fast-path and referee
evaluations, and the referee's alone), the median of the last few, the starter's first; the
finish's referee evaluations are the starter's calibration (its fast path: the episodes' own
cost; the referee's excess: a lockstep batch's round trips) scaled by how much dearer the
programs' referee evaluations are. Until a program is in, the calibration stands in, scaled by
how much slower the workers' recent evaluations run than the calibration's (`load_factor`, at
least 1): a calibration is a few seconds of a machine whose load changes.
"""

from __future__ import annotations

import logging
import math
import os
import statistics
import threading
import time
from collections import deque
from pathlib import Path
from typing import Callable, Optional, Sequence

from colmo.config import LanguageModelConfig, SearchConfig
from colmo.evaluation import Executor
from colmo.finish_plan import FINISH_SHARE, SAFETY, FinishPlan, RefereeCost, plan_finish
from colmo.optimize.tune import ProgramResult
from colmo.record import Totals

log = logging.getLogger("colmo.search")

# The finish ends this long before the limit: writing the summary, closing the workers and leaving
# the process took up to 6.5 s on 2 loaded cores, which this and the 5 s a run may take past its limit cover.
_CLOSE_S = 1.5
_STARTER_SHARE = 1 / 3  # of the time limit, at most, for the starter's tuning before the search
_LOAD_EVERY_S = 1.0  # how often the deadline follows the workers' speed
_LOAD_WINDOW = 8  # evaluations per worker over which their recent speed is measured
_OBSERVED = 8  # programs whose final scores say what the next ones' will cost
_RESAY = 0.3  # an estimate of the search's end is said again when it moves by more than this share


def programs_per_batch(cfg: SearchConfig) -> int:
    """The programs one generation adds: `llm.batch_size`, or one with `search.steady_state`."""
    return 1 if cfg.search.steady_state else cfg.llm.batch_size


def program_slots(cfg: SearchConfig, workers: int) -> int:
    """The programs `workers` tune at once: one per `gfo.workers` workers, at least one."""
    return max(1, workers // cfg.gfo.workers)


def programs_at_once(cfg: SearchConfig, workers: int) -> int:
    """The most programs a search has in flight: `search.queue_size` batches, or with
    `search.steady_state` one per program slot and `search.steady_queue` more."""
    if cfg.search.steady_state:
        return program_slots(cfg, workers) + cfg.search.steady_queue
    return cfg.llm.batch_size * cfg.search.queue_size


class TimeBudget:
    """The time of one search from `start` (`time.perf_counter()`) to `end`, its limit (inf
    without `search.max_seconds`), and the search's `deadline` in between: until the starter's
    calibration tells what the finish costs (`plan`), a third of the time at most; then early
    enough for the finish and the drain of the `programs_in_flight()` at the workers' current speed."""

    def __init__(
        self, max_seconds: float, programs_in_flight: Callable[[], int] = lambda: 0, started: Optional[float] = None, tuned: bool = True,
        spent: float = 0.0,
    ):
        """`started`: when the limit began (`time.perf_counter()`: the job's start, `job_start`; default: now);
        `tuned`: whether programs are tuned (their final scores are then a fast-path and a
        referee evaluation, not the referee's alone); `spent`: seconds of the limit a resumed
        run's earlier processes took (the store's `Elapsed`): the limit is the whole run's, as
        `search.max_samples` is, so a run stopped and resumed gets what a run never stopped gets."""
        self.max_seconds = max_seconds
        self.tuned = tuned
        self.programs_in_flight = programs_in_flight  # programs being tuned now (the search's program threads)
        self.start = time.perf_counter()
        self._job_start = self.start if started is None else started
        # A run resumed past its limit gets a second: it ends at once, its finish cut to the least.
        self.end = self._job_start + max(max_seconds - spent, 1.0) if max_seconds else math.inf
        if max_seconds and spent:
            log.info(
                "resumed after %s of the run's search.max_seconds=%g: %s left", duration(spent), max_seconds, duration(max(max_seconds - spent, 0.0)),
            )
        self._searching: Optional[float] = None  # when the first batch began (`search_starts`)
        self._stopped: Optional[float] = None  # when the search stopped (`search_stops`)
        self._starter_deadline = self.start + _STARTER_SHARE * (self.end - self.start)
        self.calibration = RefereeCost(0.0, 0.0)  # the starter's referee cost, from its calibration
        self._calibration_referee = 0.0  # the calibration's referee evaluation, worker seconds
        # When the search ends by max_samples, in seconds from `start`: from the starter's tuning
        # (`plan`), then from the samples settled (`follow_samples`); None while nothing tells.
        self.estimated_seconds: Optional[float] = None
        self._said: Optional[tuple[float, float]] = None  # when an estimate of the search's end was last said, and that end
        # A language model's run, until its first batch is generated: (a program's tuning, programs tuned at a time, whether
        # generation overlaps tuning, search.max_samples), for the estimate from the model's first calls (`follow_generation`).
        self._model_first: Optional[tuple[float, int, bool, int]] = None
        self.load_factor = 1.0  # the workers' recent seconds per evaluation over the calibration's
        self._lock = threading.Lock()
        self._executor: Optional[Executor] = None
        self._reference = 0.0  # seconds per evaluation until the plan (calibration, the starter's tuning)
        self._recent: deque[tuple[int, float]] = deque()  # (evaluations, busy seconds) of the executor
        self._followed = 0.0  # when the deadline last followed the workers' speed
        self._cfg: Optional[SearchConfig] = None
        self._calibration = 0.0  # worker seconds of the starter's fast and referee evaluations
        self._scoring: deque[float] = deque(maxlen=_OBSERVED)  # recent programs' final scores, worker seconds
        self._referee: deque[float] = deque(maxlen=_OBSERVED)  # and their referee evaluations' alone
        self._finish_seconds = 0.0  # the finish's plan at the workers' current speed
        self._available = 0.0  # for the finish, at the calibration's speed

    def elapsed(self) -> float:
        """Seconds since the search started in this process."""
        return time.perf_counter() - self.start

    @property
    def limit_seconds(self) -> float:
        """The run's time limit counted from the search's start; 0 without one."""
        return self.end - self.start if math.isfinite(self.end) else 0.0

    @property
    def finish_referee_cost(self) -> RefereeCost:
        """The referee's cost at the workers' current speed, for the programs the search makes:
        what `colmo.finish` plans with."""
        if self._referee and self._calibration_referee > 0:
            return self.calibration.scaled(statistics.median(self._referee) / self._calibration_referee)
        return self.calibration.scaled(self.load_factor)

    def _scoring_seconds(self) -> float:
        """Worker seconds a program costs once its tuning stops: its final scores."""
        if self._scoring:
            return statistics.median(self._scoring)
        return self._calibration * self.load_factor

    def observe(self, result: ProgramResult) -> None:
        """A program's final scores, as the workers measured them now: what the next programs'
        and the finish's will cost. Thread-safe."""
        if result.failure or not result.evaluation.returns or result.scoring_seconds <= 0:
            return
        if self.tuned and result.evaluations == 1:  # nothing to tune (the starter's zeros): the referee's score alone
            return
        with self._lock:
            self._scoring.append(result.scoring_seconds)
            self._referee.append(result.evaluation.seconds)
            if self._executor is not None:
                self._plan_finish()

    @property
    def deadline(self) -> float:
        """When the programs in flight now must stop tuning (`time.perf_counter()`)."""
        return self.deadline_with(0)

    def deadline_with(self, more_programs: int) -> float:
        """The deadline were `more_programs` more programs in flight: the finish and the drain of
        every program in flight before the end. Before the plan, a share of the time for the starter."""
        if self._executor is None:
            return self._starter_deadline
        programs = self.programs_in_flight() + more_programs
        if not programs:
            return self.end - self._finish_seconds
        # Each worker ends its candidate (about half a program's final scores: one fast-path
        # evaluation, often raced short), then scores its programs' final constants one after another.
        rounds = math.ceil(programs / self._executor.n_workers)
        return self.end - self._finish_seconds - SAFETY * self._scoring_seconds() * (0.5 + rounds)

    def past_deadline(self) -> bool:
        """Whether the programs in flight must stop (at their next candidate); thread-safe."""
        self._follow()
        return time.perf_counter() >= self.deadline

    def can_start(self, programs: int) -> bool:
        """Whether `programs` more programs could be tuned and drained before the finish: a batch
        that cannot is not generated (or its generation is abandoned)."""
        self._follow()
        return time.perf_counter() < self.deadline_with(programs)

    def programs_that_fit(self, most: int) -> int:
        """How many more programs, up to `most`, could be tuned and drained before the finish."""
        return next((programs for programs in range(most, 0, -1) if self.can_start(programs)), 0)

    def _follow(self) -> None:
        now = time.perf_counter()
        if self._executor is not None and now - self._followed >= _LOAD_EVERY_S:
            with self._lock:
                if now - self._followed >= _LOAD_EVERY_S:
                    self._followed = now
                    self._follow_load()

    def plan(self, cfg: SearchConfig, calibration: tuple[float, float], program_seconds: float, executor: Executor) -> None:
        """The run's duration estimated from the starter's calibration (worker seconds of its
        fast-path and referee evaluations on the training episodes) and tuning
        (`program_seconds`), the search's deadline set to leave the finish and the programs in
        flight their time, both said in one line; from then on the deadline follows `executor`'s speed."""
        workers = executor.n_workers
        self.calibration = RefereeCost.of(*calibration, cfg.task.episodes)
        self._calibration_referee = calibration[1]
        self._reference = executor.busy_seconds / executor.evaluations_done if executor.evaluations_done else 0.0
        in_parallel = min(programs_at_once(cfg, workers), program_slots(cfg, workers))
        search = cfg.search.max_samples * program_seconds / in_parallel if program_seconds else None
        self.estimated_seconds = None if search is None else self.elapsed() + search
        if isinstance(cfg.llm, LanguageModelConfig) and program_seconds:
            self._model_first = (program_seconds, in_parallel, cfg.search.queue_size > 1, cfg.search.max_samples)
        plan = plan_finish(cfg, self.calibration, workers)
        limit = "max_samples"
        if self.max_seconds:
            self._calibration = sum(calibration)  # the starter's two evaluations, as a program's final scores are
            self._cfg, self._executor, self._available = cfg, executor, FINISH_SHARE * max(self.end - time.perf_counter(), 0.0)
            self._recent.append((executor.evaluations_done, executor.busy_seconds))
            plan = self._plan_finish()
            limit = f"max_seconds={self.max_seconds:g}"
            if search is None:
                limit = f"max_samples={cfg.search.max_samples} or {limit}, whichever comes first"
            elif self.deadline_with(programs_per_batch(cfg)) - time.perf_counter() >= search:
                limit = "max_samples"
        early = ""
        if "max_seconds" in limit:
            early = f" (search stops {duration(self.end - self.deadline_with(programs_per_batch(cfg)))} early to finish)"
            if not self.can_start(1):
                early = " (no time left to search: the finish works on the starter)"
        if search is None:
            what = "estimated once the first samples are in (the starter has no constants to tune: its time says nothing of a program's)"
        else:
            # A model's calls and its duplicates are not known before its first answers.
            unknown = ", if every answer is a new program; the model's calls come on top: measured on the first samples"
            assumed = unknown if isinstance(cfg.llm, LanguageModelConfig) else ""
            what = f"{duration(search)} ({cfg.search.max_samples} samples x {program_seconds:.1f} s of tuning, {in_parallel} at a time{assumed})"
        log.info("estimated duration: search %s, finish %s; limit that binds: %s%s", what, duration(plan.seconds), limit, early)

    def follow_samples(
        self, totals: Totals, resumed_samples: int, max_samples: int, settled: tuple[int, float], in_flight: Sequence[tuple[int, float]],
        now: Optional[float] = None,
    ) -> None:
        """The search's end re-estimated as a batch settles (`settled`: its samples and when its
        generation began, `time.perf_counter()`; `in_flight`: the batches still evaluating,
        likewise; `totals.samples` settled so far, `resumed_samples` of them in an earlier
        process). The pace is Little's law: the samples in the pipeline (the batch and those
        still in flight) over the batch's time in it, generation, tuning and waiting included, so
        that the samples that started beside it count as well as those that finished with it.
        The time left is the samples not started yet at that pace, or the end of those in flight,
        whichever is later; where the time limit comes first, the line says the search's time
        left and what the samples would take. Said in one line the first time and whenever the
        end moves by more than 30%, with what the model calls take. `now`: `time.perf_counter()` unless given."""
        if self._searching is None or totals.samples - resumed_samples < 1:
            return
        now = time.perf_counter() if now is None else now
        size, began = settled
        in_system = now - began
        flying = sum(count for count, _ in in_flight)
        per_sample = in_system / (size + flying)
        left = max(max(max_samples - totals.samples - flying, 0) * per_sample, max((start + in_system - now for _, start in in_flight), default=0.0))
        end, binds = self._end(now, left, max_samples)
        if self._said is not None and abs(end - self._said[1]) <= _RESAY * max(self._said[1] - self._said[0], per_sample):
            return
        self._said = (now, end)
        model = ""
        if totals.tokens_per_second:  # a language model: what its calls take
            model = f", model calls {totals.generator_busy * totals.seconds / totals.samples:.0f} s each at {totals.tokens_per_second:.1f} tokens/s"
        log.info(
            "estimated duration after %d samples: search %s more (%.1f s a sample%s); limit that binds: %s",
            totals.samples, duration(end - now), per_sample, model, binds,
        )

    def follow_generation(self, samples_left: int, calls: int, seconds: float, to_tune: int, now: Optional[float] = None) -> None:
        """The search's end estimated once a language model's first batch is generated (its
        `calls` in `seconds`, `to_tune` of their answers new programs; `samples_left` of
        `search.max_samples`, which counts model calls, not started yet), before any sample
        settles: the plan's line could not know what the model's calls take, nor how many answers
        are duplicates (asked again, each call a sample) that are never tuned. A sample takes its
        call and its share of tuning, or the longer of the two where batches queue (generation
        then overlaps tuning); the last batch's tuning comes on top. Said once; `follow_samples`
        takes over when samples settle."""
        if self._model_first is None or self._said is not None or not calls:
            return
        program_seconds, in_parallel, overlaps, max_samples = self._model_first
        self._model_first = None
        now = time.perf_counter() if now is None else now
        call = seconds / calls
        tuning = program_seconds * to_tune / calls / in_parallel
        per_sample = max(call, tuning) if overlaps else call + tuning
        left = samples_left * per_sample + tuning * calls
        end, binds = self._end(now, left, max_samples)
        self._said = (now, end)
        log.info(
            "estimated duration after the model's first %d calls: search %s more (%.1f s a sample: a call %.1f s, %d new programs "
            "of %d calls tuned, %.1f s each, %d at a time); limit that binds: %s",
            calls, duration(end - now), per_sample, call, to_tune, calls, program_seconds, in_parallel, binds,
        )

    def _end(self, now: float, left: float, samples: int) -> tuple[float, str]:
        """When the search ends if `left` more seconds take its `samples` to the end, and the
        limit that binds; `estimated_seconds` set to match."""
        self.estimated_seconds = now - self.start + left
        if self.max_seconds and now + left > self.deadline:
            return max(self.deadline, now), f"max_seconds={self.max_seconds:g} ({samples} samples would take {duration(left)})"
        return now + left, "max_samples"

    def _plan_finish(self) -> FinishPlan:
        """The finish planned at the workers' current speed; the deadlines leave it its time."""
        plan = plan_finish(self._cfg, self.finish_referee_cost, self._executor.n_workers, self._available)
        self._finish_seconds = plan.seconds
        return plan

    def _follow_load(self) -> None:
        """`load_factor` from the executor's last `_LOAD_WINDOW` evaluations per worker, and the
        deadline moved to match."""
        done, busy = self._executor.evaluations_done, self._executor.busy_seconds
        self._recent.append((done, busy))
        window = _LOAD_WINDOW * self._executor.n_workers
        while len(self._recent) > 2 and self._recent[1][0] <= done - window:
            self._recent.popleft()
        first_done, first_busy = self._recent[0]
        if done - first_done < window / 2 or self._reference <= 0:
            return
        factor = max(1.0, (busy - first_busy) / (done - first_done) / self._reference)
        if abs(factor - self.load_factor) >= 0.1:
            self.load_factor = factor
            self._plan_finish()
            log.debug("the workers run %.1fx slower than calibrated: the search stops at %.0f s", factor, self.deadline - self.start)

    def search_starts(self) -> None:
        """The start-up is over: the first batch begins."""
        self._searching = time.perf_counter()

    def search_stops(self) -> None:
        self._stopped = time.perf_counter()

    def phases(self) -> tuple[float, float]:
        """Seconds of start-up (from the job's start to the first batch, or to the stop of a run
        that never searched) and of search (from the first batch to the stop)."""
        stopped = self._stopped or time.perf_counter()
        if self._searching is None:
            return stopped - self._job_start, 0.0
        return self._searching - self._job_start, stopped - self._searching

    def finish_by(self) -> float:
        """When the work on the best programs must end (`time.monotonic()`): with a time limit,
        in time to write the summary and close the workers by its end."""
        if not self.max_seconds:
            return math.inf
        return time.monotonic() + max(self.end - _CLOSE_S - time.perf_counter(), 0.0)


def duration(seconds: Optional[float]) -> str:
    """`12m05s`, `3h20m`; `?` for an unknown or endless duration."""
    if seconds is None or not math.isfinite(seconds):
        return "?"
    minutes, secs = divmod(int(seconds), 60)
    return f"{minutes // 60}h{minutes % 60:02d}m" if minutes >= 60 else f"{minutes}m{secs:02d}s"


def job_start(sweep_job: bool) -> float:
    """When a job's `search.max_seconds` began (`time.perf_counter()`): a single run's at the
    process's start, so that the process ends by its limit; a sweep job's now, at the start of
    its own work, since the jobs of a sweep may share one process (Hydra's basic launcher, the
    joblib launcher's reused workers) and each must have the whole limit to itself."""
    now = time.perf_counter()
    return now if sweep_job else now - process_seconds()


def process_seconds() -> float:
    """Seconds since this process started (Linux's /proc); 0 where that is not known."""
    try:
        ticks = int(Path("/proc/self/stat").read_text().rsplit(")", 1)[1].split()[19])
        return max(time.clock_gettime(time.CLOCK_BOOTTIME) - ticks / os.sysconf("SC_CLK_TCK"), 0.0)
    except (OSError, ValueError, IndexError, AttributeError):
        return 0.0
