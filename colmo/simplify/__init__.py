"""Simplifying a policy program: a static clean-up, measured greedy deletions, then re-tuning.

The output of colmo is a policy a person will read. This package makes it shorter without
making it worse, and measures every step:

- `scope`, `fold`, `deadcode`: `remove_dead_code`, the static, behaviour-preserving clean-up
  (unreachable statements, unused assignments and definitions, constant conditions, literal
  arithmetic folded: `np.abs(4.4)` -> `4.4`). It parses and rewrites code, and evaluates only
  literal arithmetic with trusted functions; it never runs the program.
- `candidates`: `deletion_candidates`, every one-step deletion of a program (a statement, a
  branch, a term, a factor, a wrapping call, a subexpression replaced by 0 or 1); with `merge`,
  two terms alike but for their constants written as one (mutation's blend of relatives); with
  `linear`, a sum's like terms collected and its numbers added.
- `greedy`: `simplify`, the algorithm and its acceptance rule, with the scoring and re-tuning
  injected; every score it reports is measured.
- `sandboxed`: `simplify_program`, the algorithm for a task: the referee scores programs in
  sandboxed workers on training and held-out episodes, the GFO re-tunes. `colmo-simplify`
  (`python -m colmo.simplify`, `__main__`) and a search's final step call it.

Sizes are `colmo.program.measure`: lines, AST nodes (`colmo.astutil.node_count`: a signed
literal is one node) and tunable constants.
"""

from colmo.simplify.candidates import Candidate, deletion_candidates
from colmo.simplify.deadcode import remove_dead_code
from colmo.simplify.greedy import ProgramFails, Retune, ScoreBatch, Scores, Scoring, SimplifyResult, Step, simplify
from colmo.simplify.sandboxed import RefereeScores, gfo_retune, simplify_program

__all__ = [
    "Candidate", "ProgramFails", "RefereeScores", "Retune", "ScoreBatch", "Scores", "Scoring", "SimplifyResult", "Step",
    "deletion_candidates", "gfo_retune", "remove_dead_code", "simplify", "simplify_program",
]
