"""Gradient-free optimization methods behind one ask/tell interface, in one registry.

Each method registers itself where it is defined (`@register`), and the `gfo.method` option
is validated against the registry's names (`colmo.config`), so there is one list. Methods
search in normalized coordinates `z` (`params = x0 + step * z`, see `colmo.optimize.tune`):
`z = 0` is the program's own constants, which every method asks for first.

A method is *comparison-based* when only the order of the values it is told matters to it
(the ES and DE, by selection; CMA-ES, by ranks): racing (`colmo.racing.Race`) is on by
default for those. Racing stops a candidate once a paired test on the incumbent's own episode
seeds says it very likely (90 %) does not beat the incumbent by more than `gfo.racing_margin`;
a raced-out candidate has returns for its first episodes only, and what it is told must rank
it as its full evaluation would. The mean of the episodes run does not: with fixed seeds the
first episodes may be easier than the rest for every candidate (the pendulum's first two are),
so a candidate that trails the incumbent on each of them can still show a higher mean than the
incumbent's over all episodes, and a (1+1)-ES would then take that worse point as its parent
and keep it. A raced-out candidate is told `Race.estimate` instead: the incumbent's mean plus
the candidate's mean paired difference, which is below the incumbent's score whenever the test
found it worse, and within the margin of it for a near tie; so selection and ranks against the
incumbent come out as they would without racing, with the test's confidence. BO models the
values themselves, for which an estimate is not a measurement: racing is off by default.
"""

from __future__ import annotations

import abc
import importlib.util
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Optional

import numpy as np

from colmo.errors import ConfigError

if TYPE_CHECKING:
    from colmo.config import GFOConfig

# Loss handed to a method for a failed candidate: worse than any real score, but finite,
# since some methods average or rank losses.
_FAILED_LOSS = 1e12


class Method(abc.ABC):
    """Ask/tell over normalized coordinates; higher scores are better."""

    @abc.abstractmethod
    def ask(self) -> tuple[Any, np.ndarray]:
        """A candidate token and its coordinates."""

    @abc.abstractmethod
    def tell(self, token: Any, score: Optional[float]) -> None:
        """Report a candidate's score (None: it failed). For a raced-out candidate the score is
        `Race.estimate`, its estimated mean over all episodes (see the module docstring)."""


@dataclass(frozen=True)
class MethodEntry:
    make: Callable[[int, "GFOConfig", int], Method]  # (dimension, config, seed)
    comparison_based: bool


METHODS: dict[str, MethodEntry] = {}


def register(name: str, comparison_based: bool) -> Callable[[Callable[[int, "GFOConfig", int], Method]], Callable[[int, "GFOConfig", int], Method]]:
    """Decorator for a method factory `(dim, cfg, seed) -> Method`: makes it `gfo=<name>`."""

    def add(make: Callable[[int, "GFOConfig", int], Method]) -> Callable[[int, "GFOConfig", int], Method]:
        METHODS[name] = MethodEntry(make, comparison_based)
        return make

    return add


class NevergradMethod(Method):
    def __init__(self, optimizer_name: str, dim: int, cfg: "GFOConfig", seed: int):
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

    def tell(self, token: Any, score: Optional[float]) -> None:
        self.optimizer.tell(token, _FAILED_LOSS if score is None else -score)


@register("oneplusone", comparison_based=True)
def one_plus_one(dim: int, cfg: "GFOConfig", seed: int) -> Method:
    """Nevergrad's (1+1)-ES, the paper's choice."""
    return NevergradMethod("OnePlusOne", dim, cfg, seed)


@register("cma", comparison_based=True)
def cma(dim: int, cfg: "GFOConfig", seed: int) -> Method:
    """Nevergrad's CMA-ES."""
    return NevergradMethod("CMA", dim, cfg, seed)


@register("de", comparison_based=True)
def differential_evolution(dim: int, cfg: "GFOConfig", seed: int) -> Method:
    """Nevergrad's TwoPointsDE."""
    return NevergradMethod("TwoPointsDE", dim, cfg, seed)


@register("bo", comparison_based=False)
class OptunaMethod(Method):
    """Optuna's Bayesian optimization, TPE (default) or GP sampler, within ±`search_range` steps."""

    def __init__(self, dim: int, cfg: "GFOConfig", seed: int):
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

    def tell(self, token: Any, score: Optional[float]) -> None:
        if score is None:
            self.study.tell(token, state=self._fail)
        else:
            self.study.tell(token, score)
