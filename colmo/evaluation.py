"""Evaluations as plain data: what crosses from the search to a sandbox and back, and the
`Executor` protocol that carries it.

- `EvalRequest`: one candidate evaluation (spec path, environment options, episode seeds,
  skeleton code, parameters, allowed imports, and how to run it). Only plain data, so any
  executor (local processes, a Ray cluster) can carry it.
- `Evaluation`: its outcome: per-episode returns or the failure reason, the control steps
  simulated, whether racing (`colmo.racing`) cut it short, and what was asked for besides (the
  referee's recorded episode, the program's branch coverage).
- `Executor`: anything that evaluates batches of requests, results in request order.
- `Evaluator`: a task's evaluation settings, which make the request for a program.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Optional, Protocol, Sequence

import numpy as np

from colmo.coverage import Counts, added, checked_counts
from colmo.errors import failure_reason
from colmo.racing import Race

if TYPE_CHECKING:
    from colmo.specs import Spec

# Where a policy's score is measured: `fast`, in one sandboxed process that runs the simulator
# and the policy together (what GFO candidates use); `referee`, in a trusted process that owns
# the simulator and the reward while the policy runs in a separate confined process that only
# sees observations and returns actions (what final scores use: a program cannot forge it).
FAST, REFEREE = "fast", "referee"
PROVISIONAL_TIMEOUT_S = 600.0  # before a task's time limits are known
# What a reply from a sandbox may claim, past which it is forged: control steps per episode (the
# longest task runs 1000; a spec's horizon 10,000 times longer is not a control task), and the
# size of a return (a reward of 10**6 per step for 10**6 steps; past it a mean loses its digits).
_MAX_EPISODE_STEPS = 10**7
_MAX_ABS_RETURN = 1e12


@dataclass(frozen=True)
class EvalRequest:
    """One candidate evaluation, as plain data."""

    spec: str
    env: tuple[tuple[str, Any], ...]
    seeds: tuple[int, ...]
    skeleton: str
    params: tuple[float, ...]
    allowed_imports: tuple[str, ...]
    steps: Optional[int] = None  # episodes cut to this many control steps (a probe); None: whole
    mode: str = FAST
    timeout_s: float = PROVISIONAL_TIMEOUT_S  # wall-clock limit for the whole request
    memory_mb: int = 4096  # address-space limit of the process running the policy
    race: Optional[Race] = None
    trace: bool = False  # referee mode: also record the episode (`colmo.trace.EpisodeTrace`)
    coverage: bool = False  # also count what each branch of the program did (`colmo.coverage`)
    label: str = ""  # what is evaluated, for the executor's messages ("sample 12"); workers ignore it


@dataclass(frozen=True)
class Evaluation:
    """The outcome of running one policy on a list of episode seeds."""

    returns: tuple[float, ...] = ()
    failure: Optional[str] = None
    steps: int = 0  # control steps simulated
    raced_out: bool = False  # racing stopped it early: `returns` covers the first episodes only
    seconds: float = 0.0  # wall time of the evaluation, measured by the (trusted) sandbox worker
    trace: Optional[dict] = None  # the recorded episode, as `EpisodeTrace.to_dict()`, when asked for
    coverage: Optional[tuple[Counts, ...]] = None  # per branch site (`colmo.coverage`), when asked for

    @property
    def score(self) -> float:
        """Mean return (over the episodes run); -inf for a failed evaluation, so it loses
        every comparison."""
        return -math.inf if self.failure or not self.returns else float(np.mean(self.returns))

    @classmethod
    def joined(cls, parts: Sequence["Evaluation"]) -> "Evaluation":
        """One evaluation from the evaluations of consecutive parts of the seeds: the first
        failure, every return in order, and the workers' time over all parts."""
        if len(parts) == 1:
            return parts[0]
        returns = tuple(r for part in parts for r in part.returns)
        failure = next((part.failure for part in parts if part.failure), None)
        return cls(
            returns, failure, sum(part.steps for part in parts), any(part.raced_out for part in parts), sum(part.seconds for part in parts),
            coverage=added([part.coverage for part in parts]),
        )

    def to_bytes(self) -> bytes:
        """The evaluation as JSON (what a sandbox process sends back)."""
        failure = failure_reason(self.failure) if self.failure else None
        returns = [float(r) for r in self.returns]
        fields = {"returns": returns, "failure": failure, "steps": int(self.steps), "raced_out": bool(self.raced_out), "seconds": float(self.seconds)}
        if self.trace is not None:
            fields["trace"] = self.trace
        if self.coverage is not None:
            fields["coverage"] = [list(site) for site in self.coverage]
        return json.dumps(fields).encode()

    @classmethod
    def from_bytes(
        cls, data: bytes, request: Optional[EvalRequest] = None, horizon: Optional[int] = None, max_abs_reward: Optional[float] = None,
    ) -> "Evaluation":
        """An evaluation sent by a sandbox process, checked field by field: it is data only,
        and with `request` it must fit it: one return per seed (fewer only for a failure, or
        racing where the request races), at most `horizon` (else `_MAX_EPISODE_STEPS`) control
        steps per seed, or the probe's `steps`, and each return within what that many steps
        earn at `max_abs_reward` a step, if the task knows it (else `_MAX_ABS_RETURN`), and a
        trace only where the request asked the referee for one. A failure reason is bounded,
        and one that claims to be an executor's (`EXECUTOR_REASONS`) is marked `program: ...`.
        `ValueError` (saying what is wrong) if it is not a well-formed evaluation."""
        try:
            reply = json.loads(data)
        except RecursionError:  # nested deeper than the decoder's stack: no evaluation is
            raise ValueError("nested too deeply") from None
        if not isinstance(reply, dict):
            raise ValueError("not a JSON object")
        returns, failure, steps = reply.get("returns"), reply.get("failure"), reply.get("steps")
        raced_out, seconds, trace = reply.get("raced_out"), reply.get("seconds"), reply.get("trace")
        counts = None if reply.get("coverage") is None else checked_counts(reply["coverage"])
        if (
            not isinstance(returns, list) or not all(type(r) is float and math.isfinite(r) for r in returns)
            or not isinstance(failure, (str, type(None))) or type(steps) is not int or steps < 0
            or type(raced_out) is not bool or type(seconds) is not float or not math.isfinite(seconds)
            or not isinstance(trace, (dict, type(None)))
        ):
            raise ValueError("a field is missing or of the wrong type")
        if any(abs(r) > _MAX_ABS_RETURN for r in returns):
            raise ValueError(f"a return beyond {_MAX_ABS_RETURN:g}")
        if request is not None:
            if trace is not None and not (request.trace and request.mode == REFEREE):
                raise ValueError("a trace that was not asked for")  # only the worker records one
            if counts is not None and not request.coverage:
                raise ValueError("coverage that was not asked for")
            episodes = len(request.seeds)
            if len(returns) > episodes or (len(returns) < episodes and failure is None and not (raced_out and request.race is not None)):
                raise ValueError(f"{len(returns)} returns for {episodes} episodes")
            if raced_out and request.race is None:
                raise ValueError("raced out of a request that does not race")
            episode_steps = min(request.steps or _MAX_EPISODE_STEPS, horizon or _MAX_EPISODE_STEPS)
            if steps > max(episodes, 1) * episode_steps:
                raise ValueError(f"{'a huge number of' if steps > 10**18 else steps} control steps for {episodes} episodes")
            if max_abs_reward is not None:
                bound = episode_steps * max_abs_reward * (1 + 1e-9)  # a sum of that many rewards, rounded
                if any(abs(r) > bound for r in returns):
                    raise ValueError(f"a return beyond the {bound:.6g} that {episode_steps} steps earn")
        if failure and failure.startswith(EXECUTOR_REASONS):  # the program's text, not the executor's
            failure = f"program: {failure}"
        return cls(tuple(returns), failure_reason(failure) if failure else None, steps, raced_out, seconds, trace, counts)


class ExecutorClosed(RuntimeError):
    """The executor was closed (the search is stopping); no more evaluations."""


# The failure of a request that a closing executor cancelled before it ran.
CANCELLED = "cancelled: the executor was closed"
# How the reasons an executor gives in the coordinator's own process begin (never a sandbox's:
# a cancellation stops the search's finish), so a reply claiming one is marked as the program's.
EXECUTOR_REASONS = ("cancelled:", "lost worker:")


class WorkerLost(Exception):
    """An executor's worker died or cannot be reached (its process killed, its node gone);
    the message says how. Executors retry the request on a fresh worker."""


class Executor(Protocol):
    """Anything that evaluates batches of requests, results in request order (local sandboxed
    processes, a Ray cluster). Thread-safe: several programs' optimizers share one executor."""

    n_workers: int
    closed: bool
    evaluations_done: int
    steps_done: int

    def evaluate(self, requests: Sequence[EvalRequest]) -> list[Evaluation]: ...

    def worker_pids(self) -> list[int]: ...

    @property
    def busy_seconds(self) -> float: ...

    def close(self, cancel: bool = False) -> None: ...


@dataclass(frozen=True)
class Evaluator:
    """Everything about a task's evaluation except the program: which spec, environment
    options, episode seeds, limits. `request(skeleton, params)` makes the plain-data request."""

    spec: str
    env: tuple[tuple[str, Any], ...]
    seeds: tuple[int, ...]
    allowed_imports: tuple[str, ...]
    timeout_s: float  # per fast-path request
    referee_timeout_s: float  # per referee request (slower: a round trip per control step)
    memory_mb: int
    # Worker seconds of the starter's fast-path and referee evaluations on these episodes, which
    # set the time limits (`colmo.optimize.tune.calibrated`); (0, 0) until calibrated.
    calibration: tuple[float, float] = (0.0, 0.0)

    @classmethod
    def for_task(cls, spec: "Spec", env: dict[str, Any], seeds: Sequence[int], memory_mb: int, timeout_s: float = PROVISIONAL_TIMEOUT_S) -> "Evaluator":
        """An evaluator for a task, with the same time limit for both modes until calibrated
        (`colmo.optimize.tune.calibrated`)."""
        return cls(str(spec.path), tuple(sorted(env.items())), tuple(seeds), spec.allowed_imports, timeout_s, timeout_s, memory_mb)

    def request(self, skeleton: str, params: Sequence[float], timeout_s: Optional[float] = None, **options: Any) -> EvalRequest:
        """The request for a program with `params`, limited to `timeout_s` or else to the time
        limit of its mode; `options` are other `EvalRequest` fields."""
        if timeout_s is None:
            timeout_s = self.referee_timeout_s if options.get("mode") == REFEREE else self.timeout_s
        fields = dict(seeds=self.seeds, memory_mb=self.memory_mb) | options
        return EvalRequest(
            self.spec, self.env, skeleton=skeleton, params=tuple(float(p) for p in params), allowed_imports=self.allowed_imports,
            timeout_s=timeout_s, **fields,
        )

    def seed_chunks(self, parts: int) -> list[tuple[int, ...]]:
        """The episode seeds in `parts` consecutive chunks of near-equal size (at least one
        chunk, at most one seed each): one request a chunk, to spread a program's episodes over
        workers."""
        indices = np.array_split(np.arange(len(self.seeds)), max(1, min(parts, len(self.seeds))))
        return [tuple(int(self.seeds[i]) for i in chunk) for chunk in indices]
