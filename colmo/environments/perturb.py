"""Model mismatch for every `MujocoEnvironment`: `task.perturb` (`colmo.config.PerturbConfig`).

`PerturbedEnvironment` wraps any MuJoCo environment. At each reset it draws, from the episode
seed, one scale factor per body (mass and inertia), dof (damping, frictionloss), geom (friction)
and actuator (gain), writes the scaled values into the `mujoco.MjModel` and puts the nominal
ones back at the episode's end (`check_episode`) and before the next reset; while the episode
runs it adds observation and action noise and delays the actions. The draws come from a stream
of their own (`SeedSequence([seed, _STREAM])`), so the environment's own initial-state draws
are untouched, and every factor is drawn whatever the magnitudes: a factor's direction for a
seed is the same at every magnitude and whichever other factors are on, which pairs the
points of a robustness grid. Derived constants MuJoCo computes at compile time (such as
`dof_invweight0`) keep their nominal values.

The perturbation reaches the sandbox worker as the reserved environment option `perturb`
(`with_perturbation`), which `perturbable` takes off before the spec's `make_environment` sees
the options: a user's own spec file gets perturbations without knowing of them. With every
factor 0 nothing is wrapped, so nominal scores stay bit-identical.
"""

from __future__ import annotations

import collections
import dataclasses
from typing import Any, Callable

import numpy as np

from colmo.config import PerturbConfig
from colmo.environments.base import Environment, MujocoEnvironment

PERTURB_OPTION = "perturb"  # the reserved environment option carrying a PerturbConfig
_STREAM = 0x9E37  # the perturbation stream of an episode seed, apart from the environment's own


def with_perturbation(options: dict[str, Any], perturb: PerturbConfig) -> dict[str, Any]:
    """The environment options of a task with its perturbation, as plain hashable data; the
    options unchanged when the perturbation is off."""
    if not perturb.active:
        return dict(options)
    return dict(options) | {PERTURB_OPTION: tuple(sorted(dataclasses.asdict(perturb).items()))}


def perturbable(make_environment: Callable[..., Environment]) -> Callable[..., Environment]:
    """`make_environment` that also accepts the `perturb` option and wraps its environment."""

    def make(**options: Any) -> Environment:
        fields = options.pop(PERTURB_OPTION, None)
        env = make_environment(**options)
        if fields is None:
            return env
        if not isinstance(env, MujocoEnvironment):
            raise TypeError(f"task.perturb needs a MujocoEnvironment, the spec made a {type(env).__name__}")
        return PerturbedEnvironment(env, PerturbConfig(**dict(fields)))

    return make


class PerturbedEnvironment(Environment):
    """`env` with the model mismatch of `perturb`, drawn anew for every episode seed."""

    def __init__(self, env: MujocoEnvironment, perturb: PerturbConfig):
        self.env = env
        self.perturb = perturb
        self.observation_size = env.observation_size
        self.action_size = env.action_size
        self.horizon = env.horizon
        self.max_abs_reward = env.max_abs_reward
        self.control_timestep = env.control_timestep
        model = env.model
        self._nominal = {name: getattr(model, name).copy() for name in _FIELDS}
        limited = model.actuator_ctrllimited.astype(bool)
        low, high = model.actuator_ctrlrange.T
        self._action_scale = np.where(limited, (high - low) / 2, 1.0)
        self._random = np.random.default_rng(0)
        self._pending: collections.deque[np.ndarray] = collections.deque()

    @property
    def model(self) -> Any:
        return self.env.model

    @property
    def data(self) -> Any:
        return self.env.data

    def restore_nominal(self) -> None:
        """Put the nominal values back into every model field a perturbation changes."""
        for name, nominal in self._nominal.items():
            getattr(self.env.model, name)[:] = nominal

    def _apply(self, random: np.random.Generator) -> None:
        model, nominal, p = self.env.model, self._nominal, self.perturb

        def factors(size: int, magnitude: float) -> np.ndarray:
            return 1.0 + magnitude * random.uniform(-1.0, 1.0, size)  # drawn even at magnitude 0

        body = factors(model.nbody, p.mass)
        model.body_mass[:] = nominal["body_mass"] * body
        model.body_inertia[:] = nominal["body_inertia"] * body[:, None]
        model.dof_damping[:] = nominal["dof_damping"] * factors(model.nv, p.damping)
        model.dof_frictionloss[:] = nominal["dof_frictionloss"] * factors(model.nv, p.frictionloss)
        model.geom_friction[:] = nominal["geom_friction"] * factors(model.ngeom, p.friction)[:, None]
        gain = factors(model.nu, p.gain)
        model.actuator_gainprm[:, 0] = nominal["actuator_gainprm"][:, 0] * gain
        # A servo's force is gain * ctrl + bias[1] * q + bias[2] * qdot: a weaker servo is weaker in all.
        model.actuator_biasprm[:, 1:3] = nominal["actuator_biasprm"][:, 1:3] * gain[:, None]

    def _observe(self, obs: np.ndarray) -> np.ndarray:
        if not self.perturb.obs_noise:
            return obs
        return obs + self.perturb.obs_noise * self._random.standard_normal(np.shape(obs))

    def reset(self, seed: int) -> np.ndarray:
        self.restore_nominal()
        self._random = np.random.default_rng(np.random.SeedSequence([seed, _STREAM]))
        self._apply(self._random)
        obs = self.env.reset(seed)
        # Until the first delayed action arrives, the actuators hold the control of the reset state.
        self._pending = collections.deque([self.env.data.ctrl.copy()] * self.perturb.delay)
        return self._observe(obs)

    def step(self, action: np.ndarray) -> tuple[float, np.ndarray]:
        self._pending.append(action)
        applied = self._pending.popleft()
        if self.perturb.action_noise:
            applied = applied + self.perturb.action_noise * self._action_scale * self._random.standard_normal(self.action_size)
        reward, obs = self.env.step(applied)
        return reward, self._observe(obs)

    def check_episode(self) -> None:
        try:
            self.env.check_episode()
        finally:
            self.restore_nominal()


_FIELDS = ("body_mass", "body_inertia", "dof_damping", "dof_frictionloss", "geom_friction", "actuator_gainprm", "actuator_biasprm")
