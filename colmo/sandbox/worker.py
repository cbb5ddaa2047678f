"""The sandbox worker process: `python -m colmo.sandbox.worker FD PARENT_PID`.

A worker is a fresh interpreter (never a fork of the coordinator, so it holds none of its
secrets) started by `colmo.sandbox.process` with a clean environment, in a session of its own,
its working directory a private temporary directory, unable to write files (file size limit
0) and, where the kernel allows, in a network namespace of its own (then it has no network at
all). It is trusted: it never runs program code. It prepares what evaluations need (imports,
module templates, each task's simulator, each episode's initial state) and then, for every
request, forks a child that confines itself (`colmo.sandbox.confine`) and runs the program.
So every evaluation runs in a process that no earlier program touched, and nothing a program
does survives it: not a counter kept across GFO candidates, not a change to numpy's shared
objects, not a change to the evaluator.

- `fast` requests: the child runs the simulator and the policy together and writes its
  `Evaluation` (JSON) to a pipe; the worker reads at most `_MAX_REPLY_BYTES` of it.
- `referee` requests: the child only maps observations to actions; the worker runs the
  simulator and computes the returns (`colmo.sandbox.referee`).

The worker owns the request's wall-clock limit: past it the child is killed (`timeout: ...`).
A child that dies reports how (`crash: segmentation fault`, `cpu time: ...`). Replies to the
coordinator are JSON over the connection it was given.
"""

from __future__ import annotations

import collections
import contextlib
import ctypes
import dataclasses
import gc
import json
import os
import select
import signal
import sys
import time
from multiprocessing.connection import Connection
from typing import Any, Callable, Iterator

from colmo.environments.base import Environment
from colmo.errors import describe_exception
from colmo.evaluation import FAST, REFEREE, EvalRequest, Evaluation
from colmo.rollout import evaluate_program
from colmo.sandbox.confine import enter_sandbox, make_undumpable
from colmo.sandbox.namespace import compile_or_explain, template
from colmo.sandbox.referee import LOCKSTEP, RefereeTimeout, referee_evaluation, serve_policy, write_all

_PR_SET_PDEATHSIG = 1
_CLONE_NEWUSER, _CLONE_NEWNET = 0x10000000, 0x40000000
_LIBC = ctypes.CDLL(None, use_errno=True)
_MAX_REPLY_BYTES = 1 << 20
_EXIT_GRACE_S = 1.0
_QUIT_GRACE_S = 3.0  # a referee's policy child, told to quit, exits at once: past this it is killed
_CHILD_EXITS = {
    signal.SIGKILL: "crash: the evaluation process was killed (SIGKILL): out of memory, or killed from outside",
    signal.SIGXCPU: "cpu time: the evaluation exceeded its CPU time limit",
    signal.SIGSEGV: "crash: segmentation fault",
    signal.SIGSYS: "crash: a forbidden system call",
}


# Tasks (spec and environment options) whose simulators a worker keeps: a search uses one or two
# (training and held-out episodes share theirs), a robustness report one per grid point (about
# 36); all of them, up to 16 simulators each, would not fit a worker's address-space limit.
KEPT_TASKS = 4


class EnvironmentFailure(Exception):
    """The task's simulator, not the program, failed; the message says at which step."""


class Worker:
    """What a worker keeps between requests: simulators by (spec, options), for the `KEPT_TASKS`
    tasks used last."""

    def __init__(self) -> None:
        self.environments: collections.OrderedDict[tuple, list[Environment]] = collections.OrderedDict()

    def environments_for(self, request: EvalRequest) -> list[Environment]:
        """The simulators of `request`: one for a fast request, whose child runs the episodes one
        after another, one per episode of a lockstep batch for a referee request (`colmo.sandbox.referee`)."""
        key = (request.spec, request.env)
        envs = self.environments.setdefault(key, [])
        self.environments.move_to_end(key)
        while len(self.environments) > KEPT_TASKS:
            self.environments.popitem(last=False)
        count = min(max(len(request.seeds), 1), LOCKSTEP) if request.mode == REFEREE else 1
        spec_name = os.path.basename(request.spec)
        if len(envs) < count:
            from colmo.specs import load_spec

            try:
                spec = load_spec(request.spec)
                envs.extend(spec.make_environment(**dict(request.env)) for _ in range(count - len(envs)))
            except Exception as error:
                raise EnvironmentFailure(f"building {spec_name}'s environment: {type(error).__name__}: {error}") from error
        envs = envs[:count]
        # Initial states, computed once here and inherited by every child (fast) or reused (referee).
        for index, seed in enumerate(request.seeds):
            try:
                envs[index % len(envs)].reset(seed)
            except Exception as error:
                raise EnvironmentFailure(
                    f"resetting {spec_name}'s environment to episode seed {seed} ({index + 1} of {len(request.seeds)}): {type(error).__name__}: {error}"
                ) from error
        return envs

    def evaluate(self, request: EvalRequest) -> Evaluation:
        # The spec and its imports are the user's, not the program's: say which step failed.
        try:
            envs = self.environments_for(request)
        except EnvironmentFailure as error:
            return Evaluation(failure=f"environment: {error}")
        try:
            for name in request.allowed_imports:
                template(name)
        except Exception as error:
            return Evaluation(failure=f"environment: importing the spec's allowed modules: {type(error).__name__}: {error}")
        # What exists now is shared with every child: keep their collections from touching it.
        gc.freeze()
        start = time.monotonic()
        deadline = start + request.timeout_s
        if request.mode == REFEREE:
            evaluation = self._referee(envs, request, deadline)
        elif request.mode == FAST:
            evaluation = self._fast(envs[0], request, deadline)
        else:
            evaluation = Evaluation(failure=f"invalid: unknown evaluation mode {request.mode!r}")
        return dataclasses.replace(evaluation, seconds=time.monotonic() - start)

    def _fast(self, env: Environment, request: EvalRequest, deadline: float) -> Evaluation:
        read_fd, write_fd = os.pipe()
        pid = _fork_child(request, keep=(write_fd,), run=lambda: write_all(write_fd, _run_program(env, request).to_bytes()))
        os.close(write_fd)
        try:
            data = _read_reply(read_fd, deadline)
        finally:
            os.close(read_fd)
        failure = _reap(pid, request, deadline, timed_out=data is None)
        if failure:
            return Evaluation(failure=failure)
        try:
            return Evaluation.from_bytes(data, request, env.horizon, env.max_abs_reward)
        except ValueError as error:  # the child ran the program: its reply is the program's
            return Evaluation(failure=f"program: malformed reply: {error}")

    def _referee(self, envs: list[Environment], request: EvalRequest, deadline: float) -> Evaluation:
        with _on_this_cpu():
            return self._exchange(envs, request, deadline)

    def _exchange(self, envs: list[Environment], request: EvalRequest, deadline: float) -> Evaluation:
        observations_read, observations_write = os.pipe()  # worker -> child
        actions_read, actions_write = os.pipe()  # child -> worker
        serve = lambda: serve_policy(request, envs[0].action_size, observations_read, actions_write)  # noqa: E731
        pid = _fork_child(request, keep=(observations_read, actions_write), run=serve)
        os.close(observations_read)
        os.close(actions_write)
        evaluation, timed_out, broken = None, False, ""
        try:
            evaluation = referee_evaluation(envs, request, actions_read, observations_write, deadline)
        except RefereeTimeout:
            timed_out = True
        except ValueError as error:  # an oversize or malformed frame
            broken = f"tampering: the policy process broke the referee protocol: {error}"
        except (EOFError, OSError):  # the child died, or closed its end
            pass
        finally:
            os.close(actions_read)
            os.close(observations_write)
        if evaluation is None and not broken:
            failure = _reap(pid, request, deadline, timed_out)
            return Evaluation(failure=failure or "tampering: the policy process broke the referee protocol")
        # Done with the child: told to quit (or cut off), it has a few seconds to be gone, not
        # the request's whole time limit.
        failure = _reap(pid, request, time.monotonic() + _QUIT_GRACE_S, timed_out=False)
        if broken:
            return Evaluation(failure=broken)
        if failure is not None and failure.startswith("timeout:"):  # it had to be killed
            return Evaluation(evaluation.returns, "tampering: the policy process outlived the referee's quit message", evaluation.steps)
        return evaluation


@contextlib.contextmanager
def _on_this_cpu() -> Iterator[None]:
    """The worker, and the child it forks meanwhile (which inherits the mask), kept on the CPU the
    worker is on for one lockstep exchange, then free again. The two hand a frame back and forth
    at every control step and never run at once; on two CPUs each hand-over would wake the other
    CPU (docs/referee-cost.md). Where the mask cannot be set, nothing changes."""
    try:
        allowed = os.sched_getaffinity(0)
        cpu = _LIBC.sched_getcpu()
        pinned = len(allowed) > 1 and cpu in allowed
        if pinned:
            os.sched_setaffinity(0, {cpu})
    except OSError:
        pinned = False
    try:
        yield
    finally:
        if pinned:
            os.sched_setaffinity(0, allowed)


def _run_program(env: Environment, request: EvalRequest) -> Evaluation:
    """In the child: the program's fast-path evaluation, a fresh program instance per episode."""
    program, refusal = compile_or_explain(request.skeleton, request.allowed_imports, request.params, request.coverage)
    if program is None:
        return Evaluation(failure=refusal)
    try:
        evaluation = evaluate_program(env, program.new_policy, request.seeds, request.steps, request.race)
    except BaseException as error:  # SystemExit and friends raised by the policy
        return Evaluation(failure=describe_exception(error))
    return evaluation if program.probe is None else dataclasses.replace(evaluation, coverage=program.probe.result())


def _fork_child(request: EvalRequest, keep: tuple[int, ...], run: Callable[[], Any]) -> int:
    """Fork a child that confines itself, runs `run` and exits without running any clean-up
    code (nothing of the program runs after its reply)."""
    pid = os.fork()
    if pid:
        return pid
    code = 70  # the child's own machinery failed (EX_SOFTWARE)
    try:
        enter_sandbox(keep, request.memory_mb, request.timeout_s)
        run()
        code = 0
    finally:
        os._exit(code)


def _read_reply(fd: int, deadline: float) -> bytes | None:
    """The child's whole reply (up to end of file); None if the deadline passes first."""
    chunks, size = [], 0
    while True:
        remaining = deadline - time.monotonic()
        if remaining <= 0 or not select.select([fd], [], [], remaining)[0]:
            return None
        chunk = os.read(fd, 65536)
        if not chunk or size > _MAX_REPLY_BYTES:
            return b"".join(chunks)
        chunks.append(chunk)
        size += len(chunk)


def _reap(pid: int, request: EvalRequest, deadline: float, timed_out: bool) -> str | None:
    """Collect the child, killing it if it is still running at the deadline (a child that has
    replied is exiting: it gets `_EXIT_GRACE_S` more); the failure its end means, if any."""
    if not timed_out:
        pidfd = os.pidfd_open(pid)
        try:
            timed_out = not select.select([pidfd], [], [], max(deadline - time.monotonic(), 0) + _EXIT_GRACE_S)[0]
        finally:
            os.close(pidfd)
    if timed_out:
        os.kill(pid, signal.SIGKILL)
    _, status = os.waitpid(pid, 0)
    if timed_out:
        return f"timeout: the evaluation took longer than {request.timeout_s:g} s"
    if os.WIFSIGNALED(status):
        code = os.WTERMSIG(status)
        return _CHILD_EXITS.get(code, f"crash: the evaluation process was killed by {signal.Signals(code).name}")
    if os.WEXITSTATUS(status) != 0:
        return f"crash: the evaluation process exited with code {os.WEXITSTATUS(status)}"
    return None


def _isolate(parent_pid: int) -> None:
    """Start-up hardening of the worker itself: it dies with the coordinator, no same-uid
    process (a child whose filter fell, where there is no user drop) can open its /proc/<pid>/
    mem, environ or fd entries, and it has no network where the kernel lets it leave the host's
    network namespace."""
    _LIBC.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    make_undumpable()
    if os.getppid() != parent_pid:  # the coordinator died before prctl took effect
        os._exit(1)
    # Best effort: needs root, or unprivileged user namespaces for the second form.
    if _LIBC.unshare(_CLONE_NEWNET) != 0:
        _LIBC.unshare(_CLONE_NEWUSER | _CLONE_NEWNET)


def _confinement_report() -> bytes:
    """The layers of confinement a child gets on this machine, found by confining a child that
    runs nothing (JSON: `layers`, `warnings`)."""
    read_fd, write_fd = os.pipe()
    pid = os.fork()
    if not pid:
        try:
            confinement = enter_sandbox((write_fd,), memory_mb=1024, cpu_seconds=10)
            write_all(write_fd, json.dumps(dataclasses.asdict(confinement)).encode())
        finally:
            os._exit(0)
    os.close(write_fd)
    report = _read_reply(read_fd, time.monotonic() + 30) or b'{"layers": [], "warnings": ["confinement: the probe failed"]}'
    os.close(read_fd)
    os.waitpid(pid, 0)
    return report


def main(fd: int, parent_pid: int) -> None:
    _isolate(parent_pid)
    connection = Connection(fd)
    worker = Worker()
    connection.send_bytes(b"ready " + _confinement_report())
    while True:
        try:
            request = connection.recv()
        except (EOFError, OSError):
            return
        if request is None:
            return
        try:
            evaluation = worker.evaluate(request)
        except Exception as error:  # a bug here must reach the coordinator, not hang it
            evaluation = Evaluation(failure=f"crash: the sandbox worker failed: {type(error).__name__}: {error}")
        connection.send_bytes(evaluation.to_bytes())


if __name__ == "__main__":
    main(int(sys.argv[1]), int(sys.argv[2]))
