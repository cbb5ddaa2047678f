"""Where a referee evaluation's time goes, per lockstep control step (issue 22).

For each task's paper policy (examples/paper_<task>.py), 10 episodes of 1000 steps in one
lockstep batch, unconfined, CPU time (`time.process_time`) per control step of the batch,
medians of alternating rounds:
- simulator: the batch's environments stepped in lockstep with the actions the policy took
  (what the worker cannot avoid);
- policies: fresh program instances' `act` on the observations they saw (what the child cannot
  avoid; the fast path pays both, plus its loop);
- worker alone: `referee_evaluation` reading the child's answers, recorded, from a file and
  writing to /dev/null (no other process: its Python, its system calls, no process switch);
- child alone: `serve_policy` reading the worker's frames, recorded, from a file (it checks and
  compiles the program and loads each episode's instance, as in the sandbox);
- worker and child, paired: the real exchange, the child forked, each side's CPU and the wall
  time of the worker's loop;
- fast: the program checked, compiled and run by `evaluate_program`, as the fast path's child.
The worker's Python per step is `worker alone - simulator`, the child's `child alone -
policies`; what changing processes costs is `paired - alone` on each side.

    python benchmarks/referee_step.py --tasks pendulum cheetah --rounds 9
"""

from __future__ import annotations

import os
import statistics
import tempfile
import threading
import time
from pathlib import Path
from typing import Callable

import numpy as np
from common import argument_parser, paired_referee, parse_arguments

from colmo.evaluation import REFEREE, EvalRequest
from colmo.program import parametrize
from colmo.rollout import act, episode_seeds, evaluate_program
from colmo.sandbox.namespace import compile_or_explain, template
from colmo.sandbox.referee import LOCKSTEP, referee_evaluation, serve_policy
from colmo.specs import load_spec

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def _relay(source: int, target: int, copy: bytearray) -> None:
    """Forward what `source` yields to `target`, keeping a copy, until the end of the stream."""
    while chunk := os.read(source, 65536):
        copy += chunk
        os.write(target, chunk)
    os.close(target)


class Setup:
    """A task's environments, request and recordings (episodes, frames both ways)."""

    def __init__(self, task: str, episodes: int):
        spec = load_spec(f"{task}.py")
        program = parametrize((EXAMPLES / f"paper_{task}.py").read_text())
        self.seeds = tuple(episode_seeds(0, episodes))
        self.envs = [spec.make_environment() for _ in range(min(episodes, LOCKSTEP))]
        for name in spec.allowed_imports:
            template(name)
        self.request = EvalRequest(str(spec.path), (), self.seeds, program.skeleton, program.values, spec.allowed_imports, mode=REFEREE)
        self.steps = self.envs[0].horizon * -(-episodes // LOCKSTEP)  # lockstep steps per evaluation
        self.observations: dict[int, list[np.ndarray]] = {}
        self.actions: dict[int, list[np.ndarray]] = {}
        self.fast()  # records each episode's observations and actions
        self.to_child, self.to_worker = bytearray(), bytearray()
        self._record_frames()

    def compiled(self):
        program, refusal = compile_or_explain(self.request.skeleton, self.request.allowed_imports, self.request.params)
        assert program is not None, refusal
        return program

    def fast(self) -> None:
        program = self.compiled()

        def recording(seed: int) -> Callable[[np.ndarray], object]:
            policy = program.new_policy(seed)
            seen, taken = self.observations.setdefault(seed, []), self.actions.setdefault(seed, [])

            def recorded(obs: np.ndarray) -> object:
                seen.append(obs.copy())
                taken.append(np.asarray(policy(obs), dtype=np.float64).reshape(-1))
                return taken[-1]

            return recorded

        new_policy = recording if not self.actions else program.new_policy
        evaluation = evaluate_program(self.envs[0], new_policy, self.seeds)
        assert evaluation.failure is None, evaluation.failure

    def simulator(self) -> None:
        for first in range(0, len(self.seeds), len(self.envs)):
            batch = list(zip(self.envs, self.seeds[first : first + len(self.envs)]))
            for env, seed in batch:
                env.reset(seed)
            for step in range(self.envs[0].horizon):
                for env, seed in batch:
                    env.step(self.actions[seed][step])

    def policies(self) -> None:
        program = self.compiled()
        for seed in self.seeds:
            policy = program.new_policy(seed)
            for step, obs in enumerate(self.observations[seed]):
                act(policy, obs.copy(), self.envs[0].action_size, step)

    def _record_frames(self) -> None:
        """One real exchange, each direction relayed by a thread that keeps a copy."""
        from_worker, to_worker = os.pipe(), os.pipe()  # (read end, write end) each
        from_child, to_child = os.pipe(), os.pipe()
        pid = os.fork()
        if not pid:
            serve_policy(self.request, self.envs[0].action_size, to_child[0], from_child[1])
            os._exit(0)
        os.close(to_child[0])
        os.close(from_child[1])
        relays = [
            threading.Thread(target=_relay, args=(from_worker[0], to_child[1], self.to_child)),
            threading.Thread(target=_relay, args=(from_child[0], to_worker[1], self.to_worker)),
        ]
        for relay in relays:
            relay.start()
        evaluation = referee_evaluation(self.envs, self.request, to_worker[0], from_worker[1], time.monotonic() + 3600)
        assert evaluation.failure is None, evaluation.failure
        os.close(from_worker[1])  # the child's relay ends, then the child, then the worker's relay
        for relay in relays:
            relay.join()
        os.waitpid(pid, 0)
        for fd in (from_worker[0], from_child[0], to_worker[0]):
            os.close(fd)

    def worker_alone(self, answers: str) -> None:
        read_fd, write_fd = os.open(answers, os.O_RDONLY), os.open(os.devnull, os.O_WRONLY)
        try:
            evaluation = referee_evaluation(self.envs, self.request, read_fd, write_fd, time.monotonic() + 3600)
            assert evaluation.failure is None, evaluation.failure
        finally:
            os.close(read_fd)
            os.close(write_fd)

    def child_alone(self, frames: str) -> None:
        read_fd, write_fd = os.open(frames, os.O_RDONLY), os.open(os.devnull, os.O_WRONLY)
        try:
            serve_policy(self.request, self.envs[0].action_size, read_fd, write_fd)
        finally:
            os.close(read_fd)
            os.close(write_fd)


def measure(setup: Setup, rounds: int, directory: str) -> dict[str, list[float]]:
    """CPU seconds per evaluation of each part (module docstring), over alternating rounds."""
    answers, frames = os.path.join(directory, "answers"), os.path.join(directory, "frames")
    Path(answers).write_bytes(setup.to_worker)
    Path(frames).write_bytes(setup.to_child)
    parts: dict[str, Callable[[], None]] = {
        "fast": setup.fast,
        "simulator": setup.simulator,
        "policies": setup.policies,
        "worker alone": lambda: setup.worker_alone(answers),
        "child alone": lambda: setup.child_alone(frames),
    }
    times: dict[str, list[float]] = {name: [] for name in [*parts, "worker paired", "child paired", "paired wall", "fast wall"]}
    for index in range(rounds + 1):  # the first round warms up
        for name in list(parts)[:: 1 if index % 2 == 0 else -1]:
            wall, start = time.perf_counter(), time.process_time()
            parts[name]()
            if index:
                times[name].append(time.process_time() - start)
                if name == "fast":
                    times["fast wall"].append(time.perf_counter() - wall)
        worker, child, wall = paired_referee(setup.envs, setup.request)
        if index:
            times["worker paired"].append(worker)
            times["child paired"].append(child)
            times["paired wall"].append(wall)
    return times


def main() -> None:
    parser = argument_parser(__doc__, rounds=9, episodes=10)
    args = parse_arguments(parser)
    print(f"µs per lockstep step, CPU unless said, medians of {args.rounds} alternating rounds, load {os.getloadavg()[0]:.1f}:\n")
    print(
        "| task | simulator | policies | worker alone (its Python) | child alone (its Python) | worker paired (switching) "
        "| child paired (switching) | referee CPU / fast CPU | paired wall / fast wall |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as directory:
        for task in args.tasks:
            setup = Setup(task, args.episodes)
            times = measure(setup, args.rounds, directory)
            per_step = {name: statistics.median(values) / setup.steps * 1e6 for name, values in times.items()}
            referee = statistics.median(w + c for w, c in zip(times["worker paired"], times["child paired"]))
            print(
                f"| {task} | {per_step['simulator']:.1f} | {per_step['policies']:.1f} "
                f"| {per_step['worker alone']:.1f} ({per_step['worker alone'] - per_step['simulator']:+.1f}) "
                f"| {per_step['child alone']:.1f} ({per_step['child alone'] - per_step['policies']:+.1f}) "
                f"| {per_step['worker paired']:.1f} ({per_step['worker paired'] - per_step['worker alone']:+.1f}) "
                f"| {per_step['child paired']:.1f} ({per_step['child paired'] - per_step['child alone']:+.1f}) "
                f"| {referee / statistics.median(times['fast']):.2f}x "
                f"| {statistics.median(times['paired wall']) / statistics.median(times['fast wall']):.2f}x |",
                flush=True,
            )


if __name__ == "__main__":
    main()
