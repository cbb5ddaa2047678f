"""How far constants alone go: the paper's published policies tuned by each GFO method.

    python scripts/tune_published.py OUT [--tasks cheetah quadruped] [--methods ...] [--seeds 1 2 3] [--budget 1000]
    python scripts/tune_published.py OUT --summary      # the markdown table of what has finished

Each run is `colmo-optimize task=T policy_file=examples/paper_T.py gfo=M gfo.budget=B seed=S`
on one worker, in OUT/T/M/seed_S; a run whose result.json exists is skipped, so a stopped
experiment resumes where it was. The summary gives, per task and method, the published policy's
score and each seed's tuned training and held-out (100 episodes) scores with their mean ± std.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
from pathlib import Path

from colmo.comparison import mean_std

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def run(out: Path, task: str, method: str, seed: int, budget: int) -> None:
    directory = out / task / method / f"seed_{seed}"
    if (directory / "result.json").exists():
        return
    command = [
        "colmo-optimize", f"task={task}", f"policy_file={EXAMPLES / f'paper_{task}.py'}", f"gfo={method}",
        f"gfo.budget={budget}", f"seed={seed}", "executor.workers=1", "heldout.episodes=100", f"hydra.run.dir={directory}",
    ]
    print(" ".join(command), flush=True)
    subprocess.run(command, check=False, stdout=subprocess.DEVNULL)


def summary(out: Path) -> str:
    lines = [
        "| task | method | published (training) | tuned training, per seed | tuned held-out, per seed | held-out mean ± std | evaluations | seconds |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for task_dir in sorted(path for path in out.iterdir() if path.is_dir()):
        for method_dir in sorted(path for path in task_dir.iterdir() if path.is_dir()):
            results = [json.loads(path.read_text()) for path in sorted(method_dir.glob("seed_*/result.json"))]
            results = [result for result in results if result.get("failure") is None]
            if not results:
                continue
            heldout = [result["heldout_score"] for result in results]
            spread = mean_std(heldout)
            training = ", ".join(f"{result['score']:.1f}" for result in results)
            lines.append(
                f"| {task_dir.name} | {method_dir.name} | {results[0]['score_initial']:.1f} "
                f"| {training} | {', '.join(f'{h:.1f}' for h in heldout)} | {spread} "
                f"| {results[0]['evaluations']} | {statistics.mean(r['seconds'] for r in results):.0f} |"
            )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--tasks", nargs="+", default=["cheetah", "quadruped"])
    parser.add_argument("--methods", nargs="+", default=["oneplusone", "cma", "de", "bo"])
    parser.add_argument("--seeds", nargs="+", type=int, default=[1, 2, 3])
    parser.add_argument("--budget", type=int, default=1000)
    parser.add_argument("--summary", action="store_true", help="print the table of finished runs and exit")
    args = parser.parse_args()
    if args.summary:
        print(summary(args.out))
        return
    for seed in args.seeds:
        for task in args.tasks:
            for method in args.methods:
                run(args.out, task, method, seed, args.budget)
    print(summary(args.out))


if __name__ == "__main__":
    sys.exit(main())
