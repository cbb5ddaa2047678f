"""The closed-loop rollout that scores a policy, and the episode seeds of a run.

`evaluate_program` runs a fresh instance of a policy for each of a list of episode seeds and
returns the per-episode returns, or the reason it failed; it never raises for anything the
policy does. `as_action` is the one check of what a policy returns. `episode_seeds` and
`heldout_seeds` name the training and held-out episodes of a run.
"""

from __future__ import annotations

import math
from typing import Callable, Sequence

import numpy as np

from colmo.environments.base import Environment, PolicyFailure
from colmo.errors import describe_exception
from colmo.evaluation import Evaluation
from colmo.racing import Race

Policy = Callable[[np.ndarray], object]


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
_FLOAT64 = np.dtype(np.float64)


def as_action(raw: object, action_size: int) -> np.ndarray:
    """The policy's output as a finite `(action_size,)` float array, or `PolicyFailure` saying
    what is wrong. Only real numbers are actions: strings, bytes, complex numbers, dates and
    arbitrary objects are refused even where numpy would convert them."""
    # What policies return nearly always, a float or a float64 array of the right shape, is
    # checked without numpy's per-call costs, in a fifth to a half of the general path's time
    # (which, at every control step of every episode, took longer than a typical pendulum
    # policy itself); the result is the same array. Exact types only: a subclass, a float32 or
    # a non-finite value takes the general path.
    kind = type(raw)
    if kind is float or kind is np.float64:
        if action_size == 1 and math.isfinite(raw):
            return np.array((float(raw),))
    elif kind is np.ndarray and raw.dtype == _FLOAT64 and raw.shape == (action_size,):
        action = raw.copy()
        # A finite sum means finite values; finite values whose sum overflows take the general path.
        if math.isfinite(sum(action.tolist())):
            return action
    if raw is None:
        raise PolicyFailure("bad action: the policy returned None (it reached no return statement)")
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
