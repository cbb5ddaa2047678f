"""Sandboxed evaluation: untrusted policy code runs only in worker processes, never here.

A program first passes a static check of its AST (only allowed imports, no dangerous
builtins, no dunder attributes). Each worker is a fresh interpreter (`python -m
colmo.sandbox`) started with a clean environment (no API keys or tokens), in its own
session and a private temporary directory, with resource limits (address space, CPU time,
no file writes, no core dumps). The coordinator talks to it over a dedicated socket, so
whatever the policy prints cannot corrupt the protocol. An evaluation that outlives the
wall-clock timeout gets its worker's whole process group killed and replaced.

What crosses to a worker is plain data (`EvalRequest`: spec path, environment options,
episode seeds, skeleton code, parameters), so any executor can carry it.
"""

from __future__ import annotations

import ast
import builtins
import concurrent.futures
import os
import queue
import resource
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass
from multiprocessing.connection import Connection
from typing import TYPE_CHECKING, Any, Protocol, Sequence

from colmo.task import Evaluation

if TYPE_CHECKING:
    from colmo.spec import Spec

FORBIDDEN_NAMES = frozenset({
    "open", "exec", "eval", "compile", "__import__", "globals", "locals", "vars", "getattr",
    "setattr", "delattr", "input", "breakpoint", "exit", "quit", "help", "memoryview",
    "__builtins__", "__loader__", "__spec__", "classmethod", "staticmethod", "super", "type",
    "object", "dir",
})
# numpy functions that read or write files or reach native code.
FORBIDDEN_ATTRIBUTES = frozenset({
    "load", "loadtxt", "genfromtxt", "fromfile", "tofile", "save", "savez", "savez_compressed",
    "savetxt", "memmap", "ctypeslib", "lib", "DataSource", "fromregex", "testing", "f2py",
    "distutils", "show_config", "setbufsize", "seterrcall", "system", "popen",
})
_SAFE_BUILTINS = {
    name: getattr(builtins, name)
    for name in dir(builtins)
    if not name.startswith("_") and name not in FORBIDDEN_NAMES
}


class ForbiddenProgram(ValueError):
    """The program failed the static check; the message is the stored failure reason."""


def check_program(code: str, allowed_imports: Sequence[str]) -> None:
    """Reject code that imports or touches what a policy has no business with."""
    try:
        tree = ast.parse(code)
    except SyntaxError as error:
        raise ForbiddenProgram(f"syntax error: {error.msg} (line {error.lineno})") from None
    allowed = set(allowed_imports)
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            modules = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            modules = [node.module or ""] if node.level == 0 else ["."]
        else:
            modules = []
        for module in modules:
            if module.split(".")[0] not in allowed:
                raise ForbiddenProgram(f"forbidden: import {module}")
        if isinstance(node, ast.Name) and node.id in FORBIDDEN_NAMES:
            raise ForbiddenProgram(f"forbidden: {node.id}")
        if isinstance(node, ast.Attribute) and (node.attr.startswith("__") or node.attr in FORBIDDEN_ATTRIBUTES):
            raise ForbiddenProgram(f"forbidden: .{node.attr}")
        if isinstance(node, (ast.Global, ast.Nonlocal)):
            raise ForbiddenProgram(f"forbidden: {type(node).__name__.lower()} statement")


def _guarded_import(allowed: frozenset[str]):
    def import_(name: str, globals=None, locals=None, fromlist=(), level=0):  # noqa: A002 - mirrors __import__
        if level or name.split(".")[0] not in allowed:
            raise ImportError(f"import of {name!r} is not allowed")
        return builtins.__import__(name, globals, locals, fromlist, level)

    return import_


@dataclass(frozen=True)
class EvalRequest:
    """One candidate evaluation, as plain data."""

    spec: str
    env: tuple[tuple[str, Any], ...]
    seeds: tuple[int, ...]
    skeleton: str
    params: tuple[float, ...]
    allowed_imports: tuple[str, ...]


class Executor(Protocol):
    """Anything that evaluates batches of requests, results in request order (a `WorkerPool`,
    a Ray cluster). Thread-safe: several programs' optimizers share one executor."""

    n_workers: int
    closed: bool

    def evaluate(self, requests: Sequence[EvalRequest]) -> list[Evaluation]: ...

    @property
    def busy_seconds(self) -> float: ...

    def close(self, cancel: bool = False) -> None: ...


def batch_evaluator(executor: Executor, spec: "Spec", env: dict[str, Any], seeds: Sequence[int], skeleton: str):
    """The `evaluate_batch(params_list)` callable that GFO methods use for one program."""
    env_items = tuple(sorted(env.items()))

    def evaluate_batch(params_list: Sequence[Sequence[float]]) -> list[Evaluation]:
        return executor.evaluate([
            EvalRequest(str(spec.path), env_items, tuple(seeds), skeleton, tuple(float(p) for p in params), spec.allowed_imports)
            for params in params_list
        ])

    return evaluate_batch


def compile_policy(skeleton: str, allowed_imports: Sequence[str]) -> dict[str, Any]:
    """Execute a checked skeleton in a namespace of safe builtins; return that namespace.

    The skeleton reads its constants from the global `params`, set per candidate."""
    check_program(skeleton, allowed_imports)
    safe = dict(_SAFE_BUILTINS, __import__=_guarded_import(frozenset(allowed_imports)))
    namespace: dict[str, Any] = {"__builtins__": safe, "__name__": "policy_module", "params": ()}
    exec(compile(skeleton, "<policy>", "exec"), namespace)
    if not callable(namespace.get("policy")):
        raise ForbiddenProgram("no callable `policy` in the program")
    return namespace


class _WorkerState:
    """What a worker keeps between requests: built environments and compiled programs."""

    def __init__(self, max_programs: int = 64):
        self.environments: dict[tuple, Any] = {}
        self.programs: OrderedDict[tuple, dict[str, Any]] = OrderedDict()
        self.max_programs = max_programs

    def environment(self, request: EvalRequest):
        key = (request.spec, request.env)
        if key not in self.environments:
            from colmo.spec import load_spec

            self.environments[key] = load_spec(request.spec).make_environment(**dict(request.env))
        return self.environments[key]

    def program(self, request: EvalRequest) -> dict[str, Any]:
        key = (request.skeleton, request.allowed_imports)
        if key in self.programs:
            self.programs.move_to_end(key)
        else:
            self.programs[key] = compile_policy(request.skeleton, request.allowed_imports)
            if len(self.programs) > self.max_programs:
                self.programs.popitem(last=False)
        return self.programs[key]

    def evaluate(self, request: EvalRequest) -> Evaluation:
        from colmo.task import evaluate_policy

        try:
            env = self.environment(request)
        except Exception as error:  # the spec is the user's, not the program's: say so
            return Evaluation(failure=f"environment: {type(error).__name__}: {error}")
        try:
            namespace = self.program(request)
        except ForbiddenProgram as error:
            return Evaluation(failure=str(error))
        except BaseException as error:  # module-level code of an untrusted program
            return Evaluation(failure=f"exception: {type(error).__name__}: {error} (at import)")
        namespace["params"] = request.params
        try:
            return evaluate_policy(env, namespace["policy"], list(request.seeds))
        except BaseException as error:  # SystemExit and friends raised by the policy
            return Evaluation(failure=f"exception: {type(error).__name__}: {error}")


def _limit_cpu_time(seconds: float) -> None:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    soft = int(usage.ru_utime + usage.ru_stime + seconds) + 1
    _, hard = resource.getrlimit(resource.RLIMIT_CPU)
    resource.setrlimit(resource.RLIMIT_CPU, (soft if hard == resource.RLIM_INFINITY else min(soft, hard), hard))


def _worker_main(fd: int, timeout_s: float) -> None:
    connection = Connection(fd)
    state = _WorkerState()
    connection.send(("ready", os.getpid()))
    while True:
        try:
            request = connection.recv()
        except (EOFError, OSError):
            return
        if request is None:
            return
        _limit_cpu_time(timeout_s)
        connection.send(state.evaluate(request))


def _apply_limits(memory_mb: int) -> None:
    """Runs in the child between fork and exec."""
    memory = memory_mb * 1024 * 1024
    resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
    resource.setrlimit(resource.RLIMIT_FSIZE, (0, 0))
    # Writes past RLIMIT_FSIZE then fail with EFBIG instead of killing the worker.
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)


_PASSED_VARIABLES = ("PATH", "PYTHONPATH", "MENAGERIE_ROOT", "MENAGERIE_CACHE_DIR", "LANG", "LC_ALL")


def clean_environment(tmpdir: str) -> dict[str, str]:
    """The worker's environment: what Python and the simulators need, and nothing else."""
    env = {name: os.environ[name] for name in _PASSED_VARIABLES if name in os.environ}
    env.update(
        HOME=tmpdir, TMPDIR=tmpdir, PYTHONDONTWRITEBYTECODE="1", PYTHONNOUSERSITE="1",
        # One worker per core: numerical libraries must not spawn thread pools of their own.
        OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1",
    )
    return env


_WORKER_EXITS = {
    -signal.SIGKILL: "killed (SIGKILL): out of memory or killed from outside",
    -signal.SIGXCPU: "cpu time limit exceeded",
    -signal.SIGSEGV: "crash: segmentation fault",
}


class _Worker:
    def __init__(self, memory_mb: int, timeout_s: float, tmpdir: str):
        parent, child = socket.socketpair()
        self.process = subprocess.Popen(
            [sys.executable, "-m", "colmo.sandbox", str(child.fileno()), str(timeout_s)],
            pass_fds=(child.fileno(),), env=clean_environment(tmpdir), cwd=tmpdir,
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            start_new_session=True, preexec_fn=lambda: _apply_limits(memory_mb),
        )
        child.close()
        self.connection = Connection(parent.detach())

    def kill(self) -> None:
        try:
            os.killpg(self.process.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        self.process.wait()
        self.connection.close()

    def exit_reason(self) -> str:
        code = self.process.wait()
        return _WORKER_EXITS.get(code, f"worker exited with code {code}")


class WorkerPool:
    """`workers` sandboxed processes evaluating `EvalRequest`s; results come back as futures."""

    def __init__(self, workers: int, timeout_s: float = 600.0, memory_mb: int = 4096, startup_timeout_s: float = 120.0):
        self.timeout_s = timeout_s
        self.memory_mb = memory_mb
        self.startup_timeout_s = startup_timeout_s
        self.tmpdir = tempfile.mkdtemp(prefix="colmo-sandbox-")
        self.jobs: queue.Queue = queue.Queue()
        self.closed = False
        self._busy = [0.0] * workers
        self.threads = [threading.Thread(target=self._dispatch, daemon=True, name=f"colmo-worker-{i}") for i in range(workers)]
        self.workers: list[_Worker | None] = [None] * workers
        self.n_workers = workers
        for thread in self.threads:
            thread.start()

    @property
    def busy_seconds(self) -> float:
        """Seconds the workers spent evaluating, summed over workers."""
        return sum(self._busy)

    def submit(self, request: EvalRequest) -> concurrent.futures.Future:
        if self.closed:
            raise RuntimeError("the worker pool is closed")
        future: concurrent.futures.Future = concurrent.futures.Future()
        self.jobs.put((request, future))
        return future

    def evaluate(self, requests: Sequence[EvalRequest]) -> list[Evaluation]:
        return [future.result() for future in [self.submit(request) for request in requests]]

    def _start_worker(self) -> _Worker:
        worker = _Worker(self.memory_mb, self.timeout_s, self.tmpdir)
        if not worker.connection.poll(self.startup_timeout_s):
            worker.kill()
            raise RuntimeError("a sandbox worker did not start in time")
        try:
            worker.connection.recv()
        except EOFError:
            raise RuntimeError(f"a sandbox worker failed to start: {worker.exit_reason()}") from None
        return worker

    def _dispatch(self) -> None:
        index = self.threads.index(threading.current_thread())
        while True:
            job = self.jobs.get()
            if job is None:
                break
            request, future = job
            if not future.set_running_or_notify_cancel():
                continue
            start = time.perf_counter()
            try:
                future.set_result(self._run(index, request))
            except BaseException as error:  # the pool itself broke: the caller must hear of it
                future.set_exception(error)
            self._busy[index] += time.perf_counter() - start
        worker = self.workers[index]
        if worker is not None:
            worker.kill()

    def _run(self, index: int, request: EvalRequest) -> Evaluation:
        worker = self.workers[index]
        if worker is None or worker.process.poll() is not None:
            worker = self.workers[index] = self._start_worker()
        try:
            worker.connection.send(request)
            if worker.connection.poll(self.timeout_s):
                return worker.connection.recv()
            reason = f"timeout: evaluation took longer than {self.timeout_s:g} s"
        except (EOFError, OSError):
            reason = worker.exit_reason()
        worker.kill()
        self.workers[index] = None
        return Evaluation(failure=reason)

    def close(self, cancel: bool = False) -> None:
        """Stop the workers: after the queued jobs, or at once (`cancel`) with queued jobs cancelled."""
        self.closed = True
        if cancel:
            self._cancel_queued()
            for worker in list(self.workers):
                if worker is not None:
                    worker.kill()
        for _ in self.threads:
            self.jobs.put(None)
        for thread in self.threads:
            thread.join()
        shutil.rmtree(self.tmpdir, ignore_errors=True)

    def _cancel_queued(self) -> None:
        while True:
            try:
                job = self.jobs.get_nowait()
            except queue.Empty:
                return
            if job is not None:
                job[1].cancel()

    def __enter__(self) -> "WorkerPool":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


if __name__ == "__main__":
    _worker_main(int(sys.argv[1]), float(sys.argv[2]))
