"""OS-level confinement of the child process that runs one evaluation of an untrusted program.

Owns what the kernel enforces on that child; the Python-level defences (static check, allowlisted
builtins) live elsewhere and are assumed broken: a program that forges objects (numpy object
arrays over raw buffers, ctypes) reaches the real `__import__`, `open` and any libc function, and
so can make any system call. This layer decides which of those calls can do harm.

Contract. A trusted, pre-warmed worker (the zygote: every module the evaluation needs already
imported, including the lazily loaded `numpy.fft` and `numpy.random`, simulator built) forks one
child per evaluation from its main thread. The child calls `close_inherited_fds` (keeping only its
reply pipe and whatever else it must use), then `confine()`, before it runs any untrusted code;
then it only computes, writes its reply to the already-open pipe and leaves with os._exit (a
normal interpreter exit would run the zygote's atexit handlers, which may try to write or
delete files). The zygote must hold no secret itself (it is a fresh interpreter with a clean
environment): the child inherits its memory. After `confine()` the child cannot open files for
writing, so it must not import anything, and after the user drop it can no longer read files
under root's 0700 home directory (where the Python installation may live) either. Rlimits
(memory, CPU time, RLIMIT_NPROC, which binds once the child is no longer root) must be set
before `confine()`: it refuses setting them afterwards. Supervisors should kill a child with
SIGKILL: it may ignore other signals.

What the child can still do, by design: read what it already holds open (nothing else: the
filter refuses every open, read-only included, so whatever it needs must be imported or opened
in the zygote before the fork); use the CPU and
memory its rlimits allow, on one thread (the filter refuses threads); write to the descriptors
it kept. Other processes running as the unprivileged uid (nobody, by default) share it with
the child: pass a uid nothing else uses where that matters. Landlock would add nothing: it
governs the files a process opens (the child opens none) and, in newer kernels, TCP ports,
signals and abstract sockets (all refused).

Layers, in the order `confine()` applies them; when the kernel refuses one, the others still
apply and `Confinement.warnings` says what is missing:

0. `enter_sandbox` first (colmo's own part, before the kernel layers): resource limits on
   address space and CPU time (the worker set the file size limit to 0), only the descriptors
   the child needs and no new ones beyond the highest of them, no pending signals queued on
   its account, and the Python-level process and signal functions of `os`, `posix` and
   `_posixsubprocess` replaced by ones that refuse (a second line where seccomp is missing).
   The last two limits bound what the kernel counts per user, not per process, and so shares
   with every other process of the uid (the coordinator's, in a run without root): pipe
   buffers and epoll watches (through descriptors), and POSIX timers, each of which reserves
   a queued signal (96,000 of them made every `timer_create` of the user fail).
1. `no_dump`: prctl(PR_SET_DUMPABLE, 0). Processes of the same uid (the other children) cannot
   ptrace it, read its memory or its /proc/<pid>/ files (the kernel makes them root's).
   `no_new_privs`: prctl(PR_SET_NO_NEW_PRIVS, 1), required for an unprivileged process to install
   the filter, and no execve could ever gain privileges (setuid binaries, file capabilities).
2. `user` (only if some uid of the process is root): setgroups([]), setresgid and setresuid to
   the unprivileged ids (default nobody/nogroup). All capabilities go with root: the child cannot
   read root's 0600/0400 files (/proc/<coordinator>/environ with its API keys), signal or ptrace
   root processes, or regain root. The kernel resets the dumpable flag and the parent-death
   signal on a credential change, so both are set again after the drop.
   `no_capabilities` (only if the process still holds any): capset() to empty sets. A worker
   without root that made a user namespace of its own (`colmo.sandbox.worker`) holds every
   capability in it, and so would its child: inert under the filter, which refuses each call
   they would open (mount, unshare, chroot, ptrace, ...), and dropped all the same, so that a
   run without root gives its child what a root run's child has: none.
3. `parent_death_signal`: prctl(PR_SET_PDEATHSIG, SIGKILL by default) so the child dies with the
   zygote (it is tied to the forking thread: fork from the zygote's main thread). If the parent
   died before the signal was armed, the child sends it to itself at once.
4. `seccomp`: the system-call filter of `colmo.sandbox.seccomp` (file writes, networking, new
   processes, signals to others, privilege and kernel surfaces refused with EPERM; every open
   refused too, so a non-root run, which has no user drop, still reads no file of the user).

The worker logs the layers of its first evaluation once, and warns once about any the kernel
refused here; the rest still apply.
"""

from __future__ import annotations

import ctypes
import dataclasses
import errno
import os
import platform
import resource
import signal
import sys
from collections.abc import Callable, Collection

from colmo.sandbox.seccomp import compiled_filter, install_filter

LAYER_NO_DUMP = "no_dump"
LAYER_NO_NEW_PRIVS = "no_new_privs"
LAYER_USER = "user"
LAYER_NO_CAPABILITIES = "no_capabilities"
LAYER_PARENT_DEATH_SIGNAL = "parent_death_signal"
LAYER_SECCOMP = "seccomp"
UNPRIVILEGED_ID = 65534  # nobody / nogroup

_PR_SET_PDEATHSIG = 1
_PR_SET_DUMPABLE = 4
_PR_SET_NO_NEW_PRIVS = 38
_CAPABILITY_VERSION_3 = 0x20080522  # linux/capability.h: two 32-bit words per set
_LIBC = ctypes.CDLL(None, use_errno=True)
# Functions a policy process never needs: process creation and signals. Everything that starts
# a process (`subprocess.Popen`, `os.spawn*`, `pty`) ends in one of these.
_DISARMED = {
    "os": ("fork", "forkpty", "system", "popen", "execv", "execve", "posix_spawn", "posix_spawnp",
           "kill", "killpg", "setsid", "setpgid", "setpgrp"),
    "posix": ("fork", "forkpty", "system", "execv", "execve", "posix_spawn", "posix_spawnp", "kill",
              "killpg", "setsid", "setpgid", "setpgrp"),
    "_posixsubprocess": ("fork_exec",),
    "subprocess": ("_fork_exec",),  # its own reference to _posixsubprocess.fork_exec
}


@dataclasses.dataclass(frozen=True)
class Confinement:
    """What `confine()` achieved: the layers that took effect, in the order applied, and one
    line per layer that was skipped or that the kernel refused."""

    layers: tuple[str, ...]
    warnings: tuple[str, ...]


def _prctl(option: int, argument: int) -> None:
    result = _LIBC.prctl(
        ctypes.c_int(option), ctypes.c_ulong(argument), ctypes.c_ulong(0), ctypes.c_ulong(0),
        ctypes.c_ulong(0),
    )  # fmt: skip
    if result != 0:
        number = ctypes.get_errno()
        raise OSError(number, os.strerror(number))


def make_undumpable() -> None:
    """prctl(PR_SET_DUMPABLE, 0): no process of the same uid may open this one's /proc/<pid>/
    mem, environ or fd entries, nor ptrace it (the worker at start-up, every child in `confine`)."""
    _prctl(_PR_SET_DUMPABLE, 0)


class _CapabilityHeader(ctypes.Structure):
    _fields_ = [("version", ctypes.c_uint32), ("pid", ctypes.c_int)]


class _CapabilitySets(ctypes.Structure):
    _fields_ = [("effective", ctypes.c_uint32), ("permitted", ctypes.c_uint32), ("inheritable", ctypes.c_uint32)]


def _capability_sets(call: Callable[..., int]) -> ctypes.Array[_CapabilitySets]:
    """The sets after capget() (read) or capset() (of empty sets) on this process."""
    header, sets = _CapabilityHeader(_CAPABILITY_VERSION_3, 0), (_CapabilitySets * 2)()
    if call(ctypes.byref(header), sets) != 0:
        number = ctypes.get_errno()
        raise OSError(number, os.strerror(number))
    return sets


def _holds_capabilities() -> bool:
    return any(each.effective or each.permitted or each.inheritable for each in _capability_sets(_LIBC.capget))


def _drop_capabilities() -> None:
    _capability_sets(_LIBC.capset)


def _drop_user(uid: int, gid: int) -> None:
    os.setgroups([])
    os.setresgid(gid, gid, gid)
    os.setresuid(uid, uid, uid)
    if os.getresuid() != (uid, uid, uid) or os.getresgid() != (gid, gid, gid):
        raise OSError(errno.EPERM, f"ids are {os.getresuid()}/{os.getresgid()} after the drop")


def confine(
    unprivileged_uid: int = UNPRIVILEGED_ID,
    unprivileged_gid: int = UNPRIVILEGED_ID,
    *,
    parent_death_signal: int = signal.SIGKILL,
) -> Confinement:
    """Confine the calling process for good; call it in a freshly forked child before it runs
    untrusted code (see the module docstring). `parent_death_signal` 0 leaves it unset."""
    if sys.platform != "linux":
        return Confinement((), (f"confinement: not available on {sys.platform}",))
    parent = os.getppid()
    layers: list[str] = []
    warnings: list[str] = []

    def attempt(layer: str, action: Callable[..., object], *arguments: object) -> bool:
        try:
            action(*arguments)
        except OSError as error:
            warnings.append(f"{layer}: refused: {error.strerror or error}")
            return False
        layers.append(layer)
        return True

    attempt(LAYER_NO_DUMP, make_undumpable)
    attempt(LAYER_NO_NEW_PRIVS, _prctl, _PR_SET_NO_NEW_PRIVS, 1)

    if 0 in os.getresuid():
        if attempt(LAYER_USER, _drop_user, unprivileged_uid, unprivileged_gid):
            # The kernel resets the dumpable flag when credentials change.
            if LAYER_NO_DUMP in layers:
                layers.remove(LAYER_NO_DUMP)
            attempt(LAYER_NO_DUMP, make_undumpable)
    else:
        warnings.append(f"{LAYER_USER}: skipped: not root (uid {os.getuid()}), ids kept")
    if _holds_capabilities():
        attempt(LAYER_NO_CAPABILITIES, _drop_capabilities)

    if parent_death_signal:
        if attempt(LAYER_PARENT_DEATH_SIGNAL, _prctl, _PR_SET_PDEATHSIG, parent_death_signal):
            if os.getppid() != parent:  # the parent died before the signal was armed
                os.kill(os.getpid(), parent_death_signal)

    compiled = compiled_filter(platform.machine())
    if compiled is None:
        warnings.append(f"{LAYER_SECCOMP}: unavailable on architecture {platform.machine()!r}")
    else:
        attempt(LAYER_SECCOMP, install_filter, compiled)
    return Confinement(tuple(layers), tuple(warnings))


def _highest_open_fd() -> int:
    try:
        return max(int(name) for name in os.listdir("/proc/self/fd"))
    except (OSError, ValueError):
        return os.sysconf("SC_OPEN_MAX") - 1


def close_inherited_fds(keep: Collection[int]) -> None:
    """Close every file descriptor of this process except those in `keep`.

    Closing 0, 1 or 2 leaves Python's `sys.stdin`/`stdout`/`stderr` pointing at nothing (their
    use raises OSError); keep them, or point them at /dev/null before calling `confine()`,
    which forbids opening it for writing afterwards."""
    kept = sorted(set(keep))
    if kept and kept[0] < 0:
        raise ValueError(f"negative file descriptor in keep: {kept[0]}")
    start = 0
    for fd in [*kept, _highest_open_fd() + 1]:
        # Never an empty range: CPython turns closerange(n, n) into close_range(n, -1), which
        # closes everything from n on.
        if start < fd:
            os.closerange(start, fd)
        start = max(start, fd + 1)


def _refuse(*args: object, **kwargs: object) -> None:
    raise PermissionError("not permitted in a sandbox process")


def _limit(kind: int, value: int) -> None:
    _, hard = resource.getrlimit(kind)
    value = value if hard == resource.RLIM_INFINITY else min(value, hard)
    resource.setrlimit(kind, (value, value))


def enter_sandbox(keep_fds: Collection[int], memory_mb: int, cpu_seconds: float) -> Confinement:
    """Confine the calling process (a fresh fork of a sandbox worker's main thread) before it
    runs a program: limits, descriptors, disarmed functions, then `confine()`."""
    _limit(resource.RLIMIT_AS, memory_mb * 1024 * 1024)
    # The soft limit sends SIGXCPU, which kills: the worker reports "cpu time".
    _limit(resource.RLIMIT_CPU, int(cpu_seconds) + 1)
    kept = {0, 1, 2, *keep_fds}
    close_inherited_fds(kept)
    # Per-user kernel counters (module docstring): a new descriptor only in a free number below
    # the highest kept one, and no signal queued on the child's account (a signal the kernel
    # sends, SIGXCPU or SIGKILL, is delivered all the same).
    _limit(resource.RLIMIT_NOFILE, max(kept) + 1)
    _limit(resource.RLIMIT_SIGPENDING, 0)
    for module_name, names in _DISARMED.items():
        module = sys.modules.get(module_name)
        for name in names:
            if module is not None and hasattr(module, name):
                setattr(module, name, _refuse)
    return confine()
