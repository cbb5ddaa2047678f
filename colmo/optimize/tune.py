"""Tuning one program's constants (the paper's inner loop) and measuring its final score.

`tune` runs a registered method (`colmo.optimize.methods`) in normalized coordinates `z`,
with `params = x0 + step * z`: `z = 0` is the program's own constants (always the first
evaluation), and each constant's step is proportional to its magnitude, so a gain of 12 and a
threshold of 0.05 move on their own scales. Candidates go `gfo.workers` at a time through a
`CandidateEvaluator`, which is where the sandboxed workers are; with racing, each candidate's
episodes stop once it very likely cannot beat the best candidate so far
(`colmo.racing.Race`), and the method is told the estimate of its mean over all of them
(`Race.estimate`). A raced-out candidate never becomes the best, and every reported score is
over all episodes.

`optimize_program` is the whole evaluation of one program: have the referee
(`colmo.sandbox.referee`) score it as written, tune it on the fast path, round the tuned
constants to the 4 significant digits it will be read with, score that readable code, and
have the referee measure it; a fast-path score the referee does not reproduce marks the
program failed (`tampering: ...`). The first score is the referee's because no later check
would catch a forged one: tuning usually moves away from the program's own constants, and a
program can tell them from others (a constant compared with `float('9.437')`), so it could
report any score for them alone and have it shown as its `score_initial`. So every score
reported is measured where the program cannot write, the final one of the code shown. A tuning
cut short by `stop()` (a deadline, Ctrl-C) is rounded and scored the same way: its code is as
readable as any, and the search's deadline reserves the two evaluations this costs.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Callable, Optional, Sequence

import numpy as np

from colmo.errors import ConfigError
from colmo.evaluation import FAST, REFEREE, Evaluation, Evaluator, Executor
from colmo.optimize.methods import METHODS, racing_on, tunes_constants
from colmo.program import DISPLAY_DIGITS, ParametricProgram, ProgramSize, instantiate, measure, round_significant
from colmo.racing import Race

if TYPE_CHECKING:
    from colmo.config import GFOConfig

TIMEOUT_FLOOR_S = 10.0
TIMEOUT_FACTOR = 30.0
# Relative difference between a fast-path and a referee score beyond which the fast path was
# tampered with; the two run the same code on the same data, so honest programs agree exactly.
_TAMPERING_TOLERANCE = 1e-9
TAMPERING = "tampering:"  # how the failure of a program whose fast path the referee refutes begins
NONDETERMINISTIC = "nondeterministic:"  # ... and of one whose episodes the referee cannot repeat either


class CandidateEvaluator:
    """Evaluations of one program's parameter vectors on a task: fast (GFO candidates, raced
    and split over `episode_chunks` requests when asked) or by the referee (final scores);
    `label` names the program in the executor's messages (a lost worker says what it held);
    with `count_branches` the referee's evaluations carry the program's branch coverage."""

    def __init__(
        self, executor: Executor, evaluator: Evaluator, skeleton: str, episode_chunks: int = 1, label: str = "", count_branches: bool = False,
    ):
        self.executor = executor
        self.evaluator = evaluator
        self.skeleton = skeleton
        self.chunks = evaluator.seed_chunks(episode_chunks)
        self.label = label
        self.count_branches = count_branches  # the referee's evaluations count what each branch did

    def fast(self, params_list: Sequence[Sequence[float]], race: Optional[Race] = None) -> list[Evaluation]:
        """Each vector's fast-path evaluation. With `race` (its `incumbent` over all seeds) the
        episodes of a candidate run in order in one request, so that racing sees them all and
        the result does not depend on how many workers there are; without, they are split."""
        chunks = self.evaluator.seed_chunks(1) if race else self.chunks
        requests = [
            self.evaluator.request(self.skeleton, params, seeds=chunk, mode=FAST, race=race, label=self.label)
            for params in params_list
            for chunk in chunks
        ]
        parts = self.executor.evaluate(requests)
        return [Evaluation.joined(parts[k : k + len(chunks)]) for k in range(0, len(parts), len(chunks))]

    def coverage(self, params: Sequence[float], timeout_s: Optional[float] = None) -> Evaluation:
        """The fast path's evaluation of one vector over all the seeds (split over
        `episode_chunks` requests) with what each branch did (`Evaluation.coverage`)."""
        requests = [
            self.evaluator.request(self.skeleton, params, seeds=chunk, mode=FAST, timeout_s=timeout_s, coverage=True, label=self.label)
            for chunk in self.chunks
        ]
        return Evaluation.joined(self.executor.evaluate(requests))

    def referee(self, params: Sequence[float], timeout_s: Optional[float] = None) -> Evaluation:
        """The referee's evaluation of one vector over all the seeds (split over
        `episode_chunks` requests), each request limited to `timeout_s` if given; with
        `count_branches`, what each branch did besides (`Evaluation.coverage`)."""
        requests = [
            self.evaluator.request(
                self.skeleton, params, seeds=chunk, mode=REFEREE, timeout_s=timeout_s, coverage=self.count_branches, label=self.label,
            )
            for chunk in self.chunks
        ]
        return Evaluation.joined(self.executor.evaluate(requests))


@dataclass(frozen=True)
class Tuning:
    """The outcome of tuning one parameter vector."""

    params: tuple[float, ...]
    evaluation: Evaluation  # the best candidate's, over all episodes
    initial: Evaluation
    evaluations: int
    steps: int  # control steps simulated
    raced_out: int  # candidates whose episodes racing cut short
    cut_short: bool  # stopped before its budget (the search's deadline)


def step_sizes(x0: Sequence[float], cfg: "GFOConfig") -> np.ndarray:
    """Initial step per constant: a fraction of its magnitude, floored for constants near 0."""
    return cfg.relative_step * np.maximum(np.abs(np.asarray(x0, dtype=float)), cfg.min_step)


def tune(evaluate: CandidateEvaluator, x0: Sequence[float], cfg: "GFOConfig", seed: int, stop: Callable[[], bool] = lambda: False) -> Tuning:
    """Maximize the score over the parameters, starting from (and first evaluating, by the
    referee: module docstring) `x0`, until the budget is spent or `stop()` says so. The
    objective is deterministic (fixed episode seeds, and the referee returns what the fast path
    returns for an honest program), so the best candidate seen is the answer. A program that
    fails with its own constants is not tuned, nor is any by a method that does not tune
    (`gfo=none`)."""
    x0 = np.asarray(x0, dtype=float)
    initial = evaluate.referee(x0)
    best_params, best = x0, initial
    evaluations, steps, raced_out, cut_short = 1, initial.steps, 0, False
    if len(x0) and not initial.failure:
        method = METHODS[cfg.method](len(x0), cfg, seed)
        method.tell(method.ask()[0], initial.score)  # the first ask is z = 0, i.e. x0
        scale = step_sizes(x0, cfg)
        while method.tunes_constants and evaluations < cfg.budget:
            if stop():
                cut_short = True
                break
            asked = [method.ask() for _ in range(min(cfg.workers, cfg.budget - evaluations))]
            candidates = [x0 + scale * z for _, z in asked]
            race = Race(best.returns, cfg.racing_min_episodes, cfg.racing_margin) if racing_on(cfg) else None
            for (token, _), params, evaluation in zip(asked, candidates, evaluate.fast(candidates, race)):
                method.tell(token, _told(evaluation, race))
                evaluations, steps, raced_out = evaluations + 1, steps + evaluation.steps, raced_out + evaluation.raced_out
                if not evaluation.raced_out and evaluation.score > best.score:
                    best_params, best = params, evaluation
    return Tuning(tuple(float(p) for p in best_params), best, initial, evaluations, steps, raced_out, cut_short)


def _told(evaluation: Evaluation, race: Optional[Race]) -> Optional[float]:
    """What the method is told: None for a failure; for a raced-out candidate the estimate of
    its mean over all episodes (`Race.estimate`), not the mean of the episodes it ran."""
    if evaluation.failure:
        return None
    return race.estimate(evaluation.returns) if evaluation.raced_out and race else evaluation.score


@dataclass(frozen=True)
class ProgramResult:
    """One program's complete evaluation: what the search stores and `colmo.optimize` prints."""

    params: tuple[float, ...]
    code: str  # readable, the final constants inlined
    evaluation: Evaluation  # the referee's, over all episodes
    initial: Evaluation  # with the program's own constants (the referee's)
    evaluations: int
    steps: int
    raced_out: int
    cut_short: bool
    seconds: float
    size: ProgramSize
    # Worker seconds of scoring the final constants (the rounded ones on the fast path, then the
    # referee): what a program still costs once its tuning stops (`colmo.timelimit`).
    scoring_seconds: float = 0.0

    @property
    def score(self) -> float:
        return self.evaluation.score

    @property
    def failure(self) -> str | None:
        return self.evaluation.failure


def optimize_program(
    program: ParametricProgram, evaluate: CandidateEvaluator, cfg: "GFOConfig", seed: int, stop: Callable[[], bool] = lambda: False
) -> ProgramResult:
    """Tune `program`, and have the referee score the readable (4-digit) code that results."""
    start = time.perf_counter()
    if not tunes_constants(cfg) or not program.values:  # nothing to tune: the referee's score is the only one
        final = evaluate.referee(program.values)
        code = instantiate(program.skeleton, program.values)
        return ProgramResult(
            tuple(program.values), code, final, final, 1, final.steps, 0, False, time.perf_counter() - start, measure(code), final.seconds,
        )
    tuning = tune(evaluate, program.values, cfg, seed, stop)
    params, fast, evaluations, steps = tuple(program.values), tuning.initial, tuning.evaluations, tuning.steps
    digits, scoring_seconds = None, 0.0
    if tuning.params != params:  # cut short or not: the code a person reads has 4-digit constants
        rounded = round_significant(tuning.params)
        evaluation = evaluate.fast([rounded])[0]
        evaluations, steps, scoring_seconds = evaluations + 1, steps + evaluation.steps, evaluation.seconds
        if evaluation.score >= tuning.initial.score:  # else rounding cost more than tuning gained
            params, fast, digits = rounded, evaluation, DISPLAY_DIGITS
    final = fast
    if not fast.failure and fast is not tuning.initial:  # the program's own constants were refereed already
        refereed = evaluate.referee(params)
        final = judged(refereed, fast, again=lambda: evaluate.referee(params))
        evaluations, steps, scoring_seconds = evaluations + 1, steps + final.steps, scoring_seconds + refereed.seconds
    code = instantiate(program.skeleton, params, digits=digits)
    return ProgramResult(
        params, code, final, tuning.initial, evaluations, steps, tuning.raced_out, tuning.cut_short, time.perf_counter() - start, measure(code),
        scoring_seconds,
    )


def optimize_alone(
    executor: Executor, evaluator: Evaluator, program: ParametricProgram, cfg: "GFOConfig", seed: int,
    stop: Callable[[], bool] = lambda: False, label: str = "",
) -> ProgramResult:
    """`optimize_program` for a program that has the executor to itself (`colmo-optimize`, the
    simplifier's and the finish's re-tuning): `cfg.workers` candidates at a time, each one's
    episodes split over the workers they leave."""
    chunks = max(1, executor.n_workers // cfg.workers)
    return optimize_program(program, CandidateEvaluator(executor, evaluator, program.skeleton, chunks, label=label), cfg, seed, stop)


def judged(referee: Evaluation, fast: Evaluation, again: Callable[[], Evaluation]) -> Evaluation:
    """The referee's evaluation, failed if the program's own (fast-path) run reported other
    returns: as nondeterministic if the referee, asked `again`, cannot repeat its own returns
    either (the program's episodes differ from run to run), else as tampering."""
    if referee.failure or len(referee.returns) != len(fast.returns) or _agree(referee.returns, fast.returns):
        return referee
    second = again()
    if not second.failure and not _agree(second.returns, referee.returns):
        reason = f"{NONDETERMINISTIC} the same episodes gave different returns in two runs of the referee ({referee.score:.6g}, then {second.score:.6g})"
    else:
        reason = f"{TAMPERING} the program's own run reported other returns than the referee's, which measured {referee.score:.6g}"
    return Evaluation(referee.returns, reason, referee.steps)


def _agree(returns: Sequence[float], others: Sequence[float]) -> bool:
    return bool(np.allclose(returns, others, rtol=_TAMPERING_TOLERANCE, atol=_TAMPERING_TOLERANCE))


def calibrated(executor: Executor, evaluator: Evaluator, starter: ParametricProgram, timeout_s: Optional[float] = None) -> Evaluator:
    """`evaluator` with time limits that fit its task: `timeout_s` if given, else
    `TIMEOUT_FACTOR` times what the starter program's evaluation took in each mode, at least
    `TIMEOUT_FLOOR_S`; so a program that hangs costs seconds, not minutes. The starter must run:
    `ConfigError` if it fails (the spec is the user's)."""
    # Both at once: with two workers or more the calibration takes one evaluation's time, not two.
    fast, referee = executor.evaluate([
        evaluator.request(starter.skeleton, starter.values, mode=FAST), evaluator.request(starter.skeleton, starter.values, mode=REFEREE),
    ])
    failure = fast.failure or referee.failure
    if failure:
        raise ConfigError(f"the starter policy in {evaluator.spec} fails: {failure}")
    evaluator = replace(evaluator, calibration=(fast.seconds, referee.seconds))
    if timeout_s is not None:
        return replace(evaluator, timeout_s=timeout_s, referee_timeout_s=timeout_s)
    return replace(
        evaluator, timeout_s=max(TIMEOUT_FLOOR_S, TIMEOUT_FACTOR * fast.seconds),
        referee_timeout_s=max(TIMEOUT_FLOOR_S, TIMEOUT_FACTOR * referee.seconds),
    )

