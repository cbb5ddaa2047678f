"""Held-out evaluation: scores on fresh episodes, and `colmo-evaluate` (`python -m colmo.evaluate`).

A search selects programs by their score on the training episodes, so that score flatters the
winner. A held-out score is the referee's mean return over `episodes` other episodes, whose
seeds come from their own stream of the run seed and never coincide with a training seed
(`colmo.rollout.heldout_seeds`): the paper reports 1000 such episodes for the pendulum and the
ball-in-cup. The search scores its best programs this way at the end, `colmo-optimize` its
tuned policy, and

    colmo-evaluate task=pendulum policy_file=best_policy.py episodes=1000

any policy file. Its last stdout line is a JSON object (`score`, `episodes`, `returns`, ...).
With `robustness=true` it also scores the policy under model mismatch (`colmo.robustness`) on
`robustness_episodes` held-out episodes per grid point, prints the table, writes
`robustness.{json,csv,png}` into the run directory and adds `robustness` (one entry per
magnitude, nominal first) and `delay` to the JSON line.
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Optional

from omegaconf import MISSING

from colmo.cli import SCHEMAS, hydra_app
from colmo.config import ExecutorConfig, PerturbConfig, TaskConfig, option
from colmo.environments.perturb import with_perturbation
from colmo.errors import ConfigError
from colmo.evaluation import Evaluation, Evaluator, Executor
from colmo.intake import read_policy_file
from colmo.optimize.tune import CandidateEvaluator, calibrated
from colmo.program import ParametricProgram, parametrize
from colmo.record import finite_or_none
from colmo.robustness import RobustnessReport, robustness_report, save, table
from colmo.rollout import episode_seeds, heldout_seeds
from colmo.specs import Spec, load_task_spec


def heldout_evaluator(evaluator: Evaluator, seed: int, episodes: int) -> Evaluator:
    """`evaluator` on `episodes` held-out episodes of run seed `seed` (time limit scaled)."""
    seeds = heldout_seeds(seed, episodes, evaluator.seeds)
    scale = max(len(seeds) / len(evaluator.seeds), 1.0)
    return replace(evaluator, seeds=tuple(seeds), referee_timeout_s=evaluator.referee_timeout_s * scale)


def heldout_score(executor: Executor, evaluator: Evaluator, skeleton: str, params: tuple[float, ...], timeout_s: Optional[float] = None) -> Evaluation:
    """The referee's evaluation of one program on `evaluator`'s (held-out) episodes, spread over
    the executor's workers; each part limited to `timeout_s` if given."""
    return CandidateEvaluator(executor, evaluator, skeleton, executor.n_workers).referee(params, timeout_s)


def task_evaluator(task: TaskConfig, executor_cfg: ExecutorConfig, executor: Executor, seed: int) -> tuple[Spec, Evaluator]:
    """The spec of a configured task and its evaluator on the training episodes of `seed`, with
    time limits calibrated on the spec's starter policy."""
    spec = load_task_spec(task.spec)
    provisional = Evaluator.for_task(spec, with_perturbation(task.env, task.perturb), episode_seeds(seed, task.episodes), executor_cfg.memory_mb)
    return spec, calibrated(executor, provisional, parametrize(spec.starter_code), executor_cfg.timeout_s)


@dataclass
class EvaluateConfig:
    """`colmo-evaluate`: score a policy file on held-out episodes."""

    task: TaskConfig = MISSING
    executor: ExecutorConfig = MISSING
    policy_file: str = option(MISSING, "a .py file with `def policy(obs)`, or a raw language-model answer")
    episodes: int = option(100, "held-out episodes")
    seed: int = option(0, "the run seed whose held-out episodes are used (disjoint from its training ones)")
    robustness: bool = option(False, "also score the policy over a grid of model-mismatch magnitudes (colmo.robustness)")
    robustness_episodes: int = option(5, "held-out episodes per robustness grid point")
    robustness_magnitudes: list[float] = option([0.05, 0.1, 0.2, 0.4], "relative magnitudes of the robustness grid (0, nominal, is always scored)")
    robustness_delays: list[int] = option([1, 2, 4], "control delays (steps) of the robustness grid")

    def __post_init__(self) -> None:
        if min(self.episodes, self.robustness_episodes) < 1:
            raise ConfigError(f"episodes and robustness_episodes must be >= 1, got {self.episodes} and {self.robustness_episodes}")
        if not all(0 < m < 1 for m in self.robustness_magnitudes):
            raise ConfigError(f"robustness_magnitudes must lie in (0, 1), got {list(self.robustness_magnitudes)}")
        if not all(k >= 1 for k in self.robustness_delays):
            raise ConfigError(f"robustness_delays must be >= 1 step, got {list(self.robustness_delays)}")


def robustness_of(executor: Executor, evaluator: Evaluator, program: ParametricProgram, cfg: EvaluateConfig) -> RobustnessReport:
    """The robustness report of `program` on `cfg.robustness_episodes` held-out episodes, every
    grid point scored by the referee with the task's options plus that point's perturbation."""
    heldout = heldout_evaluator(evaluator, cfg.seed, cfg.robustness_episodes)

    def score(perturb: PerturbConfig) -> Evaluation:
        perturbed = replace(heldout, env=tuple(sorted(with_perturbation(dict(cfg.task.env), perturb).items())))
        return heldout_score(executor, perturbed, program.skeleton, program.values)

    return robustness_report(score, cfg.robustness_magnitudes, cfg.robustness_delays)


SCHEMAS[(None, "evaluate_schema")] = EvaluateConfig


def check_inputs(cfg: EvaluateConfig) -> None:
    read_policy_file(cfg.policy_file, load_task_spec(cfg.task.spec).allowed_imports)


@hydra_app("evaluate", check=check_inputs)
def main(cfg: EvaluateConfig) -> None:
    """Score a policy file with the referee on fresh episodes of the task."""
    from colmo.executor import make_executor

    executor = make_executor(cfg.executor)
    try:
        spec, evaluator = task_evaluator(cfg.task, cfg.executor, executor, cfg.seed)
        program: ParametricProgram = read_policy_file(cfg.policy_file, spec.allowed_imports)
        evaluation = heldout_score(executor, heldout_evaluator(evaluator, cfg.seed, cfg.episodes), program.skeleton, program.values)
        report = robustness_of(executor, evaluator, program, cfg) if cfg.robustness else None
    finally:
        executor.close()
    print(f"held-out score over {cfg.episodes} episodes: " + (f"{evaluation.score:.2f}" if not evaluation.failure else f"failed: {evaluation.failure}"))
    result = {
        "task": cfg.task.name, "policy_file": cfg.policy_file, "episodes": cfg.episodes, "seed": cfg.seed,
        "score": finite_or_none(evaluation.score), "returns": list(evaluation.returns), "failure": evaluation.failure,
        "seconds": round(evaluation.seconds, 3),
    }
    if report is not None:
        from hydra.core.hydra_config import HydraConfig

        print(f"robustness over {cfg.robustness_episodes} held-out episodes per point:\n{table(report)}")
        for failure in report.failures():
            print(f"  failed: {failure}")
        paths = save(report, Path(HydraConfig.get().runtime.output_dir), f"{cfg.task.name}: {Path(cfg.policy_file).name}")
        print("wrote " + ", ".join(str(path) for path in paths))
        result |= {"robustness_episodes": cfg.robustness_episodes, "robustness": report.entries(), "delay": report.delay_entries()}
    print(json.dumps(result))
    if evaluation.failure:
        sys.exit(1)


if __name__ == "__main__":
    main()
