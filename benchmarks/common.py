"""What the benchmark scripts share: the five tasks, the start of their command line, a referee
evaluation between two unconfined processes timed on both sides, and the physics-only test
menagerie beside a colmo checkout (`../shared/menagerie`, which the tests and CI use) where
`MENAGERIE_ROOT` is not set."""

from __future__ import annotations

import argparse
import os
import struct
import time
from collections.abc import Sequence
from pathlib import Path

from colmo.environments.base import Environment
from colmo.evaluation import EvalRequest
from colmo.sandbox.referee import referee_evaluation, serve_policy

TASKS = ("pendulum", "ball_in_cup", "cheetah", "quadruped", "a1")
_CHECKOUT_MENAGERIE = Path(__file__).resolve().parent.parent.parent / "shared" / "menagerie"


def argument_parser(description: str | None, *, tasks: bool = True, rounds: int | None = None, episodes: int | None = None) -> argparse.ArgumentParser:
    """A parser that prints the script's docstring as its help, with `--tasks` (all five by
    default) unless the script runs a fixed workload, and `--rounds` and `--episodes` where the
    script takes them (their defaults given)."""
    parser = argparse.ArgumentParser(description=description, formatter_class=argparse.RawDescriptionHelpFormatter)
    if tasks:
        parser.add_argument("--tasks", nargs="+", choices=TASKS, default=list(TASKS), help="tasks to run (default: all five)")
    if rounds is not None:
        parser.add_argument("--rounds", type=int, default=rounds, help="alternating rounds; medians are reported")
    if episodes is not None:
        parser.add_argument("--episodes", type=int, default=episodes, help="episodes per evaluation")
    return parser


def parse_arguments(parser: argparse.ArgumentParser) -> argparse.Namespace:
    """The command line, read once the simulator's models can be found: the checkout's test
    menagerie where `MENAGERIE_ROOT` is unset (else mujoco-menagerie downloads the A1 at first use)."""
    arguments = parser.parse_args()
    if "MENAGERIE_ROOT" not in os.environ and _CHECKOUT_MENAGERIE.is_dir():
        os.environ["MENAGERIE_ROOT"] = str(_CHECKOUT_MENAGERIE)
    return arguments


def paired_referee(envs: Sequence[Environment], request: EvalRequest) -> tuple[float, float, float]:
    """One referee evaluation without the sandbox: this process runs the worker's side
    (`referee_evaluation`), a forked child the policy's (`serve_policy`). Returns the worker's
    and the child's CPU seconds and the exchange's wall seconds."""
    observations_read, observations_write = os.pipe()
    actions_read, actions_write = os.pipe()
    child_read, child_write = os.pipe()  # the child's CPU seconds, once it is done
    pid = os.fork()
    if not pid:
        for fd in (observations_write, actions_read, child_read):
            os.close(fd)
        start = time.process_time()
        serve_policy(request, envs[0].action_size, observations_read, actions_write)
        os.write(child_write, struct.pack("<d", time.process_time() - start))
        os._exit(0)
    for fd in (observations_read, actions_write, child_write):
        os.close(fd)
    wall, start = time.perf_counter(), time.process_time()
    evaluation = referee_evaluation(envs, request, actions_read, observations_write, time.monotonic() + 3600)
    worker, wall = time.process_time() - start, time.perf_counter() - wall
    assert evaluation.failure is None, evaluation.failure
    for fd in (actions_read, observations_write):
        os.close(fd)
    (child,) = struct.unpack("<d", os.read(child_read, 8))
    os.close(child_read)
    os.waitpid(pid, 0)
    return worker, child, wall
