"""The schema of config group `task`: the spec file, its episodes, and the model mismatch
(`task.perturb`) every `MujocoEnvironment` draws per episode."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Optional

from omegaconf import MISSING

from colmo.config.fields import at_least, option, require


@dataclass
class PerturbConfig:
    """Model mismatch drawn per episode from the episode seed, for every `MujocoEnvironment`
    (`colmo.environments.perturb`); every factor 0 (the default) is the nominal model.

    Each relative magnitude `m` scales its model fields by factors drawn uniformly from
    [1 - m, 1 + m] (one per body, dof, geom or actuator), from a random stream of their own, so
    the nominal episode draws are untouched and every candidate meets the same perturbations."""

    mass: float = option(0.0, "relative range of each body's mass and inertia (scaled together)")
    damping: float = option(0.0, "relative range of each joint dof's damping")
    frictionloss: float = option(0.0, "relative range of each joint dof's dry friction (frictionloss)")
    friction: float = option(0.0, "relative range of each geom's friction coefficients")
    gain: float = option(0.0, "relative range of each actuator's gain (and, for servos, its feedback gains)")
    obs_noise: float = option(0.0, "standard deviation of Gaussian noise added to every observation entry, in its units")
    action_noise: float = option(0.0, "standard deviation of Gaussian noise added to every action, relative to its control half-range")
    delay: int = option(0, "control delay: each action is applied this many control steps late")

    def __post_init__(self) -> None:
        at_least(self, "task.perturb", delay=0, obs_noise=0, action_noise=0)
        for name in ("mass", "damping", "frictionloss", "friction", "gain"):
            value = getattr(self, name)
            require(0 <= value < 1, f"task.perturb.{name} must be in [0, 1), got {value}")

    @property
    def active(self) -> bool:
        """Whether anything differs from the nominal model."""
        return any(getattr(self, name) for name in self.__dataclass_fields__)


ROBUSTNESS_MAGNITUDES = [0.05, 0.1, 0.2, 0.4]  # a robustness grid's relative magnitudes (colmo.robustness)
ROBUSTNESS_DELAYS = [1, 2, 4]  # ... and its control delays, in steps


def check_robustness_grid(
    group: str, episodes: int, magnitudes: list[float], delays: list[int], precision: Optional[float], max_episodes: int,
) -> None:
    """`ConfigError` for a robustness grid (`group`'s `robustness_*` fields) that cannot be scored."""
    require(episodes >= 1, f"{group}robustness_episodes must be >= 1, got {episodes}")
    require(all(0 < m < 1 for m in magnitudes), f"{group}robustness_magnitudes must lie in (0, 1), got {list(magnitudes)}")
    require(all(k >= 1 for k in delays), f"{group}robustness_delays must be >= 1 step, got {list(delays)}")
    require(precision is None or precision > 0, f"{group}robustness_precision must be > 0 or null, got {precision}")
    require(
        max_episodes >= episodes,
        f"{group}robustness_max_episodes ({max_episodes}) must be >= {group}robustness_episodes ({episodes})",
    )


# The options of an adaptive robustness report (`colmo.robustness.adaptive_report`), in both configs that make one.
PRECISION_HELP = (
    "more held-out episodes for every grid point, doubling from robustness_episodes, until each point's 95% interval "
    "half-width is at most this share of the nominal score (0.05: 5%), up to robustness_max_episodes; null: robustness_episodes exactly"
)
MAX_EPISODES_HELP = "the most held-out episodes per grid point that robustness_precision may take"


@dataclass
class TaskConfig:
    """The control task: a spec file and how it is scored."""

    name: str = option(MISSING, "the task's name (MLflow experiment, output directory)")
    spec: str = option(MISSING, "spec file: a bundled name (pendulum.py) or a path")
    episodes: int = option(10, "training episodes per score; their seeds derive from `seed`")
    target_score: Optional[float] = option(None, "reports count the samples needed to reach this score")
    env: dict[str, Any] = option({}, "keyword arguments for the spec's make_environment")
    perturb: PerturbConfig = field(default_factory=PerturbConfig, metadata={"help": "per-episode model mismatch (default: none)"})

    def __post_init__(self) -> None:
        at_least(self, "task", episodes=1)
        if "horizon" in self.env:  # the bundled environments' episode length: 0 would run episodes of no steps
            horizon = self.env["horizon"]
            require(
                isinstance(horizon, int) and not isinstance(horizon, bool) and horizon >= 1,
                f"task.env.horizon must be a whole number of control steps >= 1, got {horizon!r}",
            )

