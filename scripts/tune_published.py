"""How far constants alone go: the paper's published policies tuned by each GFO method.

    python scripts/tune_published.py OUT [--tasks cheetah quadruped] [--methods ...] [--seeds 1 2 3] [--budget 1000]
    python scripts/tune_published.py OUT --summary      # the markdown table of what has finished

Each run is `colmo-optimize task=T policy_file=examples/paper_T.py gfo=M gfo.budget=B seed=S`
on one worker, in OUT/T/M/seed_S, and the published policy as written is scored on the same 100
held-out episodes (`colmo-evaluate ... seed=S episodes=100`, in OUT/T/published/seed_S); a run
whose result.json exists is skipped, so a stopped experiment resumes where it was. The summary
gives, per task, the published policy's training and held-out scores on each seed, then per
method each seed's tuned training and held-out (100 episodes) scores with their mean ± std.
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
PUBLISHED = "published"  # the policy as written, scored on the held-out episodes


def run(out: Path, task: str, method: str, seed: int, budget: int) -> None:
    """Tune the published policy with `method` (`PUBLISHED`: score it as written) on `seed`."""
    directory = out / task / method / f"seed_{seed}"
    if (directory / "result.json").exists():
        return
    policy, run_dir = f"policy_file={EXAMPLES / f'paper_{task}.py'}", f"hydra.run.dir={directory}"
    if method == PUBLISHED:
        command = ["colmo-evaluate", f"task={task}", policy, f"seed={seed}", "episodes=100", run_dir]
    else:
        command = [
            "colmo-optimize", f"task={task}", policy, f"gfo={method}", f"gfo.budget={budget}", f"seed={seed}",
            "executor.workers=1", "heldout.episodes=100", run_dir,
        ]
    print(" ".join(command), flush=True)
    subprocess.run(command, check=False, stdout=subprocess.DEVNULL)


def _results(directory: Path) -> dict[str, dict]:
    """The finished runs under `directory`, by seed folder."""
    found = {path.parent.name: json.loads(path.read_text()) for path in sorted(directory.glob("seed_*/result.json"))}
    return {seed: result for seed, result in found.items() if result.get("failure") is None}


def summary(out: Path) -> str:
    lines = [
        "| task | policy | seeds | training (10 episodes), per seed | held-out (100), per seed | held-out mean ± std | evaluations | seconds |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for task_dir in sorted(path for path in out.iterdir() if path.is_dir()):
        tuned = {path.name: _results(path) for path in sorted(task_dir.iterdir()) if path.is_dir() and path.name != PUBLISHED}
        published = _results(task_dir / PUBLISHED)
        if published:  # its training score is what each tuning started from
            initial = {seed: result["score_initial"] for runs in tuned.values() for seed, result in runs.items()}
            training = ", ".join(f"{initial[seed]:.1f}" if seed in initial else "-" for seed in published)
            heldout = [result["score"] for result in published.values()]
            lines.append(
                f"| {task_dir.name} | published, as written | {_seeds(published)} | {training} "
                f"| {', '.join(f'{h:.1f}' for h in heldout)} | {mean_std(heldout)} | | |"
            )
        for method, runs in tuned.items():
            if not runs:
                continue
            results = list(runs.values())
            heldout = [result["heldout_score"] for result in results]
            training = ", ".join(f"{result['score']:.1f}" for result in results)
            lines.append(
                f"| {task_dir.name} | tuned by `{method}` | {_seeds(runs)} | {training} "
                f"| {', '.join(f'{h:.1f}' for h in heldout)} | {mean_std(heldout)} "
                f"| {results[0]['evaluations']} | {statistics.mean(r['seconds'] for r in results):.0f} |"
            )
    return "\n".join(lines)


def _seeds(runs: dict[str, dict]) -> str:
    return ", ".join(seed.removeprefix("seed_") for seed in runs)


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
            for method in [PUBLISHED, *args.methods]:
                run(args.out, task, method, seed, args.budget)
    print(summary(args.out))


if __name__ == "__main__":
    sys.exit(main())
