"""Tasks: the simulated systems a policy is scored on, and the closed-loop rollout that scores it.

An `Environment` is reset with an episode seed and stepped with an action; it returns
`(reward, observation)`. `MujocoEnvironment` steps a compiled MuJoCo model directly,
reproducing dm_control's `control.Environment` exactly (same reset, same sub-stepping,
same observations) without its per-step Python bookkeeping. `evaluate_program` runs a
fresh instance of a policy for each of a list of episode seeds and returns the per-episode
returns, or the reason it failed; it never raises for anything the policy does. `episode_seeds` and `heldout_seeds`
name the training and held-out episodes of a run.
"""

from __future__ import annotations

import abc
import copy
from typing import Callable, Sequence

import mujoco
import numpy as np

from colmo.errors import describe_exception
from colmo.evaluation import Evaluation, Race

Policy = Callable[[np.ndarray], object]

_INSTABILITY_WARNINGS = (
    mujoco.mjtWarning.mjWARN_BADQPOS,
    mujoco.mjtWarning.mjWARN_BADQVEL,
    mujoco.mjtWarning.mjWARN_BADQACC,
)


_MAX_CACHED_RESETS = 1024


class PolicyFailure(Exception):
    """The policy, or the simulation it drove, failed; the message is the stored reason."""


class Environment(abc.ABC):
    """A deterministic episodic control task: same seed and actions, same rewards."""

    observation_size: int
    action_size: int
    horizon: int = 1000

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
        self._initial_states: dict[int, mujoco.MjData] = {}

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
        if initial is None:
            mujoco.mj_resetData(self.model, self.data)
            self.forward_unactuated()
            self.initialize_episode(np.random.RandomState(seed))
            self.forward_unactuated()
            if len(self._initial_states) < _MAX_CACHED_RESETS:
                self._initial_states[seed] = copy.copy(self.data)
        else:
            mujoco.mj_copyData(self.data, self.model, initial)
        return self.observation()

    def step(self, action: np.ndarray) -> tuple[float, np.ndarray]:
        # As in dm_control, MuJoCo clamps controls of limited actuators to their range.
        self.data.ctrl[:] = action
        mujoco.mj_step2(self.model, self.data)
        if self.n_sub_steps > 1:
            mujoco.mj_step(self.model, self.data, self.n_sub_steps - 1)
        mujoco.mj_step1(self.model, self.data)
        return self.reward(), self.observation()

    def check_episode(self) -> None:
        # MuJoCo resets a diverged state by itself and only counts a warning, so an unstable
        # episode would otherwise go on scoring garbage; one check per episode is enough.
        for warning in _INSTABILITY_WARNINGS:
            if self.data.warning[warning].number:
                raise PolicyFailure(f"unstable simulation: {warning.name} at time {self.data.warning[warning].lastinfo}")


def episode_seeds(seed: int, episodes: int) -> list[int]:
    """Fixed episode seeds derived from the run seed (common random numbers for every candidate)."""
    return [int(s) for s in np.random.SeedSequence(seed).generate_state(episodes)]


def heldout_seeds(seed: int, episodes: int, training: Sequence[int]) -> list[int]:
    """`episodes` seeds for held-out evaluation: from their own stream of the run seed, and
    disjoint from the `training` seeds."""
    excluded = set(training)
    stream = np.random.SeedSequence([seed, 1]).generate_state(episodes + len(excluded))
    return [int(s) for s in stream if int(s) not in excluded][:episodes]


_REAL_KINDS = frozenset("biuf")  # bool, signed and unsigned integers, floats


def as_action(raw: object, action_size: int) -> np.ndarray:
    """The policy's output as a finite `(action_size,)` float array, or `PolicyFailure` saying
    what is wrong. Only real numbers are actions: strings, bytes, complex numbers, dates and
    arbitrary objects are refused even where numpy would convert them."""
    try:
        array = np.asarray(raw)
        if array.dtype.kind == "O":  # a sequence mixing numbers and size-1 arrays, or arbitrary objects
            array = np.asarray([np.asarray(item).item() if _is_real_scalar(item) else _refuse(item) for item in np.ravel(array)])
        if array.dtype.kind not in _REAL_KINDS:
            raise PolicyFailure(f"bad action: {array.dtype} values are not real numbers")
        action = array.astype(np.float64)
    except (TypeError, ValueError, OverflowError) as error:
        raise PolicyFailure(f"bad action: {type(raw).__name__} is not numeric ({error})") from None
    if action.shape != (action_size,):
        if action.size == action_size and action.ndim <= 1:
            action = action.reshape(action_size)
        else:
            raise PolicyFailure(f"bad action shape: {action.shape}, expected ({action_size},)")
    if not np.isfinite(action).all():
        raise PolicyFailure("non-finite action")
    return action


def _is_real_scalar(item: object) -> bool:
    if isinstance(item, (int, float, np.integer, np.floating, np.bool_)):
        return True
    return isinstance(item, np.ndarray) and item.size == 1 and item.dtype.kind in _REAL_KINDS


def _refuse(item: object) -> float:
    raise PolicyFailure(f"bad action: an entry of type {type(item).__name__} is not a real number")


def act(policy: Policy, obs: np.ndarray, action_size: int, step: int) -> np.ndarray:
    """The policy's checked action for `obs` at control step `step` of an episode; raises
    `PolicyFailure` with the reason if the policy fails or its output is not an action."""
    try:
        raw = policy(obs)
    except Exception as error:  # the policy is untrusted code: any error is its failure
        raise PolicyFailure(describe_exception(error, f" (step {step})")) from None
    try:
        return as_action(raw, action_size)
    except PolicyFailure as failure:
        raise PolicyFailure(f"{failure} (step {step})") from None


def rollout(env: Environment, policy: Policy, seed: int, steps: int | None = None) -> tuple[float, int]:
    """Return of one episode and the control steps it took; raises `PolicyFailure` with the
    reason if anything goes wrong."""
    # Policies may draw from np.random (the paper's quadruped policy adds noise): seeding it per
    # episode keeps the objective a deterministic function of the parameters.
    np.random.seed(seed % 2**32)
    obs = env.reset(seed)
    total = 0.0
    horizon = steps or env.horizon
    for step in range(horizon):
        # A copy: an environment may return a view of its simulation state (`self.data.qpos`),
        # which a policy writing to its `obs` would otherwise change.
        reward, obs = env.step(act(policy, obs.copy(), env.action_size, step))
        total += reward
    env.check_episode()
    return total, horizon


def evaluate_policy(env: Environment, policy: Policy, seeds: Sequence[int], steps: int | None = None, race: Race | None = None) -> Evaluation:
    """`evaluate_program` with one policy object for every episode: for trusted in-process
    callers whose policy keeps no state."""
    return evaluate_program(env, lambda seed: policy, seeds, steps, race)


def evaluate_program(
    env: Environment, new_policy: Callable[[int], Policy], seeds: Sequence[int], steps: int | None = None, race: Race | None = None,
) -> Evaluation:
    """Mean-return evaluation over `seeds`, in order, each episode run by the fresh policy that
    `new_policy(seed)` makes (it raises `PolicyFailure` when it cannot); a failure in any
    episode fails the whole evaluation; with `race`, the episodes stop once the candidate gives
    up (`Race.gives_up`)."""
    returns: list[float] = []
    simulated = 0
    for seed in seeds:
        try:
            policy = new_policy(seed)
            episode_return, episode_steps = rollout(env, policy, seed, steps)
        except PolicyFailure as failure:
            return Evaluation(tuple(returns), str(failure), simulated)
        except RecursionError:
            return Evaluation(tuple(returns), "exception: RecursionError: maximum recursion depth exceeded", simulated)
        returns.append(episode_return)
        simulated += episode_steps
        if race is not None and race.gives_up(returns):
            return Evaluation(tuple(returns), None, simulated, raced_out=True)
    return Evaluation(tuple(returns), None, simulated)
