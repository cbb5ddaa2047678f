"""Held-out scoring: a program's score on fresh episodes, and the task evaluator it starts from.

A search selects programs by their score on the training episodes, so that score flatters the
winner. A held-out score is the referee's mean return over `episodes` other episodes, whose
seeds come from their own stream of the run seed and never coincide with a training seed
(`colmo.rollout.heldout_seeds`): the paper reports 1000 such episodes for the pendulum and the
ball-in-cup. The end of a search (`colmo.finish`) scores its best programs this way,
`colmo-optimize` its tuned policy, and `colmo-evaluate` (`colmo.heldout.__main__`) any policy
file, with the robustness report of `robustness_of` on request. A library: it imports no
front end.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable, Optional, Sequence

from colmo.config import ExecutorConfig, PerturbConfig, TaskConfig
from colmo.environments.perturb import with_perturbation
from colmo.evaluation import Evaluation, Evaluator, Executor
from colmo.optimize.tune import CandidateEvaluator, calibrated
from colmo.program import parametrize
from colmo.robustness import RobustnessReport, adaptive_report, perturbed
from colmo.rollout import episode_seeds, heldout_seeds
from colmo.specs import Spec, load_task_spec


def alike(returns: Optional[Sequence[float]]) -> bool:
    """Whether a program's training episodes all returned the same: its task then draws nothing
    at random from an episode's seed (the quadruped's upright start), and a held-out score can
    only repeat the training score."""
    if not returns or len(returns) < 2:
        return False
    return max(returns) - min(returns) <= 1e-9 * max(1.0, abs(max(returns)))


def heldout_evaluator(evaluator: Evaluator, seed: int, episodes: int) -> Evaluator:
    """`evaluator` on `episodes` held-out episodes of run seed `seed` (time limit scaled)."""
    seeds = heldout_seeds(seed, episodes, evaluator.seeds)
    scale = max(len(seeds) / len(evaluator.seeds), 1.0)
    return replace(evaluator, seeds=tuple(seeds), referee_timeout_s=evaluator.referee_timeout_s * scale)


def heldout_score(executor: Executor, evaluator: Evaluator, skeleton: str, params: tuple[float, ...], timeout_s: Optional[float] = None) -> Evaluation:
    """The referee's evaluation of one program on `evaluator`'s (held-out) episodes, spread over
    the executor's workers; each part limited to `timeout_s` if given."""
    return CandidateEvaluator(executor, evaluator, skeleton, executor.n_workers).referee(params, timeout_s)


def branch_counts(executor: Executor, evaluator: Evaluator, skeleton: str, params: Sequence[float], timeout_s: Optional[float] = None) -> Evaluation:
    """The fast path's evaluation of one program on `evaluator`'s episodes, spread over the
    executor's workers, with what each of its branches did (`Evaluation.coverage`,
    `colmo.coverage`); each part limited to `timeout_s` if given."""
    return CandidateEvaluator(executor, evaluator, skeleton, executor.n_workers).coverage(params, timeout_s)


def training_evaluator(spec: Spec, task: TaskConfig, executor_cfg: ExecutorConfig, executor: Executor, seed: int) -> Evaluator:
    """The evaluator of `spec` on the training episodes of `seed` (under `task.perturb`, if
    set), with time limits calibrated on the spec's starter policy."""
    provisional = Evaluator.for_task(spec, with_perturbation(task.env, task.perturb), episode_seeds(seed, task.episodes), executor_cfg.memory_mb)
    return calibrated(executor, provisional, parametrize(spec.starter_code), executor_cfg.timeout_s)


def task_evaluator(task: TaskConfig, executor_cfg: ExecutorConfig, executor: Executor, seed: int) -> tuple[Spec, Evaluator]:
    """The spec of a configured task and its `training_evaluator`."""
    spec = load_task_spec(task.spec)
    return spec, training_evaluator(spec, task, executor_cfg, executor, seed)


def robustness_of(
    executor: Executor, evaluator: Evaluator, skeleton: str, params: Sequence[float], seed: int, episodes: int,
    magnitudes: Sequence[float], delays: Sequence[int], precision: Optional[float] = None, max_episodes: Optional[int] = None,
    may_add: Callable[[int, int], bool] = lambda scored, added: True,
) -> RobustnessReport:
    """The robustness report of a program on `episodes` held-out episodes of run seed `seed`
    (with `precision`, more until it holds, up to `max_episodes` and while `may_add` agrees:
    `colmo.robustness.adaptive_report`),
    every grid point scored by the referee on the task's nominal model plus that point's perturbation."""
    heldout = heldout_evaluator(evaluator, seed, max(episodes, max_episodes or episodes) if precision is not None else episodes)

    def score(perturb: PerturbConfig, start: int, stop: int) -> Evaluation:
        return heldout_score(executor, perturbed(replace(heldout, seeds=heldout.seeds[start:stop]), perturb), skeleton, tuple(params))

    return adaptive_report(score, magnitudes, delays, episodes, precision, max_episodes, may_add)
