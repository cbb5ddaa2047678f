"""`python -m colmo.simplify task=... policy_file=...`: shorten one policy, measuring every step.

Prints each accepted step, the simplified code, its training and held-out scores and its size
before and after (AST nodes, lines, parameters); the last line of stdout is one JSON object
(`score_initial`, `score`, `heldout_score_initial`, `heldout_score`, `size_initial`, `size`
(AST nodes), `lines`, `n_params`, `code`, `seconds`, `steps`, ...). Also writes
`simplified_policy.py` (its scores in a header) and `result.json` to the Hydra run directory,
and says where. `simplify.tolerance` is the share of the training score a deletion may cost;
`gfo=none` skips the final re-tuning.
"""

from __future__ import annotations

import json
import logging
import sys
from dataclasses import dataclass, field
from pathlib import Path

from hydra.core.hydra_config import HydraConfig
from omegaconf import MISSING

from colmo.cli import SCHEMAS, hydra_app
from colmo.config import ExecutorConfig, GFOConfig, HeldoutConfig, SimplifyConfig, TaskConfig, option
from colmo.errors import ConfigError
from colmo.evaluate import heldout_evaluator, task_evaluator
from colmo.extract import extract_policy
from colmo.intake import read_policy_file
from colmo.simplify.greedy import SimplifyResult
from colmo.simplify.sandboxed import simplify_program
from colmo.specs import load_task_spec

log = logging.getLogger("colmo.simplify")


@dataclass
class SimplifyAppConfig:
    """`colmo-simplify`: shorten a policy file, every step measured by the referee."""

    task: TaskConfig = MISSING
    gfo: GFOConfig = MISSING
    executor: ExecutorConfig = MISSING
    policy_file: str = option(MISSING, "a .py file with `def policy(obs)`, or a raw language-model answer")
    simplify: SimplifyConfig = field(default_factory=SimplifyConfig)
    evaluation: HeldoutConfig = field(default_factory=HeldoutConfig)
    seed: int = option(0, "episode seeds (training and held-out) and the optimizer's randomness derive from it")

    def __post_init__(self) -> None:
        if self.seed < 0:
            raise ConfigError(f"seed must be >= 0, got {self.seed}")


SCHEMAS[(None, "simplify_schema")] = SimplifyAppConfig


def check_inputs(cfg: SimplifyAppConfig) -> None:
    """The spec file loads and the policy file holds a usable policy."""
    read_policy_file(cfg.policy_file, load_task_spec(cfg.task.spec).allowed_imports)


def _score(value: float) -> str:
    return f"{value:.2f}" if value != float("-inf") else "failed"


def _report(result: SimplifyResult, episodes: int, heldout_episodes: int) -> str:
    before, after = result.size_initial, result.size
    lines = [
        f"{step.size.nodes:5d} nodes  training {_score(step.scores.train):>9}  held-out {_score(step.scores.heldout):>9}  {step.description}"
        for step in result.steps
    ]
    lines += [
        "", result.code, "",
        f"score: {_score(result.scores_initial.train)} -> {_score(result.scores.train)} (training, {episodes} episodes); "
        f"held-out: {_score(result.scores_initial.heldout)} -> {_score(result.scores.heldout)} ({heldout_episodes} episodes)",
        f"size: {before.nodes} -> {after.nodes} AST nodes, {before.lines} -> {after.lines} lines, {before.params} -> {after.params} parameters "
        f"({result.programs_scored} programs scored, {result.seconds:.1f} s)",
    ]
    return "\n".join(lines)


@hydra_app("simplify", check=check_inputs)
def main(cfg: SimplifyAppConfig) -> None:
    """Delete dead code and each part that costs at most simplify.tolerance of the score, then re-tune."""
    from colmo.executor import make_executor

    text = Path(cfg.policy_file).expanduser().read_text(errors="replace")
    executor = make_executor(cfg.executor)
    try:
        spec, evaluator = task_evaluator(cfg.task, cfg.executor, executor, cfg.seed)
        code = extract_policy(text)
        heldout = heldout_evaluator(evaluator, cfg.seed, cfg.evaluation.episodes)
        log.info(
            "%s: simplifying with tolerance %g on %d training and %d held-out episodes, gfo=%s",
            cfg.policy_file, cfg.simplify.tolerance, len(evaluator.seeds), len(heldout.seeds), cfg.gfo.method,
        )
        result = simplify_program(
            executor, evaluator, heldout, code, cfg.gfo, cfg.simplify.tolerance, cfg.seed, cfg.simplify.max_rounds, cfg.simplify.batch_size
        )
    finally:
        executor.close()

    print(_report(result, len(evaluator.seeds), len(heldout.seeds)))
    summary = result.to_json() | {
        "task": cfg.task.name, "policy_file": cfg.policy_file, "tolerance": cfg.simplify.tolerance, "gfo": cfg.gfo.method,
        "episodes": len(evaluator.seeds), "heldout_episodes": len(heldout.seeds), "seed": cfg.seed,
    }
    output_dir = Path(HydraConfig.get().runtime.output_dir)
    (output_dir / "result.json").write_text(json.dumps(summary, indent=2))
    header = (
        f"# simplified by colmo-simplify (tolerance {cfg.simplify.tolerance:g}, gfo={cfg.gfo.method}) from {cfg.policy_file}:\n"
        f"# training score {_score(result.scores_initial.train)} -> {_score(result.scores.train)}, "
        f"held-out {_score(result.scores_initial.heldout)} -> {_score(result.scores.heldout)}; "
        f"{result.size_initial.nodes} -> {result.size.nodes} AST nodes\n"
    )
    (output_dir / "simplified_policy.py").write_text(header + result.code + "\n")
    print(f"wrote {output_dir / 'simplified_policy.py'} and {output_dir / 'result.json'}", file=sys.stderr)
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
