"""The coordinator's handle on one sandbox worker process (`colmo.sandbox.worker`).

`SandboxProcess` starts the worker as a fresh interpreter with a clean environment (no API
keys or tokens), in its own session and process group, its working directory a private
temporary directory that is removed once the worker is ready (it writes nothing after, and a
coordinator killed with SIGKILL leaves no directory behind), with an address-space limit, no core dumps and a file size limit of 0
(no file writes; SIGXFSZ ignored so a write fails instead of killing it). `evaluate` sends one
request and waits for the reply, a checked JSON `Evaluation` (never unpickled: even a worker
taken over by a program cannot run code here). The worker enforces each request's time limit
itself; the coordinator waits `_BACKSTOP_S` longer, then kills the worker's whole process
group. A worker that dies or breaks the protocol raises `WorkerLost`: the executor retries
its request on a fresh worker.
"""

from __future__ import annotations

import json
import logging
import os
import resource
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
from multiprocessing.connection import Connection

from colmo.evaluation import EvalRequest, Evaluation, WorkerLost

log = logging.getLogger("colmo.sandbox")

_MAX_REPLY_BYTES = 64 << 20  # an episode trace of the quadruped is 2.6 MB
_BACKSTOP_S = 60.0  # past a request's own limit: the worker itself is stuck (building a simulator)
_PASSED_VARIABLES = ("PATH", "PYTHONPATH", "MENAGERIE_ROOT", "MENAGERIE_CACHE_DIR", "LANG", "LC_ALL")
_WORKER_EXITS = {
    -signal.SIGKILL: "the worker was killed (SIGKILL): out of memory, or killed from outside",
    -signal.SIGSEGV: "the worker crashed (segmentation fault)",
}


def clean_environment(tmpdir: str) -> dict[str, str]:
    """The worker's environment: what Python and the simulators need, and nothing else."""
    env = {name: os.environ[name] for name in _PASSED_VARIABLES if name in os.environ}
    env.update(
        HOME=tmpdir, TMPDIR=tmpdir, PYTHONDONTWRITEBYTECODE="1", PYTHONNOUSERSITE="1",
        # The same hash() of a string in every worker: a policy's score must not depend on which ran it.
        PYTHONHASHSEED="0",
        # One worker per core: numerical libraries must not spawn thread pools of their own.
        OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1",
    )
    return env


def _apply_limits(memory_mb: int) -> None:
    """Runs in the worker between fork and exec."""
    memory = memory_mb * 1024 * 1024
    resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
    resource.setrlimit(resource.RLIMIT_FSIZE, (0, 0))
    # Writes past RLIMIT_FSIZE then fail with EFBIG instead of killing the worker.
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)


_logged: set[str] = set()


def _log_confinement(report: dict) -> None:
    """Say once per process which confinement layers evaluations get, and warn once about each
    layer the kernel refused."""
    layers = ", ".join(report.get("layers", ()))
    if layers not in _logged:
        _logged.add(layers)
        log.info("sandbox: each evaluation runs in a process confined by: %s", layers or "no OS layer")
    for warning in report.get("warnings", ()):
        if warning not in _logged:
            _logged.add(warning)
            log.warning("sandbox: %s (the other layers still apply)", warning)


class SandboxProcess:
    """One running sandbox worker. Not thread-safe: one dispatcher thread uses it."""

    def __init__(self, memory_mb: int, startup_timeout_s: float = 120.0):
        workdir = tempfile.mkdtemp(prefix="colmo-sandbox-")
        try:
            self._start(workdir, memory_mb, startup_timeout_s)
        finally:
            shutil.rmtree(workdir, ignore_errors=True)
        _log_confinement(self.confinement)

    def _start(self, workdir: str, memory_mb: int, startup_timeout_s: float) -> None:
        parent, child = socket.socketpair()
        self.process = subprocess.Popen(
            [sys.executable, "-m", "colmo.sandbox.worker", str(child.fileno()), str(os.getpid())],
            pass_fds=(child.fileno(),), env=clean_environment(workdir), cwd=workdir,
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            start_new_session=True, preexec_fn=lambda: _apply_limits(memory_mb),
        )
        child.close()
        self.connection = Connection(parent.detach())
        if not self.connection.poll(startup_timeout_s):
            self.kill()
            raise WorkerLost("a sandbox worker did not start in time")
        try:
            ready = self.connection.recv_bytes(_MAX_REPLY_BYTES)
            self.confinement = json.loads(ready.removeprefix(b"ready "))
        except (EOFError, OSError, ValueError):
            raise WorkerLost(f"a sandbox worker failed to start: {self.exit_reason()}") from None

    @property
    def pid(self) -> int:
        return self.process.pid

    def alive(self) -> bool:
        return self.process.poll() is None

    def evaluate(self, request: EvalRequest) -> Evaluation:
        """The worker's evaluation of `request`; `WorkerLost` if it died or broke the protocol."""
        try:
            self.connection.send(request)
            if not self.connection.poll(request.timeout_s + _BACKSTOP_S):
                raise WorkerLost(f"the worker did not answer within {request.timeout_s + _BACKSTOP_S:g} s")
            return Evaluation.from_bytes(self.connection.recv_bytes(_MAX_REPLY_BYTES), request)
        except (EOFError, OSError):
            raise WorkerLost(self.exit_reason()) from None
        except (ValueError, KeyError, TypeError) as error:
            raise WorkerLost(f"the worker sent a malformed reply: {error}") from None

    def kill(self) -> None:
        """Kill the worker and every process it started (its whole process group)."""
        try:
            os.killpg(self.process.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        self.process.wait()
        self.connection.close()

    def exit_reason(self) -> str:
        """Why the worker stopped answering; it may still be running if it broke the protocol."""
        try:
            code = self.process.wait(timeout=5)
        except subprocess.TimeoutExpired:
            return "the worker broke the protocol"
        if code in _WORKER_EXITS:
            return _WORKER_EXITS[code]
        if code < 0:
            return f"the worker was killed by {signal.Signals(-code).name}"
        return f"the worker exited with code {code}"
