"""What the sandbox's guarantees cost: the referee, and a fresh confined process per evaluation.

For each task's paper policy (examples/paper_<task>.py), on 10 episodes of 1000 steps, side by
side in alternating rounds on one sandbox worker (medians reported):
- fast: one evaluation as GFO candidates get it (a fresh confined process runs the simulator
  and the policy);
- referee: the same evaluation as final scores get it (the trusted worker runs the simulator,
  the confined process only maps observations to actions; the episodes run in lockstep, a
  pipe round trip per control step for all of them);
- unconfined: the simulator and the policy in this process, no sandbox at all (the floor),
  a fresh program instance per episode as in the sandbox;
and the referee's share of a tuned program (`gfo.budget` fast evaluations, one referee).

With `--cpu`, also the CPU time of the same work without confinement, in processes this script
forks: the fast path (the program checked and compiled, then `evaluate_program`, here) against
the referee's two sides (the worker's loop here, `serve_policy`, which checks and compiles too,
in a forked child), each process's `time.process_time`. On a loaded machine wall times mostly
measure the share of a core the scheduler gives; CPU time is what the code costs.

    python benchmarks/referee_cost.py                       # every task, 5 rounds
    python benchmarks/referee_cost.py --tasks pendulum cheetah --rounds 3 --cpu
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path

from common import argument_parser, paired_referee, parse_arguments

from colmo.evaluation import FAST, REFEREE, EvalRequest
from colmo.executor import LocalExecutor
from colmo.program import parametrize
from colmo.rollout import episode_seeds, evaluate_program
from colmo.sandbox.namespace import Program, compile_or_explain, template
from colmo.sandbox.referee import LOCKSTEP
from colmo.specs import load_spec

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def measure_task(executor: LocalExecutor, task: str, seeds: tuple[int, ...], rounds: int) -> dict[str, list[float]]:
    """Seconds per evaluation of the task's paper policy, each way, over alternating rounds."""
    spec = load_spec(f"{task}.py")
    program = parametrize((EXAMPLES / f"paper_{task}.py").read_text())
    env = spec.make_environment()
    trusted = Program(program.skeleton, spec.allowed_imports, program.values)  # the paper's code: trusted

    def sandboxed(mode: str) -> float:
        request = EvalRequest(str(spec.path), (), seeds, program.skeleton, program.values, spec.allowed_imports, mode=mode, timeout_s=600)
        [evaluation] = executor.evaluate([request])
        assert evaluation.failure is None, evaluation.failure
        return evaluation.seconds  # measured by the worker: fork to reply

    def unconfined() -> float:
        start = time.perf_counter()
        evaluate_program(env, trusted.new_policy, seeds)
        return time.perf_counter() - start

    measures = {"fast": lambda: sandboxed(FAST), "referee": lambda: sandboxed(REFEREE), "unconfined": unconfined}
    for measure in measures.values():  # warm-up: simulators built, initial states cached
        measure()
    times: dict[str, list[float]] = {name: [] for name in measures}
    for index in range(rounds):
        for name in list(measures)[:: 1 if index % 2 == 0 else -1]:
            times[name].append(measures[name]())
    return times


def cpu_seconds(task: str, seeds: tuple[int, ...], rounds: int) -> dict[str, list[float]]:
    """CPU seconds per evaluation, unconfined: the fast path, and the referee's worker and child."""
    spec = load_spec(f"{task}.py")
    program = parametrize((EXAMPLES / f"paper_{task}.py").read_text())
    envs = [spec.make_environment() for _ in range(min(len(seeds), LOCKSTEP))]
    for name in spec.allowed_imports:
        template(name)
    request = EvalRequest(str(spec.path), (), seeds, program.skeleton, program.values, spec.allowed_imports, mode=REFEREE)

    def fast() -> float:
        start = time.process_time()
        # As the fast path's child does (and the referee's child, timed below): check and compile, then run.
        checked, _ = compile_or_explain(request.skeleton, request.allowed_imports, request.params)
        evaluate_program(envs[0], checked.new_policy, seeds)
        return time.process_time() - start

    def refereed() -> tuple[float, float]:
        worker, child, _ = paired_referee(envs, request)
        return worker, child

    fast(), refereed()  # warm-up: initial states cached, templates built
    times: dict[str, list[float]] = {"fast": [], "worker": [], "child": []}
    for _ in range(rounds):
        times["fast"].append(fast())
        worker, child = refereed()
        times["worker"].append(worker)
        times["child"].append(child)
    return times


def main() -> None:
    parser = argument_parser(__doc__, rounds=5, episodes=10)
    parser.add_argument("--budget", type=int, default=100, help="fast evaluations per tuned program")
    parser.add_argument("--cpu", action="store_true", help="also the CPU time of the fast path and of the referee's two processes, unconfined")
    args = parse_arguments(parser)
    seeds = tuple(episode_seeds(0, args.episodes))
    rows = []
    with LocalExecutor(1) as executor:
        for task in args.tasks:
            times = measure_task(executor, task, seeds, args.rounds)
            fast, referee, floor = (statistics.median(times[name]) for name in ("fast", "referee", "unconfined"))
            share = referee / (args.budget * fast + referee)
            rows.append((task, floor, fast, referee, referee / fast, share))
            print(f"{task}: unconfined {floor:.3f} s, fast {fast:.3f} s, referee {referee:.3f} s", flush=True)
    print(f"\n{args.episodes} episodes per evaluation, one worker, medians of {args.rounds} alternating rounds:\n")
    print("| task | unconfined (s) | fast, sandboxed (s) | referee (s) | referee / fast | referee's share of a tuned program (budget %d) |" % args.budget)
    print("|---|---|---|---|---|---|")
    for task, floor, fast, referee, ratio, share in rows:
        print(f"| {task} | {floor:.3f} | {fast:.3f} | {referee:.3f} | {ratio:.2f}x | {share:.1%} |")
    if args.cpu:
        print(f"\nCPU seconds per evaluation, unconfined, medians of {args.rounds} rounds:\n")
        print("| task | fast | referee: worker + child | referee / fast |")
        print("|---|---|---|---|")
        for task in args.tasks:
            times = cpu_seconds(task, seeds, args.rounds)
            fast, worker, child = (statistics.median(times[name]) for name in ("fast", "worker", "child"))
            referee = statistics.median(map(sum, zip(times["worker"], times["child"])))
            print(f"| {task} | {fast:.3f} | {worker:.3f} + {child:.3f} | {referee / fast:.2f}x |", flush=True)


if __name__ == "__main__":
    main()
