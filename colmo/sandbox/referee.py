"""The referee: scores that a program cannot forge.

In referee mode the sandbox worker, a trusted process that never runs program code, owns the
simulator and the reward; the program runs in a separate confined child that only receives
observations and returns actions, over two pipes. Whatever the child does to itself (an escape
of the Python-level checks included), it can change only the actions it sends, which is what a
policy does anyway: the returns are computed here.

Wire format, both ways: frames of a tag byte, a payload length (4 bytes, little endian) and
the payload. Worker to child: `E` + episode seed (int64) at each episode start, `O` + the
observation (float64), `Q` to quit. Child to worker: `A` + the action (float64, exactly
`action_size` values) or `F` + a failure reason (UTF-8), after which the child is done.

With `trace` set, a request runs one episode, which the worker also records as it steps it
(`colmo.trace.TraceRecorder`) and returns in `Evaluation.trace`: the recording is as
trustworthy as the returns, since the child takes no part in it.

The child mirrors `colmo.task.rollout`: the same global numpy seeding per episode, the same
`act` (policy call and action check) and failure reasons, so a referee evaluation returns
exactly what the fast path returns for an honest program.
"""

from __future__ import annotations

import math
import os
import select
import struct
import time
from typing import Optional

import numpy as np

from colmo.errors import describe_exception, failure_reason
from colmo.evaluation import EvalRequest, Evaluation
from colmo.sandbox.namespace import load_or_explain
from colmo.task import Environment, PolicyFailure, act
from colmo.trace import MAX_STEPS, TraceError, TraceRecorder

_HEADER = struct.Struct("<cI")
_MAX_FRAME = 1 << 20


class RefereeTimeout(Exception):
    """The child did not answer before the evaluation's deadline."""


def write_all(fd: int, data: bytes) -> None:
    """Write all of `data` to the pipe `fd` (a write may take only part of it)."""
    while data:
        data = data[os.write(fd, data):]


class _Channel:
    """Frames over a pair of pipe descriptors, reads bounded by a deadline."""

    def __init__(self, read_fd: int, write_fd: int, deadline: float = float("inf")):
        self.read_fd, self.write_fd, self.deadline = read_fd, write_fd, deadline
        self.buffer = b""

    def send(self, tag: bytes, payload: bytes = b"") -> None:
        write_all(self.write_fd, _HEADER.pack(tag, len(payload)) + payload)

    def receive(self) -> tuple[bytes, bytes]:
        tag, length = _HEADER.unpack(self._read(_HEADER.size))
        if length > _MAX_FRAME:
            raise ValueError(f"frame of {length} bytes")
        return tag, self._read(length)

    def _read(self, size: int) -> bytes:
        while len(self.buffer) < size:
            remaining = self.deadline - time.monotonic()
            if remaining <= 0 or not select.select([self.read_fd], [], [], None if math.isinf(remaining) else remaining)[0]:
                raise RefereeTimeout
            chunk = os.read(self.read_fd, max(65536, size - len(self.buffer)))
            if not chunk:
                raise EOFError
            self.buffer += chunk
        data, self.buffer = self.buffer[:size], self.buffer[size:]
        return data


def serve_policy(request: EvalRequest, action_size: int, read_fd: int, write_fd: int) -> None:
    """The child's side: load the program, then answer observations with actions until told
    to quit or until the policy fails (then say why)."""
    channel = _Channel(read_fd, write_fd)
    policy, failure = load_or_explain(request.skeleton, request.allowed_imports, request.params)
    if failure:
        channel.send(b"F", failure.encode())
        return
    step = 0
    while True:
        try:
            tag, payload = channel.receive()
        except EOFError:
            return
        if tag == b"E":
            (seed,) = struct.unpack("<q", payload)
            np.random.seed(seed % 2**32)
            step = 0
        elif tag == b"O":
            try:
                action = act(policy, np.frombuffer(payload, dtype=np.float64).copy(), action_size, step)
            except PolicyFailure as failure:  # its text is the program's to choose (a type's name): bounded
                channel.send(b"F", failure_reason(str(failure)).encode())
                return
            except BaseException as error:  # SystemExit and friends raised by the policy
                channel.send(b"F", describe_exception(error, f" (step {step})").encode())
                return
            channel.send(b"A", action.tobytes())
            step += 1
        else:
            return


def referee_evaluation(env: Environment, request: EvalRequest, read_fd: int, write_fd: int, deadline: float) -> Evaluation:
    """The worker's side: run the episodes of `request`, asking the child for every action.
    Raises `RefereeTimeout` past `deadline` and `EOFError` if the child stops answering.
    With `request.trace`, the one episode of the request is recorded too (module docstring)."""
    recorder = None
    if request.trace:
        if len(request.seeds) != 1 or (request.steps or env.horizon) > MAX_STEPS:
            return Evaluation(failure=f"invalid: a traced evaluation runs one episode of at most {MAX_STEPS} steps")
        recorder = TraceRecorder(env)
    channel = _Channel(read_fd, write_fd, deadline)
    returns: list[float] = []
    simulated = 0
    for seed in request.seeds:
        np.random.seed(seed % 2**32)  # as rollout does, for any environment that draws from it
        channel.send(b"E", struct.pack("<q", seed))
        obs = env.reset(seed)
        if recorder is not None:
            recorder.start(obs)
        total = 0.0
        for _ in range(request.steps or env.horizon):
            channel.send(b"O", np.asarray(obs, dtype=np.float64).tobytes())
            action = _action(channel, env.action_size)
            if isinstance(action, str):
                return Evaluation(tuple(returns), action, simulated)
            reward, obs = env.step(action)
            if recorder is not None:
                recorder.step(action, reward, obs)
            total += reward
            simulated += 1
        try:
            env.check_episode()
        except PolicyFailure as failure:
            return Evaluation(tuple(returns), str(failure), simulated)
        returns.append(total)
        if request.race is not None and request.race.gives_up(returns):
            return Evaluation(tuple(returns), None, simulated, raced_out=True)
    channel.send(b"Q")
    if recorder is None:
        return Evaluation(tuple(returns), None, simulated)
    try:
        trace = recorder.finish().to_dict()
    except TraceError as error:  # e.g. non-finite observations: nothing a renderer could draw
        return Evaluation(tuple(returns), str(error), simulated)
    return Evaluation(tuple(returns), None, simulated, trace=trace)


def _action(channel: _Channel, action_size: int) -> np.ndarray | str:
    """The child's next action, checked here (it comes from untrusted code), or its failure."""
    tag, payload = channel.receive()
    if tag == b"F":
        return failure_reason(payload.decode("utf-8", errors="replace"))
    action: Optional[np.ndarray] = None
    if tag == b"A" and len(payload) == 8 * action_size:
        action = np.frombuffer(payload, dtype=np.float64).copy()
    if action is None or not np.isfinite(action).all():
        return "tampering: the policy process sent a malformed action"
    return action
