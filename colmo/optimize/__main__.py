"""`colmo-optimize task=... policy_file=... gfo=...` (or `python -m colmo.optimize`): tune one
policy's constants.

Prints the policy's score with its own constants, the tuned readable policy, its training
score (measured by the referee) and its held-out score; the last line of stdout is one JSON
object (`score_initial`, `score`, `heldout_score`, `steps`, `evaluations`, `code`, ...). Also
writes `tuned_policy.py` (with its scores in a header) and `result.json` to the Hydra run
directory, and says where; with `tracker=mlflow`, also one MLflow run (`colmo.track`). With
several workers, each candidate's episodes are spread over them when racing is off
(`gfo.racing=false`, or `gfo=bo`); racing runs a candidate's episodes in order in one request,
so that results do not depend on the number of workers, and the referee's final score is still
spread.
"""

from __future__ import annotations

import json
import logging
import sys
import time
from pathlib import Path

from hydra.core.hydra_config import HydraConfig

from colmo.cli import hydra_app
from colmo.config import OptimizeConfig
from colmo.evaluate import heldout_evaluator, heldout_score, task_evaluator
from colmo.executor import make_executor
from colmo.intake import read_policy_file
from colmo.optimize.tune import CandidateEvaluator, optimize_program
from colmo.record import finite_or_none
from colmo.specs import load_task_spec

log = logging.getLogger("colmo.optimize")


def check_inputs(cfg: OptimizeConfig) -> None:
    """The spec file loads and the policy file holds a usable policy."""
    read_policy_file(cfg.policy_file, load_task_spec(cfg.task.spec).allowed_imports)


@hydra_app("optimize", check=check_inputs)
def main(cfg: OptimizeConfig) -> None:
    """Tune the constants of one policy file with a gradient-free optimizer."""
    started = time.time()
    executor = make_executor(cfg.executor)
    try:
        spec, evaluator = task_evaluator(cfg.task, cfg.executor, executor, cfg.seed)
        program = read_policy_file(cfg.policy_file, spec.allowed_imports)
        log.info("%s: %d parameters, gfo=%s budget=%d, %d episodes", cfg.policy_file, program.n_params, cfg.gfo.method, cfg.gfo.budget, len(evaluator.seeds))
        chunks = max(1, executor.n_workers // cfg.gfo.workers)
        result = optimize_program(program, CandidateEvaluator(executor, evaluator, program.skeleton, chunks), cfg.gfo, cfg.seed)
        heldout = None
        if not result.failure:
            heldout = heldout_score(executor, heldout_evaluator(evaluator, cfg.seed, cfg.evaluation.episodes), program.skeleton, result.params)
    finally:
        executor.close()

    print(f"score with its own constants: {result.initial.score:.2f}" + (f" (failed: {result.initial.failure})" if result.initial.failure else ""))
    heldout_value = finite_or_none(heldout.score) if heldout else None
    if not result.failure:
        print(f"tuned policy ({result.evaluations} evaluations, {result.steps:,} control steps, {result.seconds:.1f} s):\n")
        print(result.code)
        heldout_text = f"{heldout_value:.2f}" if heldout_value is not None else f"failed ({heldout.failure})"
        print(f"score: {result.score:.2f} (training, {len(evaluator.seeds)} episodes); held-out: {heldout_text} ({cfg.evaluation.episodes} episodes)")
    summary = {
        "score_initial": finite_or_none(result.initial.score), "score": finite_or_none(result.score), "heldout_score": heldout_value,
        "n_params": program.n_params, "evaluations": result.evaluations, "steps": result.steps, "raced_out": result.raced_out,
        "seconds": round(result.seconds, 3), "gfo": cfg.gfo.method, "task": cfg.task.name, "episodes": len(evaluator.seeds),
        "heldout_episodes": cfg.evaluation.episodes, "returns": list(result.evaluation.returns), "params": list(result.params),
        "failure": result.failure, "code": result.code,
    }
    output_dir = Path(HydraConfig.get().runtime.output_dir)
    (output_dir / "result.json").write_text(json.dumps(summary, indent=2))
    header = f"# tuned by colmo-optimize (gfo={cfg.gfo.method}): training score {result.score:.2f}"
    header += f", held-out {heldout_value:.2f}\n" if heldout_value is not None else "\n"
    (output_dir / "tuned_policy.py").write_text(header + result.code + "\n")
    print(f"wrote {output_dir / 'tuned_policy.py'} and {output_dir / 'result.json'}", file=sys.stderr)
    if cfg.tracker.name == "mlflow":
        from colmo.track import track_optimize

        run_id = track_optimize(cfg, summary, [output_dir / "tuned_policy.py", output_dir / "result.json"], started)
        print(f"MLflow run {run_id} (experiment {cfg.tracker.experiment or cfg.task.name})", file=sys.stderr)
    print(json.dumps(summary))
    if result.failure:
        print(f"colmo: the policy failed: {result.failure}", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
