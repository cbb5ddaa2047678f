"""The environment interface every simulated system implements, and dm_control's physics
stepping on a bare MuJoCo model that the shipped tasks (and most spec files) build on.

An `Environment` is reset with an episode seed and stepped with an action; it returns
`(reward, observation)`. `MujocoEnvironment` steps a compiled MuJoCo model directly,
reproducing dm_control's `control.Environment` exactly (same reset, same sub-stepping,
same observations) without its per-step Python bookkeeping. `PolicyFailure` is what the
rollout (`colmo.rollout`) and an environment's episode check raise; its message is the stored reason.
"""

from __future__ import annotations

import abc

import mujoco
import numpy as np

_INSTABILITY_WARNINGS = (
    mujoco.mjtWarning.mjWARN_BADQPOS,
    mujoco.mjtWarning.mjWARN_BADQVEL,
    mujoco.mjtWarning.mjWARN_BADQACC,
)


# What a reset keeps per seed: the state `mj_step` integrates (a few hundred floats), not a copy
# of `MjData`, whose arena is tens of megabytes; the cap bounds a long run's memory.
_INITIAL_STATE = mujoco.mjtState.mjSTATE_INTEGRATION
_MAX_CACHED_RESETS = 100_000


class PolicyFailure(Exception):
    """The policy, or the simulation it drove, failed; the message is the stored reason."""


class Environment(abc.ABC):
    """A deterministic episodic control task: same seed and actions, same rewards."""

    observation_size: int
    action_size: int
    horizon: int = 1000
    # The most |reward| one step can earn, where the task knows it: a sandbox's reply claiming a
    # return beyond horizon x this is forged (None: only colmo's fixed bound applies).
    max_abs_reward: float | None = None

    @abc.abstractmethod
    def reset(self, seed: int) -> np.ndarray:
        """Start the episode that `seed` names; return the first observation."""

    @abc.abstractmethod
    def step(self, action: np.ndarray) -> tuple[float, np.ndarray]:
        """Apply `action` (already of shape `(action_size,)`) for one control period."""

    def check_episode(self) -> None:
        """Raise `PolicyFailure` if the episode just simulated is not trustworthy."""


class MujocoEnvironment(Environment):
    """dm_control's physics stepping on a bare `mujoco.MjModel`.

    dm_control resets with `mj_resetData` and an unactuated `mj_forward` both before and after
    the task places the initial state, and steps as `mj_step2; mj_step(n - 1); mj_step1`, so
    that position-dependent fields (and thus observations) are current after each step.
    A plain `mj_step` loop drifts from it; this class does exactly the same calls.
    """

    def __init__(self, model: mujoco.MjModel, n_sub_steps: int, horizon: int = 1000):
        self.model = model
        self.data = mujoco.MjData(model)
        self.n_sub_steps = n_sub_steps
        self.horizon = horizon
        self.action_size = model.nu
        self.control_timestep = n_sub_steps * model.opt.timestep
        # Every candidate replays the same episode seeds: keep each seed's initial state.
        self._initial_states: dict[int, np.ndarray] = {}

    @abc.abstractmethod
    def initialize_episode(self, random: np.random.RandomState) -> None:
        """Place the initial state, drawing from `random` exactly as the dm_control task does."""

    @abc.abstractmethod
    def observation(self) -> np.ndarray:
        """The flat observation, a new array (the policy may keep or modify it)."""

    @abc.abstractmethod
    def reward(self) -> float:
        """The reward for the state just reached."""

    def forward_unactuated(self) -> None:
        flags = self.model.opt.disableflags
        self.model.opt.disableflags = flags | int(mujoco.mjtDisableBit.mjDSBL_ACTUATION)
        try:
            mujoco.mj_forward(self.model, self.data)
        finally:
            self.model.opt.disableflags = flags

    def reset(self, seed: int) -> np.ndarray:
        initial = self._initial_states.get(seed)
        mujoco.mj_resetData(self.model, self.data)
        if initial is None:
            self.forward_unactuated()
            self.initialize_episode(np.random.RandomState(seed))
            if len(self._initial_states) < _MAX_CACHED_RESETS:
                initial = np.empty(mujoco.mj_stateSize(self.model, _INITIAL_STATE))
                mujoco.mj_getState(self.model, self.data, initial, _INITIAL_STATE)
                self._initial_states[seed] = initial
        else:
            mujoco.mj_setState(self.model, self.data, initial, _INITIAL_STATE)
        # Everything else follows from the integrated state, so a restored reset is the first one.
        self.forward_unactuated()
        return self.observation()

    def step(self, action: np.ndarray) -> tuple[float, np.ndarray]:
        # As in dm_control, MuJoCo clamps controls of limited actuators to their range.
        self.data.ctrl[:] = action
        mujoco.mj_step2(self.model, self.data)
        if self.n_sub_steps > 1:
            mujoco.mj_step(self.model, self.data, self.n_sub_steps - 1)
        mujoco.mj_step1(self.model, self.data)
        return self.reward(), self.observation()

    def applied_actions(self, actions: np.ndarray) -> np.ndarray:
        """`actions` (one row per step) as MuJoCo applies them in `step`: clamped to the control
        range of each actuator whose range is limited, unless the model disables clamping."""
        if self.model.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_CLAMPCTRL):
            return np.array(actions, dtype=np.float64)
        low, high = self.model.actuator_ctrlrange[:, 0], self.model.actuator_ctrlrange[:, 1]
        return np.where(self.model.actuator_ctrllimited.astype(bool), np.clip(actions, low, high), actions)

    def check_episode(self) -> None:
        # MuJoCo resets a diverged state by itself and only counts a warning, so an unstable
        # episode would otherwise go on scoring garbage; one check per episode is enough.
        for warning in _INSTABILITY_WARNINGS:
            if self.data.warning[warning].number:
                raise PolicyFailure(f"unstable simulation: {warning.name} at time {self.data.warning[warning].lastinfo}")
