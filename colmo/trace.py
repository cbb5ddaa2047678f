"""Episode traces: one episode as plain numbers, recorded by the trusted side.

An `EpisodeTrace` holds the observations, actions, rewards and MuJoCo physics states of every
control step of one episode, and the control timestep. It is what `colmo.render` draws from.
A trace is recorded by the sandbox worker in referee mode (`colmo.sandbox.referee`), the
trusted process that owns the simulator while the program only maps observations to actions
in its confined child: the worker feeds a `TraceRecorder` as it steps the episode, so no
program code ever takes part in recording, and the coordinator never runs program code to
get one. The trace crosses to the coordinator inside the `Evaluation` as `to_dict()` and is
checked on arrival with `from_dict` like any reply from a sandbox process; constructing a
trace validates it (`TraceError`: malformed, inconsistent or too large).

This module is imported by the sandbox worker, which may not write files: it loads nothing
for drawing.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Optional

import mujoco
import numpy as np

from colmo.environments.base import Environment, MujocoEnvironment

STATE_SPEC = mujoco.mjtState.mjSTATE_PHYSICS  # qpos, qvel, act (and actuator history, if any)

# Bounds on a trace from another process: far above any real episode (the widest, the
# quadruped's, is 1000 steps of 78 + 12 + 57 numbers), far below what would exhaust memory here.
MAX_STEPS = 200_000
MAX_WIDTH = 10_000
MAX_VALUES = 10_000_000
MAX_JSON_CHARS = 64 * 2**20  # a 1000-step quadruped trace is 2.6 MB
MAX_CONTROL_TIMESTEP = 10.0
_FIELDS = ("observations", "actions", "rewards", "states", "control_timestep")


class TraceError(ValueError):
    """An episode trace that is malformed, inconsistent or too large."""


@dataclass(frozen=True)
class EpisodeTrace:
    """One episode as plain numbers: `T` steps, `T + 1` observations and states.

    `observations[i]` and `states[i]` are the observation and the MuJoCo physics state
    (`mj_getState` with `STATE_SPEC`: qpos, qvel, act) before action `actions[i]`, which earned
    `rewards[i]`; the last row of each is the state after the last action. `states` is None for
    an environment that is not a `MujocoEnvironment` (then only the plot can be drawn), and
    `control_timestep` (seconds between actions) is None for one that does not declare it.
    Constructing a trace validates it (`TraceError`) and makes read-only float64 copies.
    """

    observations: np.ndarray
    actions: np.ndarray
    rewards: np.ndarray
    states: Optional[np.ndarray]
    control_timestep: Optional[float]

    def __post_init__(self) -> None:
        observations = _finite_array(self.observations, "observations", 2)
        actions = _finite_array(self.actions, "actions", 2)
        rewards = _finite_array(self.rewards, "rewards", 1)
        steps = len(rewards)
        if steps < 1:
            raise TraceError("invalid episode trace: no steps")
        if len(actions) != steps or len(observations) != steps + 1:
            raise TraceError(
                f"invalid episode trace: {steps} rewards need {steps} actions and {steps + 1} observations, "
                f"got {len(actions)} and {len(observations)}"
            )
        arrays = [observations, actions, rewards]
        states = None
        if self.states is not None:
            states = _finite_array(self.states, "states", 2)
            if len(states) != steps + 1:
                raise TraceError(f"invalid episode trace: {steps + 1} states expected, got {len(states)}")
            arrays.append(states)
        if sum(array.size for array in arrays) > MAX_VALUES:
            raise TraceError(f"invalid episode trace: more than {MAX_VALUES} numbers")
        timestep = self.control_timestep
        if timestep is not None:
            if isinstance(timestep, bool) or not isinstance(timestep, (int, float, np.floating)):
                raise TraceError(f"invalid episode trace: control_timestep is a {type(timestep).__name__}")
            timestep = float(timestep)
            if not 0.0 < timestep <= MAX_CONTROL_TIMESTEP:  # also false for NaN
                raise TraceError(f"invalid episode trace: control_timestep {timestep} is not in (0, {MAX_CONTROL_TIMESTEP}]")
        for name, value in (("observations", observations), ("actions", actions), ("rewards", rewards), ("states", states)):
            object.__setattr__(self, name, value)
        object.__setattr__(self, "control_timestep", timestep)

    @property
    def steps(self) -> int:
        return len(self.rewards)

    @property
    def episode_return(self) -> float:
        return float(self.rewards.sum())

    def to_dict(self) -> dict:
        """The trace as JSON-compatible lists and numbers (floats round-trip exactly)."""
        return {
            "observations": self.observations.tolist(),
            "actions": self.actions.tolist(),
            "rewards": self.rewards.tolist(),
            "states": None if self.states is None else self.states.tolist(),
            "control_timestep": self.control_timestep,
        }

    @classmethod
    def from_dict(cls, data: object) -> EpisodeTrace:
        """The trace `to_dict` made; `TraceError` for anything else."""
        if not isinstance(data, dict) or set(data) != set(_FIELDS):
            keys = sorted(map(str, data)) if isinstance(data, dict) else type(data).__name__
            raise TraceError(f"invalid episode trace: expected an object with keys {list(_FIELDS)}, got {keys}")
        return cls(**{name: data[name] for name in _FIELDS})

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), allow_nan=False, separators=(",", ":"))

    @classmethod
    def from_json(cls, text: str | bytes, max_chars: int = MAX_JSON_CHARS) -> EpisodeTrace:
        """Parse and validate a trace stored or sent as JSON, refusing one over `max_chars`
        before parsing it."""
        if len(text) > max_chars:
            raise TraceError(f"invalid episode trace: {len(text)} characters, more than {max_chars}")
        try:
            data = json.loads(text)
        except (ValueError, RecursionError) as error:  # JSONDecodeError and UnicodeDecodeError are ValueErrors
            raise TraceError(f"invalid episode trace: not JSON ({type(error).__name__})") from None
        return cls.from_dict(data)


def _finite_array(value: object, name: str, ndim: int) -> np.ndarray:
    """`value` as a read-only float64 array of `ndim` dimensions with finite entries, or `TraceError`."""
    if isinstance(value, (list, tuple)) and len(value) > MAX_STEPS + 1:
        raise TraceError(f"invalid episode trace: {name} has more than {MAX_STEPS + 1} rows")
    try:
        array = np.asarray(value)
    except (ValueError, TypeError, RecursionError) as error:  # ragged or deeply nested lists
        raise TraceError(f"invalid episode trace: {name} is not a {ndim}-d array of numbers ({type(error).__name__})") from None
    # Only numbers: numpy would otherwise convert strings ("1.5") or take objects.
    if array.dtype.kind not in "iuf" or array.ndim != ndim:
        raise TraceError(f"invalid episode trace: {name} is not a {ndim}-d array of numbers (dtype {array.dtype}, {array.ndim}-d)")
    if len(array) > MAX_STEPS + 1 or (ndim == 2 and not 1 <= array.shape[1] <= MAX_WIDTH):
        raise TraceError(f"invalid episode trace: {name} has shape {array.shape}")
    array = np.array(array, dtype=np.float64)  # a copy: the trace owns its arrays
    if not np.isfinite(array).all():
        raise TraceError(f"invalid episode trace: {name} has non-finite values")
    array.flags.writeable = False
    return array


def physics_state(env: MujocoEnvironment) -> np.ndarray:
    """The environment's current physics state (`mj_getState` with `STATE_SPEC`)."""
    state = np.empty(mujoco.mj_stateSize(env.model, STATE_SPEC))
    mujoco.mj_getState(env.model, env.data, state, STATE_SPEC)
    return state


class TraceRecorder:
    """Records one episode of `env` as its stepper (the referee) drives it: `start` with the
    first observation after `reset`, `step` after every `env.step`, then `finish`. The caller
    bounds the episode: `finish` refuses more than `MAX_STEPS` steps."""

    def __init__(self, env: Environment):
        self.env = env
        self.mujoco = env if isinstance(env, MujocoEnvironment) else None
        self.observations: list[np.ndarray] = []
        self.actions: list[np.ndarray] = []
        self.rewards: list[float] = []
        self.states: Optional[list[np.ndarray]] = [] if self.mujoco else None

    def start(self, obs: np.ndarray) -> None:
        """Begin the episode whose first observation is `obs`, forgetting any recorded before."""
        self.observations, self.actions, self.rewards = [], [], []
        self.states = [] if self.mujoco else None
        self._observe(obs)

    def step(self, action: np.ndarray, reward: float, obs: np.ndarray) -> None:
        """Record `action`, applied to the last observation, its `reward` and the observation reached."""
        self.actions.append(np.array(action, dtype=np.float64))
        self.rewards.append(float(reward))
        self._observe(obs)

    def finish(self) -> EpisodeTrace:
        """The validated trace of the episode recorded since `start`."""
        return EpisodeTrace(
            observations=np.array(self.observations),
            actions=np.array(self.actions),
            rewards=np.array(self.rewards),
            states=None if self.states is None else np.array(self.states),
            control_timestep=getattr(self.env, "control_timestep", None),
        )

    def _observe(self, obs: np.ndarray) -> None:
        # Copies: an environment may return a view of its simulation state.
        self.observations.append(np.array(obs, dtype=np.float64))
        if self.states is not None:
            self.states.append(physics_state(self.mujoco))
