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

import logging
import sys
import time

from colmo.cli import hydra_app
from colmo.config import OptimizeConfig
from colmo.heldout import heldout_score
from colmo.optimize.tune import optimize_alone
from colmo.policy_tools import check_policy_file, policy_session, print_result, write_result
from colmo.record import finite_or_none
from colmo.trackers import make_tracker

log = logging.getLogger("colmo.optimize")


@hydra_app("optimize", check=check_policy_file)
def main(cfg: OptimizeConfig) -> None:
    """Tune the constants of one policy file with a gradient-free optimizer."""
    started = time.time()
    with policy_session(cfg) as session:
        executor, evaluator, program = session.executor, session.evaluator, session.program
        log.info("%s: %d parameters, gfo=%s budget=%d, %d episodes", cfg.policy_file, program.n_params, cfg.gfo.method, cfg.gfo.budget, len(evaluator.seeds))
        result = optimize_alone(executor, evaluator, program, cfg.gfo, cfg.seed)
        heldout = None
        if not result.failure:
            heldout = heldout_score(executor, session.heldout(cfg.heldout.episodes), program.skeleton, result.params)

    print(f"score with its own constants: {result.initial.score:.2f}" + (f" (failed: {result.initial.failure})" if result.initial.failure else ""))
    heldout_value = finite_or_none(heldout.score) if heldout else None
    if not result.failure:
        print(f"tuned policy ({result.evaluations} evaluations, {result.steps:,} control steps, {result.seconds:.1f} s):\n")
        print(result.code)
        heldout_text = f"{heldout_value:.2f}" if heldout_value is not None else f"failed ({heldout.failure})"
        print(f"score: {result.score:.2f} (training, {len(evaluator.seeds)} episodes); held-out: {heldout_text} ({cfg.heldout.episodes} episodes)")
    summary = {
        "score_initial": finite_or_none(result.initial.score), "score": finite_or_none(result.score), "heldout_score": heldout_value,
        "n_params": program.n_params, "evaluations": result.evaluations, "steps": result.steps, "raced_out": result.raced_out,
        "seconds": round(result.seconds, 3), "gfo": cfg.gfo.method, "task": cfg.task.name, "episodes": len(evaluator.seeds),
        "heldout_episodes": cfg.heldout.episodes, "returns": list(result.evaluation.returns), "params": list(result.params),
        "failure": result.failure, "code": result.code,
    }
    header = f"# tuned by colmo-optimize (gfo={cfg.gfo.method}): training score {result.score:.2f}"
    header += f", held-out {heldout_value:.2f}\n" if heldout_value is not None else "\n"
    written = write_result(summary, "tuned_policy.py", header + result.code + "\n")
    where = make_tracker(cfg.tracker).record_optimize(cfg, summary, written, started)
    if where:
        print(where, file=sys.stderr)
    print_result(summary)
    if result.failure:
        print(f"colmo: the policy failed: {result.failure}", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
