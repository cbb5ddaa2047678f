"""Executor overhead: programs evaluated per minute with executor=local and executor=ray, side by side.

The workload is what the search gives an executor: 16 programs optimized at once, each in its
own thread (GFO in the coordinator, every candidate an `EvalRequest`). The programs are the
paper's pendulum policy with its constants scaled (16 fixed variants), tuned with the
(1+1)-ES, budget 10, on 10 episodes. Both executors are started once, with the same number
of workers, before the rounds; each round runs both back to back, in alternating order
(machines are noisy), and the medians are reported, with Ray's overhead relative to local.

    python benchmarks/executor_overhead.py                     # 2 workers, 3 rounds
    python benchmarks/executor_overhead.py --workers 4 --rounds 5
"""

from __future__ import annotations

import concurrent.futures
import dataclasses
import statistics
import time
from pathlib import Path

from common import argument_parser, parse_arguments

from colmo.config import ExecutorConfig, GFOConfig, RayExecutorConfig
from colmo.evaluation import Evaluator, Executor
from colmo.executor import make_executor
from colmo.optimize import CandidateEvaluator, optimize_program
from colmo.program import ParametricProgram, parametrize
from colmo.rollout import episode_seeds
from colmo.specs import load_spec

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
PROGRAMS = 16


def workload() -> list[ParametricProgram]:
    """The paper's pendulum policy with every constant scaled by one of 16 fixed factors."""
    paper = parametrize((EXAMPLES / "paper_pendulum.py").read_text())
    factors = [0.7 + 0.04 * i for i in range(PROGRAMS)]
    return [dataclasses.replace(paper, values=tuple(v * f for v in paper.values)) for f in factors]


def run_round(executor: Executor, programs: list[ParametricProgram], gfo: GFOConfig, episodes: int) -> tuple[float, float, list[float]]:
    """Seconds to optimize all programs at once, the fraction of that time the workers spent
    evaluating (the rest is dispatch), and the programs' scores."""
    evaluator = Evaluator.for_task(load_spec("pendulum.py"), {}, episode_seeds(0, episodes), memory_mb=4096, timeout_s=60)

    def optimize(index: int) -> float:
        evaluate = CandidateEvaluator(executor, evaluator, programs[index].skeleton)
        return optimize_program(programs[index], evaluate, gfo, seed=index).score

    start, busy = time.perf_counter(), executor.busy_seconds
    with concurrent.futures.ThreadPoolExecutor(len(programs)) as threads:
        scores = list(threads.map(optimize, range(len(programs))))
    seconds = time.perf_counter() - start
    return seconds, (executor.busy_seconds - busy) / (seconds * executor.n_workers), scores


def main() -> None:
    parser = argument_parser(__doc__, tasks=False, rounds=3, episodes=10)
    parser.add_argument("--workers", type=int, default=2, help="workers of each executor (local processes, Ray actors)")
    parser.add_argument("--budget", type=int, default=10, help="GFO budget per program")
    args = parse_arguments(parser)

    programs = workload()
    gfo = GFOConfig(method="oneplusone", budget=args.budget)
    executors: dict[str, Executor] = {}
    for name in ("local", "ray"):
        start = time.perf_counter()
        executors[name] = make_executor((RayExecutorConfig if name == "ray" else ExecutorConfig)(workers=args.workers))
        print(f"{name:5s} executor started in {time.perf_counter() - start:.1f} s", flush=True)
    try:
        # One unmeasured round each: sandbox processes start, simulators and programs get built.
        reference = {name: run_round(executor, programs, gfo, args.episodes)[2] for name, executor in executors.items()}
        assert reference["local"] == reference["ray"], "the executors disagree on the scores"
        rates: dict[str, list[float]] = {name: [] for name in executors}
        busy: dict[str, list[float]] = {name: [] for name in executors}
        for index in range(args.rounds):
            order = list(executors) if index % 2 == 0 else list(reversed(executors))  # no side always runs first
            for name in order:
                seconds, fraction, _ = run_round(executors[name], programs, gfo, args.episodes)
                rates[name].append(len(programs) / seconds * 60)
                busy[name].append(fraction)
            print(f"round {index + 1}: local {rates['local'][-1]:6.1f}, ray {rates['ray'][-1]:6.1f} programs/min", flush=True)
    finally:
        for executor in executors.values():
            executor.close()

    local, ray = (statistics.median(rates[name]) for name in ("local", "ray"))
    # Each round's pair ran back to back, under the same load: their ratio is the fair comparison.
    overhead = statistics.median(local_rate / ray_rate - 1 for local_rate, ray_rate in zip(rates["local"], rates["ray"])) * 100
    print(
        f"\n{PROGRAMS} pendulum programs, gfo=oneplusone budget {args.budget}, {args.episodes} episodes, "
        f"{args.workers} workers, {args.rounds} rounds (medians):\n"
        f"  executor=local {local:7.1f} programs/min, workers busy {statistics.median(busy['local']):.1%} of the time\n"
        f"  executor=ray   {ray:7.1f} programs/min, workers busy {statistics.median(busy['ray']):.1%} of the time\n"
        f"  Ray overhead   {overhead:+6.1f} % (median of the rounds' local/ray rate ratios, minus 1)"
    )


if __name__ == "__main__":
    main()
