"""Gradient-free tuning of a program's constants (the paper's inner loop).

Every method sits behind one ask/tell interface in `METHODS`: Nevergrad's (1+1)-ES, CMA-ES and
DE, and Optuna's Bayesian optimization (TPE or GP sampler). They search in normalized
coordinates `z`, with `params = x0 + step * z`: `z = 0` is the program's own constants (always
the first evaluation), and each constant's step is proportional to its magnitude, so a gain
of 12 and a threshold of 0.05 move on their own scales. Candidates are scored in batches of
`gfo.workers` through an `evaluate_batch` callable, which is where the sandboxed workers are.

`optimize_program` is the whole evaluation of one program: score it as written, tune it,
round the tuned constants to the 4 significant digits it will be read with, and score that
readable code, so the score reported is the score of the code shown.
"""

from __future__ import annotations

import abc
import importlib.util
import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np

from colmo.config import ConfigError, GFOConfig
from colmo.program import ParametricProgram, instantiate
from colmo.task import Evaluation

EvaluateBatch = Callable[[Sequence[Sequence[float]]], list[Evaluation]]

DISPLAY_DIGITS = 4
# Loss handed to a method for a failed candidate: worse than any real score, but finite,
# since some methods average or rank losses.
_FAILED_LOSS = 1e12


class Method(abc.ABC):
    """Ask/tell over normalized coordinates; higher scores are better."""

    @abc.abstractmethod
    def ask(self) -> tuple[Any, np.ndarray]:
        """A candidate token and its coordinates."""

    @abc.abstractmethod
    def tell(self, token: Any, evaluation: Evaluation) -> None:
        """Report a candidate's evaluation."""


class NevergradMethod(Method):
    def __init__(self, optimizer_name: str, dim: int, cfg: GFOConfig, seed: int):
        import nevergrad as ng  # seconds to import: only when a run tunes something

        parametrization = ng.p.Array(init=np.zeros(dim))
        parametrization.random_state = np.random.RandomState(seed)
        self.optimizer = ng.optimizers.registry[optimizer_name](
            parametrization=parametrization, budget=cfg.budget, num_workers=cfg.workers
        )
        self.optimizer.suggest(np.zeros(dim))

    def ask(self) -> tuple[Any, np.ndarray]:
        candidate = self.optimizer.ask()
        return candidate, np.asarray(candidate.value, dtype=float)

    def tell(self, token: Any, evaluation: Evaluation) -> None:
        self.optimizer.tell(token, _FAILED_LOSS if evaluation.failure else -evaluation.score)


class OptunaMethod(Method):
    def __init__(self, dim: int, cfg: GFOConfig, seed: int):
        import optuna

        optuna.logging.set_verbosity(optuna.logging.WARNING)
        if cfg.sampler == "gp":
            if importlib.util.find_spec("torch") is None:
                raise ConfigError("gfo.sampler=gp needs PyTorch (pip install torch); use gfo.sampler=tpe without it")
            sampler = optuna.samplers.GPSampler(seed=seed)
        else:
            sampler = optuna.samplers.TPESampler(seed=seed, n_startup_trials=min(10, cfg.budget))
        self.study = optuna.create_study(direction="maximize", sampler=sampler)
        bound = cfg.search_range
        self.names = [f"z{i}" for i in range(dim)]
        self.distributions = {name: optuna.distributions.FloatDistribution(-bound, bound) for name in self.names}
        self.study.enqueue_trial({name: 0.0 for name in self.names})
        self._fail = optuna.trial.TrialState.FAIL

    def ask(self) -> tuple[Any, np.ndarray]:
        trial = self.study.ask(self.distributions)
        return trial, np.array([trial.params[name] for name in self.names])

    def tell(self, token: Any, evaluation: Evaluation) -> None:
        if evaluation.failure:
            self.study.tell(token, state=self._fail)
        else:
            self.study.tell(token, evaluation.score)


METHODS: dict[str, Callable[[int, GFOConfig, int], Method]] = {
    "oneplusone": lambda dim, cfg, seed: NevergradMethod("OnePlusOne", dim, cfg, seed),
    "cma": lambda dim, cfg, seed: NevergradMethod("CMA", dim, cfg, seed),
    "de": lambda dim, cfg, seed: NevergradMethod("TwoPointsDE", dim, cfg, seed),
    "bo": OptunaMethod,
}


@dataclass(frozen=True)
class Tuning:
    """The outcome of tuning one parameter vector."""

    params: tuple[float, ...]
    evaluation: Evaluation
    initial: Evaluation
    history: tuple[float, ...]
    evaluations: int
    seconds: float


def step_sizes(x0: Sequence[float], cfg: GFOConfig) -> np.ndarray:
    """Initial step per constant: a fraction of its magnitude, floored for constants near 0."""
    return cfg.relative_step * np.maximum(np.abs(np.asarray(x0, dtype=float)), cfg.min_step)


def tune(evaluate_batch: EvaluateBatch, x0: Sequence[float], cfg: GFOConfig, seed: int) -> Tuning:
    """Maximize the score over the parameters, starting from (and first evaluating) `x0`.

    The objective is deterministic (fixed episode seeds), so the best candidate seen is the
    answer. A program that fails with its own constants is not tuned.
    """
    start = time.perf_counter()
    x0 = np.asarray(x0, dtype=float)
    initial = evaluate_batch([x0])[0]
    history = [initial.score]
    best_params, best = x0, initial
    if cfg.method != "none" and len(x0) and not initial.failure and cfg.budget > 1:
        method = METHODS[cfg.method](len(x0), cfg, seed)
        method.tell(method.ask()[0], initial)  # the first ask is z = 0, i.e. x0
        scale = step_sizes(x0, cfg)
        while len(history) < cfg.budget:
            asked = [method.ask() for _ in range(min(cfg.workers, cfg.budget - len(history)))]
            candidates = [x0 + scale * z for _, z in asked]
            for (token, _), params, evaluation in zip(asked, candidates, evaluate_batch(candidates)):
                method.tell(token, evaluation)
                history.append(evaluation.score)
                if evaluation.score > best.score:
                    best_params, best = params, evaluation
    return Tuning(
        params=tuple(float(p) for p in best_params),
        evaluation=best,
        initial=initial,
        history=tuple(history),
        evaluations=len(history),
        seconds=time.perf_counter() - start,
    )


def round_significant(values: Sequence[float], digits: int = DISPLAY_DIGITS) -> tuple[float, ...]:
    return tuple(float(f"{v:.{digits}g}") for v in values)


@dataclass(frozen=True)
class ProgramResult:
    """One program's complete evaluation: what the search stores and `colmo.optimize` prints."""

    program: ParametricProgram
    params: tuple[float, ...]
    code: str
    evaluation: Evaluation
    initial: Evaluation
    history: tuple[float, ...] = ()
    evaluations: int = 0
    seconds: float = 0.0
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def score(self) -> float:
        return self.evaluation.score

    @property
    def failure(self) -> str | None:
        return self.evaluation.failure


def optimize_program(
    program: ParametricProgram, evaluate_batch: EvaluateBatch, cfg: GFOConfig, seed: int
) -> ProgramResult:
    """Tune `program` and score the readable (4-digit) code that results."""
    tuning = tune(evaluate_batch, program.values, cfg, seed)
    params, evaluation, evaluations = program.values, tuning.initial, tuning.evaluations
    if tuning.params != tuple(program.values):
        params = round_significant(tuning.params)
        evaluation = evaluate_batch([params])[0]
        evaluations += 1
        if evaluation.score < tuning.initial.score:  # rounding cost more than tuning gained
            params, evaluation = program.values, tuning.initial
    code = instantiate(program.skeleton, params, digits=DISPLAY_DIGITS if params != program.values else None)
    return ProgramResult(
        program=program,
        params=tuple(params),
        code=code,
        evaluation=evaluation,
        initial=tuning.initial,
        history=tuning.history,
        evaluations=evaluations,
        seconds=tuning.seconds,
    )


def finite_or_none(value: float) -> float | None:
    """JSON has no infinity: a failed score is reported as null."""
    return value if math.isfinite(value) else None
