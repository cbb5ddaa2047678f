"""Gradient-free optimization methods behind one ask/tell interface, in one registry.

Each method registers itself where it is defined (`@METHODS.register`, `colmo.registry`), and
the `gfo.method` option is validated against the registry's names (`colmo.config`), so there is
one list. `none` is a method too (`EvaluateOnce`): it tunes nothing, which it declares
(`tunes_constants`), and whoever must know (the search's prompt and dedup, the tuner, the
simplifier, the reports) reads that, not the name. Methods search in normalized coordinates `z`
(`params = x0 + step * z`, see `colmo.optimize.tune`): `z = 0` is the program's own constants,
which every method asks for first.

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
from typing import Any, ClassVar, Optional

import numpy as np

from colmo.config import BOConfig, GFOConfig
from colmo.errors import ConfigError
from colmo.registry import Registry

# Loss handed to a method for a failed candidate: worse than any real score, but finite,
# since some methods average or rank losses.
_FAILED_LOSS = 1e12


class Method(abc.ABC):
    """Ask/tell over normalized coordinates; higher scores are better. A method registers
    itself as `gfo=<name>` (`@METHODS.register`) and is built as `cls(dim, cfg, seed)`."""

    options: ClassVar[type[GFOConfig]] = GFOConfig  # the schema of its `gfo` option
    comparison_based: ClassVar[bool]  # only the order of the scores it is told matters to it
    # Whether it changes a program's constants; one that does not scores each program once, as
    # written, and a program differing from an evaluated one only in its constants is then new.
    tunes_constants: ClassVar[bool] = True

    @abc.abstractmethod
    def ask(self) -> tuple[Any, np.ndarray]:
        """A candidate token and its coordinates."""

    @abc.abstractmethod
    def tell(self, token: Any, score: Optional[float]) -> None:
        """Report a candidate's score (None: it failed). For a raced-out candidate the score is
        `Race.estimate`, its estimated mean over all episodes (see the module docstring)."""


METHODS: Registry[type[Method]] = Registry("gfo.method")


def tunes_constants(cfg: GFOConfig) -> bool:
    """Whether `cfg`'s method changes a program's constants, as the method declares (`gfo=none`,
    which evaluates each program as written, does not)."""
    return METHODS[cfg.method].tunes_constants


def racing_on(cfg: GFOConfig) -> bool:
    """Whether `cfg`'s candidates race: `gfo.racing`, or by default whether the method is comparison-based."""
    return cfg.racing if cfg.racing is not None else METHODS[cfg.method].comparison_based


@METHODS.register("none")
class EvaluateOnce(Method):
    """No tuning: each program is evaluated once, with its constants as written (the paper's
    'no GFO' baseline). Its one candidate is the program's own constants, `z = 0`."""

    comparison_based = False
    tunes_constants = False

    def __init__(self, dim: int, cfg: GFOConfig, seed: int):
        self.dim = dim

    def ask(self) -> tuple[Any, np.ndarray]:
        return None, np.zeros(self.dim)

    def tell(self, token: Any, score: Optional[float]) -> None:
        """Nothing to learn: there is no other candidate."""


class NevergradMethod(Method):
    """A Nevergrad optimizer (`optimizer_name` in its registry) started at `z = 0`."""

    optimizer_name: ClassVar[str]
    comparison_based = True

    def __init__(self, dim: int, cfg: GFOConfig, seed: int):
        import nevergrad as ng  # seconds to import: only when a run tunes something

        parametrization = ng.p.Array(init=np.zeros(dim))
        parametrization.random_state = np.random.RandomState(seed)
        self.optimizer = ng.optimizers.registry[self.optimizer_name](
            parametrization=parametrization, budget=cfg.budget, num_workers=cfg.workers
        )
        self.optimizer.suggest(np.zeros(dim))

    def ask(self) -> tuple[Any, np.ndarray]:
        candidate = self.optimizer.ask()
        return candidate, np.asarray(candidate.value, dtype=float)

    def tell(self, token: Any, score: Optional[float]) -> None:
        self.optimizer.tell(token, _FAILED_LOSS if score is None else -score)


@METHODS.register("oneplusone")
class OnePlusOne(NevergradMethod):
    """Nevergrad's (1+1)-ES, the paper's choice."""

    optimizer_name = "OnePlusOne"


@METHODS.register("cma")
class CMA(NevergradMethod):
    """Nevergrad's CMA-ES."""

    optimizer_name = "CMA"


@METHODS.register("de")
class DifferentialEvolution(NevergradMethod):
    """Nevergrad's TwoPointsDE."""

    optimizer_name = "TwoPointsDE"


@METHODS.register("bo")
class OptunaMethod(Method):
    """Optuna's Bayesian optimization, TPE (default) or GP sampler, within ±`search_range` steps."""

    options = BOConfig
    comparison_based = False

    def __init__(self, dim: int, cfg: BOConfig, seed: int):
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
