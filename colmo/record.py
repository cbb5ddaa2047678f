"""What a search records: one immutable `SampleRecord` per generated sample, built once its
outcome is known, and the typed progress reports made from them (`BatchReport` after every
batch, `Summary` at the end), and who receives them (`SearchObserver`).

A sample's status is one of:
- `evaluated`: the program ran; `score` is the referee's mean return over the training episodes;
- `failed`: the program was refused by the static check or failed when it ran (`failure` says how);
- `duplicate`: its program was evaluated before (with GFO: its structure, i.e. programs differing only
  in constants; with `gfo=none`: the same code and constants), and so were its regenerations;
- `unusable`: no program could be read from the generator's output (`failure` says why);
- `interrupted`: the search stopped before the sample was evaluated; resume evaluates it.
"""

from __future__ import annotations

import collections
import math
import os
import time
from dataclasses import asdict, astuple, dataclass, field, replace
from typing import TYPE_CHECKING, Any, Mapping, Optional, Protocol

from colmo.generate.base import Generation, PromptForm

if TYPE_CHECKING:
    from colmo.optimize.tune import ProgramResult
    from colmo.program import ParametricProgram

EVALUATED, FAILED, DUPLICATE, UNUSABLE, INTERRUPTED = "evaluated", "failed", "duplicate", "unusable", "interrupted"
# Generated, its outcome not stored yet: a run that stops (or is killed) before the outcome lands
# leaves it pending, and a resumed run evaluates it, as it does an interrupted one.
PENDING = "pending"
TO_EVALUATE_AGAIN = (INTERRUPTED, PENDING)
FINISHED = ("max_samples", "max_seconds", "stop_at_score")  # the stop reasons of a run that reached its limits


@dataclass(frozen=True)
class Sample:
    """A generated sample before its outcome is known: where it comes from."""

    index: int
    batch: int
    island: int
    parent_keys: tuple[str, ...]
    generation: Generation


def generator_label(generator: str) -> str:
    """What reports split a search by: a sample's generator up to the first colon (`llamacpp:<model>` is `llamacpp`)."""
    return generator.split(":", 1)[0]


def finite_or_none(value: float) -> Optional[float]:
    """JSON has no infinity: a failed score is stored and reported as null."""
    return value if math.isfinite(value) else None


@dataclass(frozen=True)
class SampleRecord:
    sample: int
    batch: int
    status: str
    island: int
    parent_keys: tuple[str, ...]
    generator: str
    raw: str  # the generator's output as it came (a completion's continuation: prompt_prefix + raw)
    prompt_prefix: str = ""
    prompt_shown: str = ""  # the code a chat answer's prompt showed, which it may call (`Generation.shown`)
    key: Optional[str] = None
    skeleton: Optional[str] = None
    code: Optional[str] = None  # readable code with the final constants inlined
    initial_params: Optional[tuple[float, ...]] = None
    params: Optional[tuple[float, ...]] = None
    initial_score: Optional[float] = None
    score: Optional[float] = None
    returns: Optional[tuple[float, ...]] = None  # per training episode, measured by the referee
    coverage: Optional[tuple[tuple[int, int, int], ...]] = None  # per branch site, as its referee counted them (`colmo.coverage`)
    heldout_score: Optional[float] = None
    evaluations: int = 0
    steps: int = 0  # control steps simulated for this sample
    raced_out: int = 0
    cut_short: bool = False  # the search's deadline or an interruption stopped its tuning
    lines: Optional[int] = None
    nodes: Optional[int] = None
    n_params: Optional[int] = None
    failure: Optional[str] = None
    generation_seconds: float = 0.0
    evaluation_seconds: float = 0.0
    prompt_tokens: int = 0
    completion_tokens: int = 0
    model_calls: int = 1  # its answer and the duplicates generated before it (`search.duplicate_retries`)
    created: float = field(default_factory=time.time)

    @classmethod
    def of(
        cls, sample: Sample, status: str, program: Optional["ParametricProgram"] = None, failure: Optional[str] = None,
    ) -> "SampleRecord":
        """The record of `sample` settled as `status` before or without an evaluation, with the
        program it holds if one could be read."""
        generation = sample.generation
        fields: dict[str, Any] = dict(
            sample=sample.index, batch=sample.batch, status=status, island=sample.island, parent_keys=tuple(sample.parent_keys),
            generator=generation.generator, raw=generation.text, prompt_prefix=generation.prefix, prompt_shown=generation.shown,
            generation_seconds=generation.seconds, prompt_tokens=generation.prompt_tokens,
            completion_tokens=generation.completion_tokens, model_calls=generation.calls, failure=failure,
        )
        if program is not None:
            fields.update(key=program.key, skeleton=program.skeleton, initial_params=tuple(program.values), n_params=program.n_params)
        return cls(**fields)

    @classmethod
    def of_result(cls, sample: Sample, program: "ParametricProgram", result: "ProgramResult") -> "SampleRecord":
        """The record of `sample` whose `program` ran: `evaluated`, or `failed` if `result` says so."""
        settled = cls.of(sample, FAILED if result.failure else EVALUATED, program, result.failure)
        return replace(
            settled, code=result.code, params=tuple(result.params), initial_score=finite_or_none(result.initial.score),
            score=finite_or_none(result.score), returns=tuple(result.evaluation.returns), coverage=result.evaluation.coverage,
            evaluations=result.evaluations,
            steps=result.steps, raced_out=result.raced_out, cut_short=result.cut_short, evaluation_seconds=result.seconds,
            lines=result.size.lines, nodes=result.size.nodes,
        )

    def as_sample(self) -> Sample:
        """The generated sample this record was made from (`of`'s inverse: a resumed run evaluates it again)."""
        # Stored as its two contexts, of which a generation has at most one.
        form = PromptForm.COMPLETION if self.prompt_prefix else PromptForm.CHAT if self.prompt_shown else PromptForm.CODE
        generation = Generation(
            self.raw, self.generator, self.prompt_tokens, self.completion_tokens, self.generation_seconds, self.model_calls, form,
            self.prompt_prefix or self.prompt_shown,
        )
        return Sample(self.sample, self.batch, self.island, self.parent_keys, generation)

    def as_row(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class Totals:
    """What a search has done so far, as every report says it: the progress display, each
    `BatchReport` (what trackers log) and the `Summary` (made by `Counters.totals`, only there)."""

    samples: int  # model calls: each answer, the regenerated duplicates included
    programs_evaluated: int
    duplicates_skipped: int
    failures: int
    unusable_outputs: int
    interrupted: int
    evaluations: int
    steps: int  # control steps simulated
    valid_program_rate: float  # evaluated / (samples - duplicates - interrupted)
    duplicate_rate: float  # answers that were duplicates, of all model calls
    tokens_per_second: float
    evaluations_per_second: float
    generator_busy: float  # fractions of the wall time
    evaluator_busy: float
    seconds: float
    worker_seconds: float  # the evaluation workers' busy seconds, summed over workers: the compute evaluations took
    # Control steps simulated per busy worker-second: how fast this machine, at its load, ran the
    # task's episodes (and the programs in them); two runs of a task tell a slower machine by it.
    steps_per_worker_second: float
    # The machine's mean load average over the run, its own processes included
    # (`colmo.load.LoadMeter`): what a timed result was measured under; 0 where unknown.
    load: float


@dataclass(frozen=True)
class BatchReport(Totals):
    """The search's state after a batch is integrated (what trackers log, at step = samples)."""

    batch: int
    best_score: float
    best_per_island: tuple[float, ...]
    generation_seconds: float
    evaluation_seconds: float
    queue_depth: int

    def metrics(self) -> dict[str, float]:
        """The numeric fields that are metrics (the batch index and samples are the step)."""
        values = {name: float(value) for name, value in asdict(self).items() if name not in ("batch", "samples", "best_per_island")}
        values.update({f"best_score_island_{i}": score for i, score in enumerate(self.best_per_island)})
        return values


@dataclass(frozen=True)
class Summary(Totals):
    """A finished (or stopped) search: what `summary.json` holds."""

    task: str
    best_score: Optional[float]
    best_heldout_score: Optional[float]
    best_key: Optional[str]
    best_code: Optional[str]
    best_so_far: tuple[tuple[int, float], ...]
    stop_reason: str  # max_samples, max_seconds, stop_at_score, interrupted, generator failed: ..., store failed: ...
    run_dir: str
    heldout: tuple[dict, ...] = ()  # the top programs' training and held-out scores
    media: dict = field(default_factory=dict)  # the best policy's plot and video, relative to run_dir
    simplified: dict = field(default_factory=dict)  # the best policy simplified: scores, sizes, code
    retuned: dict = field(default_factory=dict)  # the final policy re-tuned at finish.retune_budget: scores, code
    robustness: dict = field(default_factory=dict)  # the best policy under model mismatch: headline scores, files in run_dir
    coverage: dict = field(default_factory=dict)  # what each branch of the best policy did (`colmo.coverage.summary`)
    misnamed: tuple[str, ...] = ()  # the best policy's variables whose names contradict the spec's (`colmo.names`)
    decided: tuple[str, ...] = ()  # the best policy's comparisons whose outcome its code fixes (`colmo.bounds`)
    readability: dict = field(default_factory=dict)  # the best policy's readability report (`colmo.readability`)
    # This process's start-up: from the job's start to the search's first batch (imports, the
    # workers, the starter's calibration and tuning), seconds of `search.max_seconds` not searched;
    # then the search's own seconds, from its first batch to its stop (the finish follows).
    startup_seconds: float = 0.0
    search_seconds: float = 0.0
    # Per generator (`mutate`, `llamacpp`, ...: `Counters.by_generator`): model calls, programs
    # evaluated, the best training score, island bests, generation and evaluation seconds.
    by_generator: dict = field(default_factory=dict)
    cpus: int = field(default_factory=lambda: os.cpu_count() or 0)  # the machine's, beside `load`

    @property
    def failure(self) -> Optional[str]:
        """Why this run has no result to compare (`shortfall`), or None."""
        return shortfall(self.stop_reason, self.samples, self.programs_evaluated)

    @property
    def resumable(self) -> bool:
        """Stopped before its limits: `resume=` continues it (and then scores its best programs
        on held-out episodes)."""
        return self.stop_reason not in FINISHED

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def shortfall(stop_reason: str, samples: int, programs_evaluated: int) -> Optional[str]:
    """Why a run (from its summary's fields) has no result to compare, or None: it stopped before
    its limits (resume it), or it ended with no program of its own evaluated, so that its best
    is the starter's score and says nothing of the search."""
    if stop_reason not in FINISHED:
        return f"stopped: {stop_reason}"
    if programs_evaluated:
        return None
    if not samples and stop_reason == "max_seconds":
        return "no sample searched: search.max_seconds left no time after the start-up"
    return f"no program evaluated in {samples} sample{'s' * (samples != 1)}"


def summary_failure(summary: Optional[Mapping[str, Any]]) -> Optional[str]:
    """`shortfall` of a run from its `summary.json` (None if it wrote none: it failed or was killed)."""
    if summary is None:
        return "no summary: the run failed or was stopped"
    return shortfall(summary.get("stop_reason", ""), summary.get("samples", 0), summary.get("programs_evaluated", 0))


@dataclass(frozen=True)
class Elapsed:
    """The time a run has taken: wall-clock seconds, the generator's busy seconds, the evaluation
    workers' busy seconds (summed over workers) and the machine's load over them. A resumed run adds its process's time
    to what the store says the earlier processes took, so its summary, batch reports and
    per-second plots count the whole run."""

    seconds: float = 0.0
    generator_seconds: float = 0.0
    evaluator_seconds: float = 0.0
    load_seconds: float = 0.0  # the machine's load average integrated over `seconds` (`colmo.load.LoadMeter`)

    def plus(self, other: Elapsed) -> Elapsed:
        return Elapsed(*(mine + theirs for mine, theirs in zip(astuple(self), astuple(other))))


@dataclass
class Counters:
    """Running sums over the samples integrated so far, from which `totals` makes the numbers
    of every report."""

    samples: int = 0  # model calls
    records: int = 0  # stored samples, one per answer kept
    duplicate_answers: int = 0  # model calls whose answer was a duplicate
    by_status: collections.Counter = field(default_factory=collections.Counter)  # records by status
    evaluations: int = 0
    steps: int = 0
    completion_tokens: int = 0
    generation_seconds: float = 0.0  # the stored samples' own generation time (for tokens/s)
    # Per generator, by its label (`generator_label`): model
    # calls, programs evaluated, the best training score, the island bests its samples set, and
    # their generation and evaluation seconds; what a search of several (`search.fill`) splits
    # and what `search.model_share=by_yield` weighs.
    by_generator: dict[str, dict[str, Any]] = field(default_factory=dict)

    def count(self, record: SampleRecord, island_best: bool = False) -> None:
        """Add one settled sample; `island_best`: it scored above every program of its island before it."""
        entry = self.by_generator.setdefault(generator_label(record.generator), {
            "samples": 0, "programs_evaluated": 0, "best_score": None, "island_bests": 0, "generation_seconds": 0.0, "evaluation_seconds": 0.0,
        })
        entry["samples"] += record.model_calls
        entry["island_bests"] += island_best
        entry["generation_seconds"] += record.generation_seconds
        entry["evaluation_seconds"] += record.evaluation_seconds
        if record.status == EVALUATED:
            entry["programs_evaluated"] += 1
            entry["best_score"] = record.score if entry["best_score"] is None else max(entry["best_score"], record.score)
        self.samples += record.model_calls
        self.records += 1
        self.duplicate_answers += record.model_calls - 1 + (record.status == DUPLICATE)
        self.by_status[record.status] += 1
        self.evaluations += record.evaluations
        self.steps += record.steps
        self.completion_tokens += record.completion_tokens
        self.generation_seconds += record.generation_seconds

    def totals(self, elapsed: Elapsed, workers: int) -> Totals:
        """The reports' numbers after `elapsed`, with `workers` evaluation workers.
        The valid program rate is the share of new programs (duplicates and interrupted samples
        aside) that could be read, passed the static check and ran."""
        status = self.by_status
        judged = self.records - status[DUPLICATE] - status[INTERRUPTED]
        return Totals(
            samples=self.samples, programs_evaluated=status[EVALUATED], duplicates_skipped=status[DUPLICATE], failures=status[FAILED],
            unusable_outputs=status[UNUSABLE], interrupted=status[INTERRUPTED], evaluations=self.evaluations, steps=self.steps,
            valid_program_rate=_ratio(status[EVALUATED], judged), duplicate_rate=_ratio(self.duplicate_answers, self.samples),
            tokens_per_second=_ratio(self.completion_tokens, self.generation_seconds),
            evaluations_per_second=_ratio(self.evaluations, elapsed.seconds), generator_busy=_ratio(elapsed.generator_seconds, elapsed.seconds),
            evaluator_busy=_ratio(elapsed.evaluator_seconds, elapsed.seconds * workers), seconds=elapsed.seconds,
            worker_seconds=elapsed.evaluator_seconds, steps_per_worker_second=_ratio(self.steps, elapsed.evaluator_seconds),
            load=_ratio(elapsed.load_seconds, elapsed.seconds),
        )


def _ratio(part: float, whole: float) -> float:
    return part / whole if whole else 0.0


class SearchObserver(Protocol):
    """Receives a search's reports after each batch and at the end: a tracker's observers
    (`colmo.trackers`). The progress display is no observer: it reads `Search.totals` on its
    own clock, between batches too."""

    def on_batch(self, report: BatchReport, records: list[SampleRecord]) -> None: ...

    def on_finish(self, summary: Summary) -> None: ...
