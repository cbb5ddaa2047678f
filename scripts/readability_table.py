"""Issue 38's readability table: `colmo-simplify` on stored policies, one row each.

    python scripts/readability_table.py OUT TASK=POLICY_FILE [TASK=POLICY_FILE ...]

Runs `python -m colmo.simplify task=TASK policy_file=POLICY_FILE` with its defaults (10 training
and 100 held-out episodes of seed 0, tolerance 0.01, oneplusone re-tuning) for each pair, one
after another, each into OUT/<n>/ (a pair whose result.json is there is not run again), and
prints the Markdown table: lines, parameters and AST nodes before and after, the branches never
taken over the training and held-out episodes (`colmo.coverage`) and whether removing them was
a step of its own (not, where the static clean-up had removed them already or removing them
cost score), the other accepted steps, and the referee's scores before and after.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

PRUNED = "removed the branches never taken"


def simplified(out: Path, index: int, task: str, policy: str) -> dict:
    run_dir = out / str(index)
    result = run_dir / "result.json"
    if not result.is_file():
        command = [sys.executable, "-m", "colmo.simplify", f"task={task}", f"policy_file={Path(policy).resolve()}", f"hydra.run.dir={run_dir}"]
        print("running: " + " ".join(command[1:]), file=sys.stderr, flush=True)
        subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    return json.loads(result.read_text())


def row(task: str, policy: str, result: dict) -> str:
    steps = [step["description"] for step in result["steps"]]
    never = result.get("branches_never_taken", 0)
    taken = any(s.startswith(PRUNED) for s in steps)
    pruned = "—" if not never else f"{never} ({'removed' if taken else 'no step of its own: dead code already, or it cost score'})"
    others = sum(not s.startswith(PRUNED) for s in steps)
    return (
        f"| {task} | {policy} | {result['lines_initial']} → {result['lines']} | {result['n_params_initial']} → {result['n_params']} "
        f"| {result['size_initial']} → {result['size']} | {pruned} | {others} "
        f"| {result['score_initial']:.2f} → {result['score']:.2f} | {result['heldout_score_initial']:.2f} → {result['heldout_score']:.2f} "
        f"| {result['seconds']:.0f} |"
    )


def main() -> None:
    out, pairs = Path(sys.argv[1]), [pair.split("=", 1) for pair in sys.argv[2:]]
    if not pairs or any(len(pair) != 2 for pair in pairs):
        sys.exit(__doc__)
    out.mkdir(parents=True, exist_ok=True)
    print("| task | policy | lines | parameters | AST nodes | branches never taken | other steps | training score | held-out score | seconds |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for index, (task, policy) in enumerate(pairs):
        print(row(task, policy, simplified(out, index, task, policy)), flush=True)


if __name__ == "__main__":
    main()
