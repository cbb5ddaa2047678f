"""`python -m colmo.optimize task=... policy_file=... gfo=...`: tune one policy's constants.

Prints the policy's score with its own constants, the tuned readable policy and its score;
the last line of stdout is one JSON object. Also writes `result.json` and `tuned_policy.py`
to the Hydra run directory.
"""

from __future__ import annotations

import json
import logging
import sys
from pathlib import Path

from hydra.core.hydra_config import HydraConfig

from colmo.config import ConfigError, OptimizeConfig, hydra_app
from colmo.extract import ExtractionError, extract_policy
from colmo.optimize import finite_or_none, optimize_program
from colmo.program import ProgramError, parametrize
from colmo.executor import make_executor
from colmo.sandbox import ForbiddenProgram, batch_evaluator, check_program
from colmo.spec import load_task_spec
from colmo.task import episode_seeds

log = logging.getLogger("colmo.optimize")


def read_policy(path: str, allowed_imports: tuple[str, ...]):
    """The parametrized program in `path`; `ConfigError` if there is no usable policy."""
    file = Path(path).expanduser()
    if not file.is_file():
        raise ConfigError(f"policy_file not found: {path}")
    try:
        program = parametrize(extract_policy(file.read_text()))
        check_program(program.skeleton, allowed_imports)
    except (ExtractionError, ProgramError, ForbiddenProgram) as error:
        raise ConfigError(f"no usable policy in {path}: {error}") from None
    return program


def check_inputs(cfg: OptimizeConfig) -> None:
    """The spec file loads and the policy file holds a usable policy."""
    read_policy(cfg.policy_file, load_task_spec(cfg.task.spec).allowed_imports)


@hydra_app("optimize", check=check_inputs)
def main(cfg: OptimizeConfig) -> None:
    spec = load_task_spec(cfg.task.spec)
    program = read_policy(cfg.policy_file, spec.allowed_imports)
    seeds = episode_seeds(cfg.seed, cfg.task.episodes)
    log.info("%s: %d parameters, gfo=%s budget=%d, %d episodes", cfg.policy_file, program.n_params, cfg.gfo.method, cfg.gfo.budget, len(seeds))

    executor = make_executor(cfg.executor, max_workers=cfg.gfo.workers)
    try:
        evaluate_batch = batch_evaluator(executor, spec, cfg.task.env, seeds, program.skeleton)
        result = optimize_program(program, evaluate_batch, cfg.gfo, cfg.seed)
    finally:
        executor.close()

    print(f"score with its own constants: {result.initial.score:.2f}" + (f" (failed: {result.initial.failure})" if result.initial.failure else ""))
    if not result.failure:
        print(f"tuned policy ({result.evaluations} evaluations, {result.seconds:.1f} s):\n")
        print(result.code)
        print(f"score: {result.score:.2f}")
    summary = {
        "score_initial": finite_or_none(result.initial.score),
        "score": finite_or_none(result.score),
        "n_params": program.n_params,
        "evaluations": result.evaluations,
        "seconds": round(result.seconds, 3),
        "gfo": cfg.gfo.method,
        "task": cfg.task.name,
        "episodes": len(seeds),
        "returns": list(result.evaluation.returns),
        "params": list(result.params),
        "failure": result.failure,
        "code": result.code,
    }
    output_dir = Path(HydraConfig.get().runtime.output_dir)
    (output_dir / "result.json").write_text(json.dumps(summary, indent=2))
    (output_dir / "tuned_policy.py").write_text(result.code)
    print(json.dumps(summary))
    if result.failure:
        print(f"colmo: the policy failed: {result.failure}", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
