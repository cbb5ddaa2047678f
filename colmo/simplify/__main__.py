"""`python -m colmo.simplify task=... policy_file=...`: shorten one policy, measuring every step.

Prints each accepted step, the simplified code, its training and held-out scores and its size
before and after (AST nodes, lines, parameters); the last line of stdout is one JSON object
(`score_initial`, `score`, `heldout_score_initial`, `heldout_score`, `size_initial`, `size`
(AST nodes), `lines`, `n_params`, `code`, `seconds`, `steps`, ...). Also writes
`simplified_policy.py` (its scores in a header) and `result.json` to the Hydra run directory,
and says where. Before the first deletion it counts what each branch of the policy did over the
training and held-out episodes (`colmo.coverage`) and tries the policy without the branches it
never took. `simplify.tolerance` is the share of the training score a deletion may cost;
`simplify.max_constants=K` goes on deleting, past the tolerance, what loses the least score per
constant until at most K tunable constants are left (the report says what that cost, and
`within_budget` whether it got there); `gfo=none` skips the final re-tuning. Ctrl-C (or SIGTERM) stops it at its next step with the
simplification so far, written and reported as above (`"interrupted": true`, exit 130); a second
one quits.
"""

from __future__ import annotations

import logging
import sys
from dataclasses import replace
from pathlib import Path
from typing import Optional

from colmo import coverage
from colmo.cli import hydra_app
from colmo.config import SimplifyAppConfig
from colmo.coverage import Pruned
from colmo.errors import EXIT_INTERRUPTED
from colmo.evaluation import Evaluator
from colmo.extract import extract_policy
from colmo.policy_tools import PolicySession, check_policy_file, policy_session, print_result, write_result
from colmo.signals import stop_signals
from colmo.simplify.greedy import SimplifyResult
from colmo.simplify.sandboxed import simplify_program

log = logging.getLogger("colmo.simplify")


def _score(value: float) -> str:
    return f"{value:.2f}" if value != float("-inf") else "failed"


def _budget(max_constants: Optional[int]) -> str:
    return "" if max_constants is None else f", at most {max_constants} constants"


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
    if result.over_budget:
        lines.append(result.over_budget)
    return "\n".join(lines)


def _untaken_branches(session: PolicySession, code: str, episodes: Evaluator) -> Optional[Pruned]:
    """`code` without the branches it never took over `episodes` (`colmo.coverage.prune`), for
    the simplifier to try first; None where it took every branch both ways or was not counted."""
    if not coverage.same_sites(code, session.program.skeleton):
        return None
    counted = session.branch_counts(episodes)
    if counted.failure or counted.coverage is None:
        return None
    return coverage.prune(code, counted.coverage)


class _Interruption:
    """The first stop signal asks the simplifier to stop at its next step; the second quits."""

    def __init__(self) -> None:
        self.signals = 0

    def __call__(self, signum: int) -> None:
        self.signals += 1
        if self.signals > 1:
            raise KeyboardInterrupt
        log.warning("interrupted: stopping with the simplification so far (again to quit now)")

    def asked(self) -> bool:
        return self.signals > 0


@hydra_app("simplify", check=check_policy_file)
def main(cfg: SimplifyAppConfig) -> None:
    """Delete dead code and each part that costs at most simplify.tolerance of the score, then re-tune."""
    code = extract_policy(Path(cfg.policy_file).expanduser().read_text(errors="replace"))
    interruption = _Interruption()
    with stop_signals(interruption), policy_session(cfg) as session:
        evaluator, heldout = session.evaluator, session.heldout(cfg.heldout.episodes)
        log.info(
            "%s: simplifying with tolerance %g%s on %d training and %d held-out episodes, gfo=%s", cfg.policy_file, cfg.simplify.tolerance,
            _budget(cfg.simplify.max_constants), len(evaluator.seeds), len(heldout.seeds), cfg.gfo.method,
        )
        hint = _untaken_branches(session, code, replace(evaluator, seeds=evaluator.seeds + heldout.seeds))
        result = simplify_program(
            session.executor, evaluator, heldout, code, cfg.gfo, cfg.simplify.tolerance, cfg.seed, cfg.simplify.max_rounds, cfg.simplify.batch_size,
            stop=interruption.asked, max_seconds=cfg.simplify.max_seconds, hint=hint, names=session.spec.observation_names,
            max_constants=cfg.simplify.max_constants,
        )

    print(_report(result, len(evaluator.seeds), len(heldout.seeds)))
    summary = result.to_json() | {
        "task": cfg.task.name, "policy_file": cfg.policy_file, "tolerance": cfg.simplify.tolerance, "gfo": cfg.gfo.method,
        "episodes": len(evaluator.seeds), "heldout_episodes": len(heldout.seeds), "seed": cfg.seed,
        "branches_never_taken": hint.branches if hint else 0, "interrupted": interruption.asked(),
    }
    header = (
        f"# simplified by colmo-simplify (tolerance {cfg.simplify.tolerance:g}{_budget(cfg.simplify.max_constants)}, gfo={cfg.gfo.method}) "
        f"from {cfg.policy_file}:\n"
        f"# training score {_score(result.scores_initial.train)} -> {_score(result.scores.train)}, "
        f"held-out {_score(result.scores_initial.heldout)} -> {_score(result.scores.heldout)}; "
        f"{result.size_initial.nodes} -> {result.size.nodes} AST nodes\n"
    )
    write_result(summary, "simplified_policy.py", header + result.code + "\n")
    print_result(summary)
    if interruption.asked():
        sys.exit(EXIT_INTERRUPTED)


if __name__ == "__main__":
    main()
