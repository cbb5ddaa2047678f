"""The referee: scores that a program cannot forge.

In referee mode the sandbox worker, a trusted process that never runs program code, owns the
simulator and the reward; the program runs in a separate confined child that only receives
observations and returns actions, over two pipes. Whatever the child does to itself (an escape
of the Python-level checks included), it can change only the actions it sends, which is what a
policy does anyway: the returns are computed here.

The episodes of a request run in lockstep, in batches of up to `LOCKSTEP` episodes, each in
its own copy of the environment, and the child holds one fresh program instance per episode
(`Program.new_policy`), so one frame each way per control step serves a whole batch (a pipe
round trip per step of the batch, not per step of each episode). Episodes are independent, so
this returns what running them one after another returns: when episode k fails, the later ones
are dropped and the earlier ones run on; the first failing episode in seed order fails the
evaluation, and racing is decided on the returns in seed order.

Wire format, both ways: frames of a tag byte, a payload length (4 bytes, little endian) and
the payload. Worker to child: `S` + a batch's first episode index (uint32) and its seeds
(int64 each) at the batch's start, then per step `O` + the number of live episodes (uint32),
their indices (uint32 each, ascending) and their observations (float64, one row each), and
`Q` to quit. Child to worker, per `O`: an `F` frame (an episode index, uint32, and a failure
reason, UTF-8) for each live episode whose policy failed, then `A` + the actions of the
others, in order (float64, exactly `action_size` values each), all in one write; after `Q`,
where the request asks for branch coverage (`colmo.coverage`), `C` + the counts of each site
(three uint64 each). Every write
of the worker is bounded by the request's deadline: a child that stops reading cannot block
it. Its descriptors are non-blocking, so a step costs it one write and one read, and a wait
(bounded by the deadline) only when the child has not answered yet. What each side derives
from the live episodes (the frame's header, the environments or instances to step) is kept
until an episode fails, so a step costs little Python beyond the simulator and the policies:
the lockstep's cost is the round trip itself, two process switches per control step.

With `trace` set, a request runs one episode, which the worker also records as it steps it
(`colmo.trace.TraceRecorder`) and returns in `Evaluation.trace`: the recording is as
trustworthy as the returns, since the child takes no part in it.

Both sides run what the fast path runs: the worker steps its episodes through the same loop
(`colmo.rollout.Episodes`: seeding, reset, step, reward sum, end check, failure order, racing),
the child calls the same `act` (policy call and action check) with the same failure reasons,
each instance's `np.random` seeded as the episode seeds the global one, so a referee evaluation
returns exactly what the fast path returns for an honest program.
"""

from __future__ import annotations

import dataclasses
import math
import os
import select
import struct
import time
from typing import Callable, Sequence

import numpy as np

from colmo.coverage import Counts, checked_counts
from colmo.environments.base import Environment, PolicyFailure
from colmo.errors import describe_exception, failure_reason
from colmo.evaluation import EvalRequest, Evaluation
from colmo.rollout import Episode, Episodes, act
from colmo.sandbox.namespace import compile_or_explain
from colmo.trace import MAX_STEPS, TraceError, TraceRecorder

_HEADER = struct.Struct("<cI")
_COUNT = struct.Struct("<I")  # an episode index or count
_MAX_FRAME = 1 << 20
LOCKSTEP = 16  # episodes stepped side by side: the environments the worker keeps per task
_COVERAGE_WAIT_S = 2.0  # for the child's counts after `Q`: a child that keeps them costs the worker no more


class RefereeTimeout(Exception):
    """The child did not answer, or did not read, before the evaluation's deadline."""


def write_all(fd: int, data: bytes, deadline: float = math.inf) -> None:
    """Write all of `data` to the pipe `fd` (a write may take only part of it); with a finite
    `deadline`, `fd` is made non-blocking and `RefereeTimeout` is raised once it passes with
    data still unwritten (the reader stopped reading)."""
    if math.isinf(deadline):
        while data:
            data = data[os.write(fd, data):]
        return
    os.set_blocking(fd, False)
    _write_before(fd, data, deadline)


def _write_before(fd: int, data: bytes, deadline: float) -> None:
    """`write_all` on the non-blocking `fd`: a write first, a wait only when the pipe is full
    (a frame is far smaller than a pipe, so a step's write is one system call)."""
    while data:
        try:
            data = data[os.write(fd, data):]
            continue
        except BlockingIOError:
            pass
        remaining = deadline - time.monotonic()
        if remaining <= 0 or not select.select([], [fd], [], remaining)[1]:
            raise RefereeTimeout


def frame(tag: bytes, payload: bytes = b"") -> bytes:
    """One frame of the wire format (module docstring)."""
    return _HEADER.pack(tag, len(payload)) + payload


class _Channel:
    """Frames over a pair of pipe descriptors; with a finite deadline (the worker's side) both
    are made non-blocking once and every read and write is bounded by it, without one (the
    child's side) reads and writes block. A step costs one write each way, and one read when
    the answer is there (one wait more when it is not yet)."""

    def __init__(self, read_fd: int, write_fd: int, deadline: float = math.inf):
        self.read_fd, self.write_fd, self.deadline = read_fd, write_fd, deadline
        # What was read and not yet returned: `pending[offset:]` (one read is one frame, the
        # common case, returned without copying the stream into a buffer first).
        self.pending, self.offset = b"", 0
        self.bounded = not math.isinf(deadline)
        if self.bounded:
            os.set_blocking(read_fd, False)
            os.set_blocking(write_fd, False)
            self.readable = select.poll()
            self.readable.register(read_fd, select.POLLIN)

    def send(self, frames: bytes) -> None:
        """Write `frames` (made by `frame`, any number of them) in one write where the pipe takes it."""
        if self.bounded:
            _write_before(self.write_fd, frames, self.deadline)
        else:
            write_all(self.write_fd, frames)

    def receive(self) -> tuple[bytes, bytes]:
        """The next frame's tag and payload; `EOFError` at the end of the stream."""
        while True:
            pending, offset = self.pending, self.offset
            if len(pending) - offset >= _HEADER.size:
                tag, length = _HEADER.unpack_from(pending, offset)
                if length > _MAX_FRAME:
                    raise ValueError(f"frame of {length} bytes")
                start = offset + _HEADER.size
                if start + length <= len(pending):
                    self.offset = start + length
                    return tag, pending[start:self.offset]
            self.pending, self.offset = pending[offset:] + self._read(), 0

    def _read(self) -> bytes:
        """What the pipe holds, waiting (until the deadline) for it."""
        while True:
            try:
                chunk = os.read(self.read_fd, 65536)
                break
            except BlockingIOError:  # only on the worker's side: wait, bounded
                remaining = self.deadline - time.monotonic()
                if remaining <= 0 or not self.readable.poll(math.ceil(remaining * 1000)):
                    raise RefereeTimeout from None
        if not chunk:
            raise EOFError
        return chunk


def serve_policy(request: EvalRequest, action_size: int, read_fd: int, write_fd: int) -> None:
    """The child's side: a fresh program instance per episode, then, for each step, the
    actions of the live episodes (or why an episode's policy failed) until told to quit."""
    channel = _Channel(read_fd, write_fd)
    program, refusal = compile_or_explain(request.skeleton, request.allowed_imports, request.params, request.coverage)
    policies: dict[int, Callable[..., object]] = {}
    failures: list[tuple[int, str]] = []
    step = 0
    framed: bytes | None = None  # the live episodes' indices as last sent ...
    acting: list[tuple[int, Callable[..., object] | None]] = []  # ... and their (index, policy)
    while True:
        try:
            tag, payload = channel.receive()
        except EOFError:
            return
        if tag == b"S":  # a batch of episodes starts: one fresh instance each
            (first,) = _COUNT.unpack_from(payload)
            policies, failures, step, framed = {}, [], 0, None
            for index, seed in enumerate(np.frombuffer(payload, dtype="<i8", offset=_COUNT.size).tolist(), start=first):
                try:
                    if program is None:
                        raise PolicyFailure(refusal)
                    policies[index] = program.new_policy(seed)
                except PolicyFailure as failure:
                    failures.append((index, failure_reason(str(failure))))
            continue
        if tag != b"O":
            if tag == b"Q" and program is not None and program.probe is not None:
                counts = np.asarray(program.probe.result(), dtype="<u8").tobytes()
                if len(counts) <= _MAX_FRAME:
                    channel.send(frame(b"C", counts))
            return
        (count,) = _COUNT.unpack_from(payload)
        header = _COUNT.size + 4 * count
        if payload[_COUNT.size:header] != framed:  # the first step, or the worker dropped episodes
            framed = payload[_COUNT.size:header]
            # An episode without an instance failed at its load, or at an earlier step: reported.
            acting = [(index, policies.get(index)) for index in np.frombuffer(framed, dtype="<u4").tolist()]
        observations = np.frombuffer(payload, dtype=np.float64, offset=header).reshape(count, -1)
        actions = []
        for (index, policy), obs in zip(acting, observations):
            if policy is None:
                continue
            try:
                actions.append(act(policy, obs.copy(), action_size, step).tobytes())
            except PolicyFailure as failure:  # its text is the program's to choose (a type's name): bounded
                failures.append((index, failure_reason(str(failure))))
            except BaseException as error:  # SystemExit and friends raised by the policy
                failures.append((index, describe_exception(error, f" (step {step})")))
        reports = b""
        if failures:
            reports = b"".join(frame(b"F", _COUNT.pack(index) + reason.encode()) for index, reason in failures)
            for index, _ in failures:
                policies.pop(index, None)
            failures, framed = [], None
        body = b"".join(actions)
        channel.send(reports + _HEADER.pack(b"A", len(body)) + body)  # one write per step
        step += 1


def referee_evaluation(envs: Sequence[Environment], request: EvalRequest, read_fd: int, write_fd: int, deadline: float) -> Evaluation:
    """The worker's side: run the episodes of `request` in lockstep, `len(envs)` at a time
    (episode i in `envs[i % len(envs)]`), asking the child for all the live episodes' actions
    at each step. Raises `RefereeTimeout` past `deadline` and `EOFError` if the child stops
    answering. With `request.trace`, the one episode of the request is recorded too (module
    docstring)."""
    recorder = None
    if request.trace:
        if len(request.seeds) != 1 or (request.steps or envs[0].horizon) > MAX_STEPS:
            return Evaluation(failure=f"invalid: a traced evaluation runs one episode of at most {MAX_STEPS} steps")
        recorder = TraceRecorder(envs[0])
    channel = _Channel(read_fd, write_fd, deadline)
    episodes = Episodes(envs, request.seeds, request.steps, request.race)
    for first in range(0, len(request.seeds), len(envs)):
        batch = range(first, min(first + len(envs), len(request.seeds)))
        channel.send(frame(b"S", _COUNT.pack(first) + np.asarray(request.seeds[first:batch.stop], dtype="<i8").tobytes()))
        episodes.run(batch, _Exchange(channel, episodes, envs[0].action_size), recorder)
        if episodes.settled:
            break
    channel.send(frame(b"Q"))
    evaluation = episodes.evaluation()
    if request.coverage:
        evaluation = dataclasses.replace(evaluation, coverage=_coverage(channel))
    if recorder is None or evaluation.failure is not None:
        return evaluation
    try:
        trace = recorder.finish().to_dict()
    except TraceError as error:  # e.g. non-finite observations: nothing a renderer could draw
        return Evaluation(evaluation.returns, str(error), evaluation.steps)
    return Evaluation(evaluation.returns, None, evaluation.steps, trace=trace)


def _coverage(channel: _Channel) -> tuple[Counts, ...] | None:
    """The counts the child sends after `Q` when the request asks for coverage (`colmo.coverage`),
    or None where it sends none in time or a malformed frame: they describe the program, and take
    no part in its score, so their absence fails nothing."""
    channel.deadline = min(channel.deadline, time.monotonic() + _COVERAGE_WAIT_S)
    try:
        tag, payload = channel.receive()
        if tag != b"C" or len(payload) % 24:
            return None
        return checked_counts(np.frombuffer(payload, dtype="<u8").reshape(-1, 3).tolist())
    except (RefereeTimeout, EOFError, OSError, ValueError):
        return None


class _Exchange:
    """The worker's side of a batch's control steps (`colmo.rollout.Actions`): the live episodes'
    observations to the child, their actions back, checked here (they come from untrusted
    code). The frame's header, derived from the live episodes, is kept until one fails."""

    def __init__(self, channel: _Channel, episodes: Episodes, action_size: int):
        self.channel, self.episodes, self.action_size = channel, episodes, action_size
        self.framed: list[Episode] | None = None
        self.indices: list[int] = []
        self.header = b""

    def __call__(self, live: list[Episode], step: int) -> np.ndarray:
        if live is not self.framed:  # the first step, or a failure changed the live episodes
            self.framed, self.indices = live, [episode.index for episode in live]
            self.header = _COUNT.pack(len(live)) + np.asarray(self.indices, dtype="<u4").tobytes()
        body = np.array([episode.obs for episode in live], dtype=np.float64).tobytes()
        self.channel.send(_HEADER.pack(b"O", len(self.header) + len(body)) + self.header + body)
        acting, actions = self._receive()
        if self.episodes.live is not live:  # some failed: the actions of the episodes still live
            still = {episode.index for episode in self.episodes.live}
            actions = actions[[k for k, index in enumerate(acting) if index in still]]
        return actions

    def _receive(self) -> tuple[list[int], np.ndarray]:
        """The episodes that act and their actions, one row each. The failures the child
        reports, and malformed answers, go to `episodes`."""
        indices, episodes, size = self.indices, self.episodes, self.action_size
        failed = set()
        while True:
            tag, payload = self.channel.receive()
            if tag != b"F":
                break
            (index,) = _COUNT.unpack_from(payload) if len(payload) >= _COUNT.size else (-1,)
            if index not in indices or index in failed:
                episodes.fail(indices[0], "tampering: the policy process sent a malformed action")
                return [], np.empty((0, size))
            failed.add(index)
            episodes.fail(index, failure_reason(payload[_COUNT.size:].decode("utf-8", errors="replace")))
        acting = [index for index in indices if index not in failed] if failed else indices
        if tag != b"A" or len(payload) != 8 * size * len(acting):
            episodes.fail(indices[0], "tampering: the policy process sent a malformed action")
            return [], np.empty((0, size))
        # A copy: the environment gets writable actions, as in the fast path.
        actions = np.frombuffer(payload, dtype=np.float64).reshape(len(acting), size).copy()
        # A finite sum means finite values (a NaN or an infinity makes it NaN or infinite); finite
        # values whose sum overflows go to the exact check, which finds no culprit. Summed as
        # Python floats: for a few values, cheaper than numpy's per-call cost.
        if not math.isfinite(sum(actions.ravel().tolist())):
            for index, finite in zip(acting, np.isfinite(actions).all(axis=1).tolist()):
                if not finite:
                    episodes.fail(index, "tampering: the policy process sent a malformed action")
        return acting, actions
