"""Racing: what each tuned program costs with `gfo.racing` on and off, and what it scores.

The workload is the paper's inner loop on mistuned programs: per task, the paper's policy
(`examples/paper_<task>.py`) with every constant scaled by its own fixed factor in [1/2, 2]
(`--programs` variants, the same for both sides), each tuned with the (1+1)-ES, budget 100, on
the task's 10 training episodes of run seed 0, optimizer seed = the program's index; so racing
off and on tune the same programs from the same seeds. Everything goes through the real
evaluation path: sandboxed workers (`colmo.executor.LocalExecutor`), time limits calibrated on
the task's starter (`colmo.heldout.task_evaluator`), `colmo.optimize.tune.optimize_program`
(tuning, then the readable 4-digit code scored by the referee over all episodes).

Each of `--workers` lanes owns a one-worker executor and takes the next job (a program with
racing off or on) from a shared queue; a program's two jobs are queued next to each other, in
alternating order (off first for even programs, on first for odd ones), so both sides see the
same load. CPU seconds are the lane's worker process's user + system time, its evaluation
processes included (`/proc/<pid>/stat`: utime + stime + cutime + cstime), over the job: the
simulation and the policy, not the coordinator's optimizer. Steps are the control steps the
job simulated (`ProgramResult.steps`: candidates, the rounded code and the referee's run).
The table reports medians over the programs and the ratio off/on; `score change` is the
median tuned score with racing relative to without.

    MENAGERIE_ROOT=../shared/menagerie python benchmarks/racing.py     # 5 tasks x 5 programs
    python benchmarks/racing.py --tasks pendulum cheetah --programs 3 --workers 1
"""

from __future__ import annotations

import dataclasses
import os
import queue
import statistics
import threading
import time
from pathlib import Path

import numpy as np
from common import TASKS, argument_parser, parse_arguments

from colmo.cli import compose
from colmo.config import ExecutorConfig, GFOConfig, TaskConfig
from colmo.evaluation import Evaluator
from colmo.executor import LocalExecutor
from colmo.heldout import task_evaluator
from colmo.optimize.tune import CandidateEvaluator, optimize_program
from colmo.program import ParametricProgram, parametrize

REPO = Path(__file__).resolve().parent.parent
EXAMPLES = REPO / "examples"
SEED = 0  # run seed: the training episodes
_CLOCK_TICKS = os.sysconf("SC_CLK_TCK")


def mistuned(task: str, programs: int) -> list[ParametricProgram]:
    """The paper's policy for `task` with each constant scaled by a fixed factor in [1/2, 2],
    drawn per program and constant from a fixed stream (the same programs on every run)."""
    paper = parametrize((EXAMPLES / f"paper_{task}.py").read_text())
    variants = []
    for index in range(programs):
        factors = 2.0 ** np.random.default_rng([TASKS.index(task), index]).uniform(-1.0, 1.0, len(paper.values))
        variants.append(dataclasses.replace(paper, values=tuple(float(f"{v * f:.4g}") for v, f in zip(paper.values, factors))))
    return variants


def worker_cpu_seconds(executor: LocalExecutor) -> float:
    """User + system CPU seconds of the executor's worker processes and of their reaped
    children (each evaluation runs in a child the worker forks and waits for)."""
    total = 0
    for pid in executor.worker_pids():
        stat = Path(f"/proc/{pid}/stat").read_text()
        fields = stat[stat.rindex(")") + 2 :].split()  # fields[0] is field 3 of proc(5)
        total += sum(int(fields[i]) for i in (11, 12, 13, 14))  # utime stime cutime cstime
    return total / _CLOCK_TICKS


@dataclasses.dataclass(frozen=True)
class Outcome:
    """One tuned program: its cost and its final (referee) score."""

    steps: int
    cpu_seconds: float
    score: float
    evaluations: int
    raced_out: int


class Lane:
    """A one-worker executor with the task's calibrated evaluator: the worker's CPU time
    measures one job at a time."""

    def __init__(self, memory_mb: int):
        self.executor = LocalExecutor(1, memory_mb)
        self.evaluator: Evaluator | None = None

    def prepare(self, task: TaskConfig, executor_cfg: ExecutorConfig) -> None:
        """Calibrate the task's time limits here (which also builds the simulator in the worker)."""
        self.evaluator = task_evaluator(task, executor_cfg, self.executor, SEED)[1]

    def tune(self, program: ParametricProgram, gfo: GFOConfig, seed: int) -> Outcome:
        cpu = worker_cpu_seconds(self.executor)
        result = optimize_program(program, CandidateEvaluator(self.executor, self.evaluator, program.skeleton), gfo, seed)
        if result.failure:
            raise RuntimeError(f"program {seed} failed: {result.failure}")
        return Outcome(result.steps, worker_cpu_seconds(self.executor) - cpu, result.score, result.evaluations, result.raced_out)


def run_task(task: str, lanes: list[Lane], programs: int, budget: int, verbose: bool) -> dict[tuple[int, bool], Outcome]:
    """Every program of `task` tuned with racing off and on; outcomes by (program, racing)."""
    cfg = compose("optimize", [f"task={task}", "gfo=oneplusone", f"gfo.budget={budget}", "policy_file=unused.py"])
    for lane in lanes:
        lane.prepare(cfg.task, cfg.executor)
    variants = mistuned(task, programs)
    jobs: queue.Queue = queue.Queue()
    for index in range(programs):
        for racing in (False, True) if index % 2 == 0 else (True, False):
            jobs.put((index, racing))
    outcomes: dict[tuple[int, bool], Outcome] = {}
    errors: list[BaseException] = []

    def serve(lane: Lane) -> None:
        while not errors:
            try:
                index, racing = jobs.get_nowait()
            except queue.Empty:
                return
            try:
                outcome = lane.tune(variants[index], dataclasses.replace(cfg.gfo, racing=racing), seed=index)
            except BaseException as error:  # reported by the main thread
                errors.append(error)
                return
            outcomes[index, racing] = outcome
            if verbose:
                print(
                    f"  {task} program {index} racing {'on ' if racing else 'off'}: score {outcome.score:8.2f}, "
                    f"{outcome.steps:>9,} steps, {outcome.cpu_seconds:6.1f} CPU s, {outcome.raced_out} raced out",
                    flush=True,
                )

    threads = [threading.Thread(target=serve, args=(lane,)) for lane in lanes]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    if errors:
        raise errors[0]
    return outcomes


def summary_row(task: str, outcomes: dict[tuple[int, bool], Outcome], programs: int) -> str:
    def median(field: str, racing: bool) -> float:
        return statistics.median(getattr(outcomes[i, racing], field) for i in range(programs))

    steps_off, steps_on = median("steps", False), median("steps", True)
    cpu_off, cpu_on = median("cpu_seconds", False), median("cpu_seconds", True)
    score_off, score_on = median("score", False), median("score", True)
    change = (score_on - score_off) / abs(score_off) * 100 if score_off else float("nan")
    return (
        f"| {task} | {programs} | {steps_off:,.0f} | {steps_on:,.0f} | {steps_off / steps_on:.2f} | "
        f"{cpu_off:.1f} | {cpu_on:.1f} | {cpu_off / cpu_on:.2f} | {score_off:.1f} | {score_on:.1f} | {change:+.1f} % |"
    )


HEADER = (
    "| task | programs | steps off | steps on | off/on | CPU s off | CPU s on | off/on | score off | score on | score change |\n"
    "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
)


def main() -> None:
    parser = argument_parser(__doc__)
    parser.add_argument("--programs", type=int, default=5, help="mistuned programs per task")
    parser.add_argument("--workers", type=int, default=2, help="lanes, each a one-worker executor")
    parser.add_argument("--budget", type=int, default=100, help="GFO budget per program")
    parser.add_argument("--verbose", action="store_true", help="a line per tuned program")
    args = parse_arguments(parser)

    start = time.perf_counter()
    lanes = [Lane(ExecutorConfig().memory_mb) for _ in range(args.workers)]
    rows = []
    try:
        for task in args.tasks:
            outcomes = run_task(task, lanes, args.programs, args.budget, args.verbose)
            rows.append(summary_row(task, outcomes, args.programs))
            print(rows[-1], flush=True)
    finally:
        for lane in lanes:
            lane.executor.close()
    print(
        f"\ngfo=oneplusone budget {args.budget}, 10 episodes, racing off vs on (medians over the programs; "
        f"CPU: worker processes, user + system), {args.workers} lanes, {time.perf_counter() - start:.0f} s wall\n"
    )
    print(HEADER)
    print("\n".join(rows))


if __name__ == "__main__":
    main()
