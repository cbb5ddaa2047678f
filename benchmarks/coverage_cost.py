"""What counting a program's branches costs the referee (issue 38: every program's final scoring
counts them, `database.shown_as_run`).

For each policy below, one referee evaluation of 10 episodes (one lockstep batch) without the
sandbox (`common.paired_referee`: this process the worker, a forked child the policy), with
`EvalRequest.coverage` off and on, alternating; the medians of the rounds, per lockstep control
step: the worker's and the child's CPU and the exchange's wall time, and the ratio on / off.

    python benchmarks/coverage_cost.py --rounds 9
"""

from __future__ import annotations

import dataclasses
import os
import statistics
from pathlib import Path

from common import argument_parser, paired_referee, parse_arguments

from colmo import coverage
from colmo.evaluation import REFEREE, EvalRequest
from colmo.program import parametrize
from colmo.rollout import episode_seeds
from colmo.sandbox.namespace import template
from colmo.sandbox.referee import LOCKSTEP
from colmo.specs import load_spec

ROOT = Path(__file__).resolve().parent.parent
POLICIES = {  # a policy with one `if`, and a mutated one with four conditions and five clips
    "pendulum": ROOT / "examples" / "paper_pendulum.py",
    "cheetah": ROOT / "docs" / "mixed-generation" / "cheetah" / "mixed" / "s0" / "best_policy.py",
}


def main() -> None:
    args = parse_arguments(argument_parser(__doc__, tasks=False, rounds=9, episodes=10))
    print(f"µs per lockstep step, medians of {args.rounds} alternating rounds, load {os.getloadavg()[0]:.1f}:\n")
    print("| task | sites | child CPU off | child CPU on | worker CPU off | worker CPU on | wall off | wall on | wall on / off |")
    print("|---|---|---|---|---|---|---|---|---|")
    for task, path in POLICIES.items():
        spec = load_spec(f"{task}.py")
        code = path.read_text()
        program = parametrize(code)
        seeds = tuple(episode_seeds(0, args.episodes))
        envs = [spec.make_environment() for _ in range(min(args.episodes, LOCKSTEP))]
        for name in spec.allowed_imports:
            template(name)
        off = EvalRequest(str(spec.path), (), seeds, program.skeleton, program.values, spec.allowed_imports, mode=REFEREE)
        requests = {"off": off, "on": dataclasses.replace(off, coverage=True)}
        times: dict[str, list[tuple[float, float, float]]] = {"off": [], "on": []}
        for index in range(args.rounds + 1):  # the first round warms up
            for name in (("off", "on") if index % 2 == 0 else ("on", "off")):
                measured = paired_referee(envs, requests[name])
                if index:
                    times[name].append(measured)
        steps = envs[0].horizon * -(-args.episodes // LOCKSTEP)
        per_step = {
            (name, part): statistics.median(t[part] for t in times[name]) / steps * 1e6 for name in times for part in range(3)
        }
        print(
            f"| {task} | {len(coverage.sites(code))} | {per_step['off', 1]:.1f} | {per_step['on', 1]:.1f} | {per_step['off', 0]:.1f} "
            f"| {per_step['on', 0]:.1f} | {per_step['off', 2]:.1f} | {per_step['on', 2]:.1f} | {per_step['on', 2] / per_step['off', 2]:.2f} |"
        )


if __name__ == "__main__":
    main()
