"""`colmo-evaluate task=... policy_file=... [episodes=100]` (or `python -m colmo.heldout`): score
one policy file on held-out episodes (`colmo.heldout`).

    colmo-evaluate task=pendulum policy_file=best_policy.py episodes=1000

Its last stdout line is a JSON object (`score`, `episodes`, `returns`, ...), also written to
`result.json` in the run directory with the run's provenance; a policy that fails exits 1.
With `robustness=true` it also scores the policy under model mismatch (`colmo.robustness`) on
`robustness_episodes` held-out episodes per grid point (with
`robustness_precision`, more until each point's interval holds it), prints the
table, writes `robustness.{json,csv,png}` into the run directory and adds `robustness` (one
entry per magnitude, nominal first) and `delay` to the JSON line. With `coverage=true` it
counts what each branch of the policy did over the held-out episodes (`colmo.coverage`), prints
the policy with those counts as comments and adds `coverage` to the JSON line. Every comparison
that the policy's code decides within the spec's observation bounds (`colmo.bounds`) is printed,
`decided by the code: ...`, and listed in the JSON line's `decided`.
"""

from __future__ import annotations

import sys
from pathlib import Path

from colmo import coverage
from colmo.bounds import decided_comparisons
from colmo.cli import hydra_app
from colmo.config import EvaluateConfig
from colmo.heldout import heldout_score, robustness_of
from colmo.policy_tools import PolicySession, check_policy_file, policy_session, print_result, run_directory, write_result_file
from colmo.program import instantiate
from colmo.record import finite_or_none
from colmo.robustness import save, table


@hydra_app("evaluate", check=check_policy_file)
def main(cfg: EvaluateConfig) -> None:
    """Score a policy file with the referee on fresh episodes of the task."""
    with policy_session(cfg) as session:
        program = session.program
        evaluation = heldout_score(session.executor, session.heldout(cfg.episodes), program.skeleton, program.values)
        report = robustness_of(
            session.executor, session.evaluator, program.skeleton, program.values, cfg.seed, cfg.robustness_episodes,
            cfg.robustness_magnitudes, cfg.robustness_delays, cfg.robustness_precision, cfg.robustness_max_episodes,
        ) if cfg.robustness else None
        counted = branch_coverage(session, cfg.episodes) if cfg.coverage else None
    print(f"held-out score over {cfg.episodes} episodes: " + (f"{evaluation.score:.2f}" if not evaluation.failure else f"failed: {evaluation.failure}"))
    result = {
        "task": cfg.task.name, "policy_file": cfg.policy_file, "episodes": cfg.episodes, "seed": cfg.seed,
        "score": finite_or_none(evaluation.score), "returns": list(evaluation.returns), "failure": evaluation.failure,
        "seconds": round(evaluation.seconds, 3),
    }
    if report is not None:
        episodes = len(report.nominal.returns)
        print(f"robustness over {episodes} held-out episodes per point:\n{table(report)}")
        for failure in report.failures():
            print(f"  failed: {failure}")
        paths = save(report, run_directory(), f"{cfg.task.name}: {Path(cfg.policy_file).name}")
        print("wrote " + ", ".join(str(path) for path in paths))
        grid = report.as_json()
        grid["robustness_episodes"] = grid.pop("episodes")  # the grid's, beside the held-out score's `episodes`
        result |= grid
    if counted is not None:
        print(counted.pop("annotated"))
        result["coverage"] = counted
    result["decided"] = [str(d) for d in decided_comparisons(instantiate(program.skeleton, program.values), session.spec.observation_bounds)]
    for line in result["decided"]:
        print(f"decided by the code: {line}")
    write_result_file(result)
    print_result(result)
    if evaluation.failure:
        sys.exit(1)


def branch_coverage(session: PolicySession, episodes: int) -> dict:
    """What each branch of the session's policy did over `episodes` held-out episodes
    (`colmo.coverage.summary`), with `annotated`: the policy's code with the counts as comments;
    `failure` instead where the fast path failed."""
    heldout = session.heldout(episodes)
    counted = session.branch_counts(heldout)
    if counted.failure or counted.coverage is None:
        return {"failure": counted.failure or "no counts", "annotated": "branch coverage: failed"}
    code = instantiate(session.program.skeleton, session.program.values)
    return coverage.summary(code, counted.coverage, len(heldout.seeds)) | {"annotated": coverage.annotate(code, counted.coverage)}

if __name__ == "__main__":
    main()
