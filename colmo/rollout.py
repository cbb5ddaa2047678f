"""The closed-loop rollout that scores a policy, and the episode seeds of a run.

`Episodes` holds the one episode loop (seeding, reset, step, reward sum, end check, failure
order, racing), which both scoring paths drive: `evaluate_program`, the fast path, runs a fresh
instance of a policy in process for each of a list of episode seeds and returns the per-episode
returns, or the reason it failed (it never raises for anything the policy does); the referee
(`colmo.sandbox.referee`) steps the same loop with the actions its confined child sends. `act`
and `as_action` are the one check of what a policy returns. `episode_seeds` and `heldout_seeds`
name the training and held-out episodes of a run.
"""

from __future__ import annotations

import math
from typing import Callable, Sequence

import numpy as np

from colmo.environments.base import Environment, PolicyFailure
from colmo.errors import describe_exception
from colmo.evaluation import Evaluation
from colmo.racing import Race
from colmo.trace import TraceRecorder

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


class Episode:
    """One episode in its environment: `np.random` seeded and the environment reset by the
    episode's seed; `Episodes.run` steps it and sums its rewards in `total`."""

    __slots__ = ("index", "env", "obs", "total")

    def __init__(self, index: int, env: Environment, seed: int):
        # Policies may draw from np.random (the paper's quadruped policy adds noise), and so may
        # an environment's reset: seeding it per episode keeps the objective a deterministic
        # function of the parameters.
        np.random.seed(seed % 2**32)
        self.index, self.env, self.total = index, env, 0.0
        self.obs = env.reset(seed)


Actions = Callable[[list[Episode], int], Sequence[np.ndarray]]


class Episodes:
    """The episodes of one evaluation, one per seed, and what running them one after another in
    seed order gives: the first failing episode fails the evaluation and the later ones never
    count; racing is decided on the returns in seed order.

    The one episode loop of both scoring paths: the fast path (`evaluate_program`) runs its
    episodes one at a time with the policy in process, the referee
    (`colmo.sandbox.referee`) runs batches side by side with the actions from its child; both
    step them through `run`, so they agree by construction."""

    def __init__(self, envs: Sequence[Environment], seeds: Sequence[int], steps: int | None = None, race: Race | None = None):
        self.envs, self.seeds, self.race = envs, seeds, race
        self.horizon = steps or envs[0].horizon
        self.returns: list[float] = []  # of the episodes finished, in seed order
        self.failures: dict[int, str] = {}
        self.live: list[Episode] = []
        self.simulated = 0
        self.raced_out = False

    @property
    def settled(self) -> bool:
        """Whether the episodes not run yet can no longer change the evaluation."""
        return self.raced_out or bool(self.failures)

    def fail(self, index: int, reason: str) -> None:
        """Episode `index` failed: run one after another, the episodes after it never start."""
        self.failures[index] = reason
        self.live = [episode for episode in self.live if episode.index < index]

    def run(self, batch: range, actions: Actions, recorder: TraceRecorder | None = None) -> None:
        """Run the episodes `batch` (consecutive indices, episode i in `envs[i % len(envs)]`)
        side by side to their end or failure. At each control step `actions(live, step)` gives
        the live episodes' actions: it reports an episode whose policy fails to `fail`, then
        gives the actions of the episodes still live (`self.live`), in order. `recorder`
        records the steps of a batch of one episode."""
        live = self.live = [Episode(index, self.envs[index % len(self.envs)], self.seeds[index]) for index in batch]
        if recorder is not None:
            recorder.start(live[0].obs)
        simulated = 0
        for step in range(self.horizon):
            if not live:
                break
            chosen = actions(live, step)
            live = self.live
            for episode, action in zip(live, chosen):
                reward, episode.obs = episode.env.step(action)
                episode.total += reward
                if recorder is not None:
                    recorder.step(action, reward, episode.obs)
            simulated += len(live)
        self.simulated += simulated
        for episode in live:
            try:
                episode.env.check_episode()
            except PolicyFailure as failure:
                self.fail(episode.index, str(failure))
        for episode in self.live:  # in seed order, each before any failure
            self.returns.append(episode.total)
            if self.race is not None and self.race.gives_up(self.returns):
                self.raced_out = True
                break

    def evaluation(self) -> Evaluation:
        """What the episodes run so far give, as if run one after another in seed order."""
        returns = tuple(self.returns)
        if self.raced_out:
            return Evaluation(returns, None, self.simulated, raced_out=True)
        failure = self.failures[min(self.failures)] if self.failures else None
        return Evaluation(returns, failure, self.simulated)


def rollout(env: Environment, policy: Policy, seed: int, steps: int | None = None) -> tuple[float, int]:
    """Return of one episode of `policy` and the control steps it took; raises `PolicyFailure`
    with the reason if anything goes wrong."""
    evaluation = evaluate_policy(env, policy, [seed], steps)
    if evaluation.failure is not None:
        raise PolicyFailure(evaluation.failure)
    return evaluation.returns[0], evaluation.steps


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
    episodes = Episodes([env], seeds, steps, race)
    for index, seed in enumerate(seeds):
        try:
            episodes.run(range(index, index + 1), _in_process(new_policy(seed), episodes))
        except PolicyFailure as failure:  # from `new_policy`
            episodes.fail(index, str(failure))
        except RecursionError:
            episodes.fail(index, "exception: RecursionError: maximum recursion depth exceeded")
        if episodes.settled:
            break
    return episodes.evaluation()


def _in_process(policy: Policy, episodes: Episodes) -> Actions:
    """The actions of `policy`, run here, for a batch of one episode."""
    action_size = episodes.envs[0].action_size

    def actions(live: list[Episode], step: int) -> Sequence[np.ndarray]:
        episode = live[0]
        try:
            # A copy: an environment may return a view of its simulation state
            # (`self.data.qpos`), which a policy writing to its `obs` would otherwise change.
            return (act(policy, episode.obs.copy(), action_size, step),)
        except PolicyFailure as failure:
            episodes.fail(episode.index, str(failure))
            return ()
    return actions
