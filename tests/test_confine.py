"""Tests of the OS-level confinement layer (`confine`).

Every test that confines forks a child, which calls `confine()` and then runs hand-written,
trusted probes (never model-written code) that try what an escaped program would try; it
reports over a pipe, and the parent checks the report and the world outside the child.

`python test_confine.py` prints the cost of fork + confine + exit per evaluation.
"""

from __future__ import annotations

import ctypes
import errno
import fcntl
import json
import mmap
import os
import platform
import re
import resource
import select
import signal
import socket
import stat
import statistics
import struct
import subprocess
import sys
import tempfile
import threading
import time
import traceback
from collections.abc import Callable
from pathlib import Path

# Everything a child uses is imported here, before any fork: a confined child cannot import
# (numpy.fft and numpy.random are loaded lazily by numpy 2 otherwise).
import numpy as np
import numpy.fft
import numpy.linalg
import numpy.random
import pytest

from colmo.sandbox import seccomp, syscalls
from colmo.sandbox.confine import (
    LAYER_NO_CAPABILITIES,
    LAYER_NO_DUMP,
    LAYER_NO_NEW_PRIVS,
    LAYER_PARENT_DEATH_SIGNAL,
    LAYER_SECCOMP,
    LAYER_USER,
    close_inherited_fds,
    confine,
)

try:
    import mujoco
except ImportError:  # the numerics test says so
    mujoco = None

NOBODY = 65534
CHILD_DEADLINE_S = 120.0

SECCOMP_SUPPORTED = (
    sys.platform == "linux"
    and platform.machine() in ("x86_64", "aarch64")
    and "Seccomp:" in Path("/proc/self/status").read_text()
)
needs_seccomp = pytest.mark.skipif(not SECCOMP_SUPPORTED, reason="needs seccomp, x86_64/aarch64")
needs_root = pytest.mark.skipif(os.geteuid() != 0, reason="the user drop needs root")
needs_x86_64 = pytest.mark.skipif(platform.machine() != "x86_64", reason="x86_64 only")

LIBC = ctypes.CDLL(None, use_errno=True)
PTRACE_TRACEME = 0
PTRACE_ATTACH = 16

PENDULUM_XML = """
<mujoco>
  <option timestep="0.01"/>
  <worldbody>
    <body>
      <joint name="hinge" type="hinge" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0 0 -1" size="0.05" mass="1"/>
    </body>
  </worldbody>
  <actuator><motor joint="hinge"/></actuator>
</mujoco>
"""


# --- running probes in a forked child ---------------------------------------------------------


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view) :]


def _read_until_eof(fd: int, pid: int, deadline: float) -> bytes:
    chunks = []
    poller = select.poll()
    poller.register(fd, select.POLLIN)
    while True:
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            raise AssertionError("child did not answer before the deadline")
        if poller.poll(min(remaining, 1.0) * 1000):
            chunk = os.read(fd, 1 << 16)
            if not chunk:
                return b"".join(chunks)
            chunks.append(chunk)


def _reap(pid: int, deadline: float) -> int:
    while True:
        reaped, status = os.waitpid(pid, os.WNOHANG)
        if reaped:
            return status
        if time.monotonic() > deadline:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            raise AssertionError("child did not exit before the deadline")
        time.sleep(0.01)


def run_in_child(body: Callable[[int], dict]) -> dict:
    """Fork; the child runs `body(reply_fd)` and sends its JSON report down the reply pipe."""
    read_fd, write_fd = os.pipe()
    pid = os.fork()
    if pid == 0:
        status = 1
        try:
            os.close(read_fd)
            report = body(write_fd)
            status = 0
        except BaseException:
            report = {"child_error": traceback.format_exc()}
        try:
            _write_all(write_fd, json.dumps(report).encode())
        finally:
            os._exit(status)
    os.close(write_fd)
    deadline = time.monotonic() + CHILD_DEADLINE_S
    try:
        data = _read_until_eof(read_fd, pid, deadline)
    finally:
        os.close(read_fd)
    status = _reap(pid, deadline)
    assert data, f"child sent nothing (wait status {status})"
    report = json.loads(data)
    assert "child_error" not in report, report["child_error"]
    assert os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0, f"wait status {status}"
    return report


def confined(probe: Callable[[], dict]) -> Callable[[int], dict]:
    """A child body that confines itself, then runs `probe`."""

    def body(reply_fd: int) -> dict:
        open_own_status()
        confinement = confine()
        return {"layers": confinement.layers, "warnings": confinement.warnings, **probe()}

    return body


def outcome(action: Callable[[], object]) -> str:
    """'ok', or the errno name of the OSError that `action` raised."""
    try:
        action()
    except OSError as error:
        return errno.errorcode.get(error.errno, str(error.errno))
    return "ok"


def libc_outcome(result: int) -> str:
    return "ok" if result >= 0 else errno.errorcode[ctypes.get_errno()]


def probe_results(report: dict) -> dict:
    """The report without what `confined` adds."""
    return {name: value for name, value in report.items() if name not in ("layers", "warnings")}


_self_status: list[int] = []  # /proc/self/status, opened before confine(), which refuses open


def open_own_status() -> None:
    """Open /proc/self/status while the child still may, for `status_fields()` after confine()."""
    _self_status.append(os.open("/proc/self/status", os.O_RDONLY))


def status_fields(pid: int | str = "self") -> dict[str, list[str]]:
    if pid == "self" and _self_status:
        text = os.pread(_self_status[-1], 1 << 16, 0).decode()
    else:
        text = Path(f"/proc/{pid}/status").read_text()
    fields = {}
    for line in text.splitlines():
        key, _, value = line.partition(":")
        fields[key] = value.split()
    return fields


# --- the filter, checked on both architectures without a kernel --------------------------------


def run_filter(program: list[tuple[int, int, int, int]], arch: int, nr: int, args=(0,) * 6) -> int:
    """Interpret the classic-BPF instructions the filter uses on one struct seccomp_data."""
    data = struct.pack("<iIQ6Q", nr, arch, 0, *args)
    accumulator, pc = 0, 0
    while True:
        code, jump_true, jump_false, k = program[pc]
        if code == seccomp.BPF_LD_W_ABS:
            (accumulator,) = struct.unpack_from("<I", data, k)
            pc += 1
            continue
        if code == seccomp.BPF_RET_K:
            return k
        taken = {
            seccomp.BPF_JEQ_K: accumulator == k,
            seccomp.BPF_JGE_K: accumulator >= k,
        }[code]
        pc += 1 + (jump_true if taken else jump_false)


ALLOW = seccomp.SECCOMP_RET_ALLOW
KILL = seccomp.SECCOMP_RET_KILL_PROCESS
EPERM = seccomp.SECCOMP_RET_ERRNO | errno.EPERM
ENOSYS = seccomp.SECCOMP_RET_ERRNO | errno.ENOSYS
AUDIT_ARCH_I386 = 0x40000003
O_CLOEXEC, O_NONBLOCK, O_PATH = 0o2000000, 0o4000, 0o10000000
# Read-only (O_RDONLY is 0), O_PATH, then writing ones: all refused, the child opens nothing.
OPEN_FLAGS = [0, O_CLOEXEC, O_CLOEXEC | O_NONBLOCK, O_PATH, 0o1, 0o2, 0o100, 0o1000, 0o2000]
FS_IOC_SETFLAGS, FS_IOC_SETVERSION = 0x40086602, 0x40087602


@pytest.mark.parametrize("machine", ["x86_64", "aarch64"])
def test_filter_decisions(machine: str) -> None:
    program = seccomp.filter_program(machine)
    numbers = syscalls.SYSCALL_NUMBERS[machine]
    arch = syscalls.AUDIT_ARCH[machine]
    assert len(program) <= 4096
    jumps = (seccomp.BPF_JEQ_K, seccomp.BPF_JGE_K)
    for index, (code, jump_true, jump_false, _) in enumerate(program):
        if code in jumps:
            assert index + 1 + max(jump_true, jump_false) < len(program)

    def decide(name: str, *args: int) -> int:
        return run_filter(program, arch, numbers[name], args + (0,) * (6 - len(args)))

    assert run_filter(program, AUDIT_ARCH_I386, numbers["openat"]) == KILL
    for group in syscalls.ALLOWED.values():
        for name in group:
            if name in numbers:
                assert decide(name) == ALLOW, name
    for group in syscalls.DENIED.values():
        for name in group:
            if name in numbers:
                assert decide(name) == EPERM, name
    # Every number neither list names: ENOSYS (glibc then falls back, from openat2 to openat).
    named = {numbers[name] for name in (*syscalls.ALLOWED_NAMES, *syscalls.DENIED_NAMES, *seccomp.argument_checks()) if name in numbers}
    for number in sorted(set(range(600)) - named):
        assert run_filter(program, arch, number) == ENOSYS, number
    assert decide("openat2") == ENOSYS
    unlisted = {"x86_64": {"uname": 63, "pipe2": 293, "timer_create": 222, "sysinfo": 99}, "aarch64": {"uname": 160, "pipe2": 59}}
    for name, number in unlisted[machine].items():
        assert run_filter(program, arch, number) == ENOSYS, name

    at_fdcwd = 0xFFFFFF9C
    for flags in OPEN_FLAGS:
        assert decide("openat", at_fdcwd, 0, flags) == EPERM, oct(flags)
    for name in ("process_vm_readv", "process_vm_writev", "fadvise64", "sync", "syncfs",
                 "io_setup", "io_uring_setup", "cachestat"):  # fmt: skip
        assert decide(name) == EPERM, name

    pthread_flags = 0x3D0F00  # glibc pthread_create: VM|FS|FILES|SIGHAND|THREAD|SYSVSEM|SETTLS...
    for flags in (pthread_flags, signal.SIGCHLD, 0x4000 | 0x100 | signal.SIGCHLD, pthread_flags | 0x10000000):
        assert decide("clone", flags) == EPERM, hex(flags)  # a thread, fork, vfork, a user namespace
    assert decide("clone3") == EPERM

    assert decide("prlimit64", 0, 7, 0, 0x1000) == ALLOW  # getrlimit
    assert decide("prlimit64", 0, 7, 0x1000, 0) == EPERM
    assert decide("prlimit64", 0, 7, 1 << 32, 0) == EPERM
    assert decide("prlimit64", 1, 7, 0, 0x1000) == EPERM  # another process's limits
    assert decide("sched_getaffinity", 0, 128, 0x1000) == ALLOW  # its own CPUs (os.cpu_count's fallback)
    for pid in (1, 1 << 32):
        assert decide("sched_getaffinity", pid, 128, 0x1000) == EPERM
        assert decide("prlimit64", pid, 7, 0, 0x1000) == EPERM
    for name in ("listmount", "statmount", "file_getattr", "mincore"):
        assert decide(name) == EPERM, name
    assert decide("fcntl", 3, 3) == ALLOW  # F_GETFL
    assert decide("fcntl", 3, 1030) == ALLOW  # F_DUPFD_CLOEXEC
    assert decide("fcntl", 3, 6) == EPERM  # F_SETLK
    assert decide("fcntl", 3, 8) == EPERM  # F_SETOWN
    assert decide("fcntl", 3, 1031) == EPERM  # F_SETPIPE_SZ
    assert decide("ioctl", 0, 0x541B) == ALLOW  # FIONREAD
    assert decide("ioctl", 0, 0x5401) == ALLOW  # TCGETS, isatty
    for command in (0x5412, FS_IOC_SETFLAGS, FS_IOC_SETVERSION, 0x80086601, 0x8901):
        assert decide("ioctl", 0, command) == EPERM, hex(command)  # TIOCSTI, FS_IOC_*, FIOSETOWN

    if machine == "x86_64":
        assert run_filter(program, arch, 0x40000000 | numbers["openat"]) == KILL  # x32 ABI
        assert decide("open", 0, 0) == EPERM  # read-only too


def _header_numbers(path: Path) -> dict[str, int]:
    definitions = re.findall(r"#define __NR(?:3264)?_(\w+)\s+(\d+)", path.read_text())
    return {name: int(number) for name, number in definitions}


@pytest.mark.parametrize(
    ("machine", "header"),
    [
        ("x86_64", Path("/usr/include/x86_64-linux-gnu/asm/unistd_64.h")),
        ("aarch64", Path("/usr/include/asm-generic/unistd.h")),
    ],
)
def test_syscall_numbers_agree_with_kernel_headers(machine: str, header: Path) -> None:
    if not header.exists():
        pytest.skip(f"{header} not installed")
    known = _header_numbers(header)
    ours = syscalls.SYSCALL_NUMBERS[machine]
    compared = [name for name in ours if name in known]
    assert len(compared) > 100  # headers older than a call cannot check it
    assert {name: ours[name] for name in compared} == {name: known[name] for name in compared}


def test_every_named_syscall_is_numbered_somewhere() -> None:
    names = set(syscalls.ALLOWED_NAMES) | set(syscalls.DENIED_NAMES) | set(seccomp.argument_checks())
    numbered = {name for table in syscalls.SYSCALL_NUMBERS.values() for name in table}
    assert names - numbered == set()
    assert set(syscalls.ALLOWED_NAMES) <= set(syscalls.SYSCALL_NUMBERS["x86_64"])


def test_no_call_is_both_allowed_and_refused() -> None:
    checked = set(seccomp.argument_checks())
    assert not set(syscalls.ALLOWED_NAMES) & set(syscalls.DENIED_NAMES)
    assert not checked & (set(syscalls.ALLOWED_NAMES) | set(syscalls.DENIED_NAMES))


# --- the layers, in a real child ---------------------------------------------------------------


@needs_root
@needs_seccomp
def test_confine_reports_every_layer_and_the_kernel_state_matches() -> None:
    def probe() -> dict:
        fields = status_fields()
        return {
            "ids": [os.getresuid(), os.getresgid(), fields["Groups"]],  # getgroups is not on the allowlist
            "seccomp": fields["Seccomp"],
            "no_new_privs": fields["NoNewPrivs"],
            "capabilities": fields["CapEff"],
        }

    report = run_in_child(confined(probe))
    assert set(report["layers"]) == {
        LAYER_NO_DUMP, LAYER_NO_NEW_PRIVS, LAYER_USER, LAYER_PARENT_DEATH_SIGNAL, LAYER_SECCOMP,
    }  # fmt: skip
    assert report["warnings"] == []
    assert report["ids"] == [[NOBODY] * 3, [NOBODY] * 3, []]
    assert report["seccomp"] == ["2"]  # filter mode
    assert report["no_new_privs"] == ["1"]
    assert report["capabilities"] == ["0000000000000000"]


def drop_to_nobody() -> None:
    os.setgroups([])
    os.setresgid(NOBODY, NOBODY, NOBODY)
    os.setresuid(NOBODY, NOBODY, NOBODY)


def start_waiting_child(prepare: Callable[[], object]) -> tuple[int, int]:
    """Fork a child that runs `prepare`, says so, and lives until the returned fd is closed."""
    ready_read, ready_write = os.pipe()
    release_read, release_write = os.pipe()
    pid = os.fork()
    if pid == 0:
        try:
            os.close(ready_read)
            os.close(release_write)
            prepare()
            os.write(ready_write, b"r")
            os.read(release_read, 1)
        finally:
            os._exit(0)
    os.close(ready_write)
    os.close(release_read)
    ready = os.read(ready_read, 1)
    os.close(ready_read)
    assert ready == b"r"
    return pid, release_write


def read_proc(pid: int, name: str) -> bytes:
    with open(f"/proc/{pid}/{name}", "rb") as file:
        return file.read(1)


def dumpable_nobody() -> None:
    drop_to_nobody()
    LIBC.prctl(4, 1, 0, 0, 0)  # PR_SET_DUMPABLE: the kernel cleared it at the drop


@needs_root
def test_other_processes_of_the_same_uid_cannot_inspect_a_confined_child() -> None:
    confined_pid, release_confined = start_waiting_child(confine)
    control_pid, release_control = start_waiting_child(dumpable_nobody)
    try:

        def probe_as_a_sibling(reply_fd: int) -> dict:
            drop_to_nobody()  # same uid as the confined child, and no filter of its own
            return {
                "control environ": outcome(lambda: read_proc(control_pid, "environ")),
                "environ": outcome(lambda: read_proc(confined_pid, "environ")),
                "mem": outcome(lambda: read_proc(confined_pid, "mem")),
                "maps": outcome(lambda: read_proc(confined_pid, "maps")),
                "ptrace": libc_outcome(LIBC.ptrace(PTRACE_ATTACH, confined_pid, None, None)),
            }

        report = run_in_child(probe_as_a_sibling)
        assert report == {
            "control environ": "ok", "environ": "EACCES", "mem": "EACCES", "maps": "EACCES",
            "ptrace": "EPERM",
        }  # fmt: skip
        owner = os.stat(f"/proc/{confined_pid}/environ")
        assert (owner.st_uid, owner.st_gid) == (0, 0)
        assert status_fields(confined_pid)["Uid"] == [str(NOBODY)] * 4
    finally:
        os.close(release_confined)
        os.close(release_control)
        os.kill(confined_pid, signal.SIGCONT)  # had a ptrace attach succeeded, it would be stopped
        deadline = time.monotonic() + CHILD_DEADLINE_S
        assert _reap(confined_pid, deadline) == 0
        assert _reap(control_pid, deadline) == 0


@pytest.fixture
def world_writable_dir():
    """A directory anyone may write in, holding a file anyone may write: only the filter can
    stop the child, so every refusal must be EPERM (a permission problem would be EACCES)."""
    directory = Path(tempfile.mkdtemp(prefix="confine-"))
    directory.chmod(0o777)
    (directory / "existing.txt").write_text("original")
    (directory / "existing.txt").chmod(0o666)
    (directory / "empty_dir").mkdir()
    (directory / "empty_dir").chmod(0o777)
    yield directory
    for path in sorted(directory.rglob("*"), reverse=True):
        path.rmdir() if path.is_dir() and not path.is_symlink() else path.unlink()
    directory.rmdir()


def snapshot(directory: Path) -> dict[str, tuple]:
    entries = {}
    for path in sorted(directory.rglob("*")):
        info = path.lstat()
        content = path.read_bytes() if stat.S_ISREG(info.st_mode) else None
        entries[str(path.relative_to(directory))] = (
            info.st_mode, info.st_uid, info.st_gid, info.st_size, info.st_mtime_ns, content,
        )  # fmt: skip
    return entries


@needs_seccomp
def test_file_system_writes_are_refused_and_nothing_changes(world_writable_dir: Path) -> None:
    directory = world_writable_dir
    existing = directory / "existing.txt"
    before = snapshot(directory)
    before_listing = sorted(os.listdir(directory))
    machine = platform.machine()

    read_only_fd = os.open(existing, os.O_RDONLY)  # before the fork: the child opens nothing

    def probe() -> dict:
        new = directory / "new.txt"
        results = {
            "create": outcome(lambda: open(new, "w")),
            "create exclusive": outcome(lambda: os.open(new, os.O_CREAT | os.O_EXCL | os.O_RDONLY)),
            "write": outcome(lambda: open(existing, "r+")),
            "append": outcome(lambda: open(existing, "a")),
            "truncate on open": outcome(lambda: os.open(existing, os.O_RDONLY | os.O_TRUNC)),
            "tmpfile": outcome(lambda: os.open(directory, os.O_TMPFILE | os.O_WRONLY)),
            "truncate": outcome(lambda: os.truncate(existing, 0)),
            "ftruncate": outcome(lambda: os.ftruncate(read_only_fd, 0)),
            "rename": outcome(lambda: os.rename(existing, directory / "renamed.txt")),
            "replace": outcome(lambda: os.replace(existing, directory / "empty_dir" / "moved")),
            "unlink": outcome(lambda: os.unlink(existing)),
            "rmdir": outcome(lambda: os.rmdir(directory / "empty_dir")),
            "mkdir": outcome(lambda: os.mkdir(directory / "new_dir")),
            "hard link": outcome(lambda: os.link(existing, directory / "hard.txt")),
            "symlink": outcome(lambda: os.symlink(existing, directory / "soft.txt")),
            "chmod": outcome(lambda: os.chmod(existing, 0o777)),
            "chown": outcome(lambda: os.chown(existing, os.getuid(), os.getgid())),
            "utime": outcome(lambda: os.utime(existing, (0, 0))),
            "mkfifo": outcome(lambda: os.mkfifo(directory / "fifo")),
            "setxattr": outcome(lambda: os.setxattr(existing, "user.mark", b"1")),
            "read": outcome(lambda: open(existing).read()),
            "FS_IOC_SETFLAGS": outcome(lambda: fcntl.ioctl(read_only_fd, FS_IOC_SETFLAGS, b"\0" * 8)),
            "FS_IOC_SETVERSION": outcome(
                lambda: fcntl.ioctl(read_only_fd, FS_IOC_SETVERSION, b"\0" * 8)
            ),
            "fadvise": outcome(lambda: os.posix_fadvise(read_only_fd, 0, 0, os.POSIX_FADV_DONTNEED)),
            "sync": libc_outcome(LIBC.syscall(syscalls.SYSCALL_NUMBERS[machine]["sync"])),
            "content": os.pread(read_only_fd, 100, 0).decode(),
        }
        if machine == "x86_64":  # the legacy calls glibc no longer uses
            path = bytes(new)
            write_create = os.O_WRONLY | os.O_CREAT
            results["raw open(2)"] = libc_outcome(LIBC.syscall(2, path, write_create, 0o666))
            results["raw creat(2)"] = libc_outcome(LIBC.syscall(85, path, 0o666))
        return results

    report = probe_results(run_in_child(confined(probe)))
    os.close(read_only_fd)
    assert report.pop("content") == "original"
    assert report == dict.fromkeys(report, "EPERM")
    assert sorted(os.listdir(directory)) == before_listing
    assert snapshot(directory) == before


@needs_root
def test_root_only_files_and_the_parents_environment_are_unreadable() -> None:
    directory = Path(tempfile.mkdtemp(prefix="confine-"))
    try:
        directory.chmod(0o755)  # traversable, so only each file's own mode decides
        public, secret = directory / "public.txt", directory / "secret.txt"
        public.write_text("public")
        public.chmod(0o644)
        secret.write_text("API_KEY=secret")
        secret.chmod(0o600)
        parent = os.getpid()

        def probe() -> dict:
            return {
                "public": outcome(lambda: open(public).read()),
                "secret": outcome(lambda: open(secret).read()),
                "parent environ": outcome(lambda: read_proc(parent, "environ")),
                "parent memory": outcome(lambda: read_proc(parent, "mem")),
            }

        report = run_in_child(confined(probe))
        # Opening anything is refused by the filter, before the file's mode is even looked at.
        assert report["public"] == "EPERM"
        assert report["secret"] == "EPERM"
        assert report["parent environ"] == "EPERM"
        assert report["parent memory"] == "EPERM"
    finally:
        for path in directory.iterdir():
            path.unlink()
        directory.rmdir()


@needs_seccomp
def test_networking_is_refused() -> None:
    def probe() -> dict:
        return {
            "inet": outcome(lambda: socket.socket(socket.AF_INET, socket.SOCK_STREAM)),
            "inet6 udp": outcome(lambda: socket.socket(socket.AF_INET6, socket.SOCK_DGRAM)),
            "unix": outcome(lambda: socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)),
            "socketpair": outcome(lambda: socket.socketpair()),
        }

    report = probe_results(run_in_child(confined(probe)))
    assert report == dict.fromkeys(report, "EPERM")


@needs_seccomp
def test_which_paths_exist_is_unreadable(tmp_path: Path) -> None:
    """No stat, access, listing or working directory: a program cannot probe the user's files."""
    held = os.open(tmp_path, os.O_RDONLY | os.O_DIRECTORY)

    def probe() -> dict:
        return {
            "stat": outcome(lambda: os.stat("/etc/passwd")),
            "lstat": outcome(lambda: os.lstat(str(tmp_path))),
            "stat of a held descriptor's path": outcome(lambda: os.stat("x", dir_fd=held)),
            "access": libc_outcome(LIBC.access(b"/etc/passwd", os.R_OK)),  # os.access hides the errno
            "listdir of a held descriptor": outcome(lambda: os.listdir(held)),
            "getcwd": outcome(os.getcwd),
            "statvfs": outcome(lambda: os.statvfs("/")),
        }

    try:
        report = probe_results(run_in_child(confined(probe)))
    finally:
        os.close(held)
    assert report == dict.fromkeys(report, "EPERM")


@needs_seccomp
def test_what_other_processes_run_with_is_unreadable_and_its_own_is_not() -> None:
    """Issue 33 finding 7: another process's CPUs and limits, which pages are resident; the
    child's own CPUs and limits stay readable (glibc and numpy ask for them)."""
    page = mmap.mmap(-1, mmap.PAGESIZE)
    address = ctypes.addressof(ctypes.c_char.from_buffer(page))
    vector = ctypes.create_string_buffer(1)
    number = syscalls.SYSCALL_NUMBERS[platform.machine()]["mincore"]

    def probe() -> dict:
        return {
            "own affinity": outcome(lambda: os.sched_getaffinity(0)),
            "own limits": outcome(lambda: resource.getrlimit(resource.RLIMIT_NOFILE)),
            "parent's affinity": outcome(lambda: os.sched_getaffinity(os.getppid())),
            "parent's limits": outcome(lambda: resource.prlimit(os.getppid(), resource.RLIMIT_NOFILE)),
            "mincore": libc_outcome(LIBC.syscall(ctypes.c_long(number), ctypes.c_void_p(address), ctypes.c_size_t(mmap.PAGESIZE), vector)),
        }

    assert outcome(lambda: os.sched_getaffinity(os.getppid())) == "ok"  # unconfined, it can
    report = probe_results(run_in_child(confined(probe)))
    assert report == {"own affinity": "ok", "own limits": "ok", "parent's affinity": "EPERM", "parent's limits": "EPERM", "mincore": "EPERM"}


@needs_seccomp
def test_new_processes_and_threads_are_refused() -> None:
    def start_a_thread() -> None:
        try:
            threading.Thread(target=lambda: None).start()
        except RuntimeError:  # "can't start new thread": Python drops the errno
            raise PermissionError(errno.EPERM, "can't start new thread") from None

    def probe() -> dict:
        return {
            "fork": outcome(os.fork),
            "subprocess": outcome(lambda: subprocess.run(["/bin/true"], check=False)),
            "posix_spawn": outcome(lambda: os.posix_spawn("/bin/true", ["true"], {})),
            "execv": outcome(lambda: os.execv("/bin/true", ["true"])),
            "thread": outcome(start_a_thread),
            "pthread_create": errno.errorcode[LIBC.pthread_create(ctypes.byref(ctypes.c_ulong()), None, LIBC.getpid, None)],
        }

    report = probe_results(run_in_child(confined(probe)))
    # subprocess first makes its pipes: pipe2 is not on the allowlist.
    assert report == {**dict.fromkeys(report, "EPERM"), "subprocess": "ENOSYS"}


@needs_seccomp
def test_signals_to_other_processes_are_refused() -> None:
    received = []
    previous = signal.signal(signal.SIGTERM, lambda number, frame: received.append(number))
    victim = subprocess.Popen(["sleep", "300"], start_new_session=True)
    try:
        parent = os.getpid()

        def probe() -> dict:
            return {
                "kill parent": outcome(lambda: os.kill(parent, signal.SIGTERM)),
                "kill victim": outcome(lambda: os.kill(victim.pid, signal.SIGKILL)),
                "kill process group": outcome(lambda: os.killpg(victim.pid, signal.SIGKILL)),
                "pidfd_open": outcome(lambda: os.pidfd_open(victim.pid)),
                "setsid": outcome(os.setsid),
            }

        report = run_in_child(confined(probe))
        for name in ("kill parent", "kill victim", "kill process group", "pidfd_open", "setsid"):
            assert report[name] == "EPERM", name
        time.sleep(0.2)  # a signal, had one been sent, would have arrived by now
        assert received == []
        assert victim.poll() is None
    finally:
        signal.signal(signal.SIGTERM, previous)
        victim.kill()
        victim.wait()


@needs_seccomp
def test_ptrace_and_privilege_calls_are_refused() -> None:
    parent = os.getpid()

    def probe() -> dict:
        limit = (ctypes.c_ulong * 2)()
        return {
            "attach parent": libc_outcome(LIBC.ptrace(PTRACE_ATTACH, parent, None, None)),
            "traceme": libc_outcome(LIBC.ptrace(PTRACE_TRACEME, 0, None, None)),
            "setuid 0": outcome(lambda: os.setuid(0)),
            "dumpable back": libc_outcome(LIBC.prctl(4, 1, 0, 0, 0)),  # PR_SET_DUMPABLE
            "read cpu limit": libc_outcome(LIBC.getrlimit(resource.RLIMIT_CPU, limit)),
            # the same limit back: only the filter refuses (Python turns EPERM into ValueError)
            "set cpu limit": libc_outcome(LIBC.setrlimit(resource.RLIMIT_CPU, limit)),
        }

    report = run_in_child(confined(probe))
    for name in ("attach parent", "traceme", "setuid 0", "dumpable back", "set cpu limit"):
        assert report[name] == "EPERM", name
    assert report["read cpu limit"] == "ok"


# A process-creating call that the filter failed to refuse would fork the test itself.
SWEEP_EXCLUDED = {"fork", "vfork"}


@needs_seccomp
def test_every_denied_call_is_refused_by_the_running_kernel() -> None:
    # Invalid arguments (-1, then zeros), so that a call the filter missed fails harmlessly
    # with EINVAL, EBADF, EFAULT, ESRCH... instead of EPERM.
    numbers = syscalls.SYSCALL_NUMBERS[platform.machine()]
    denied = {
        name: numbers[name]
        for group in syscalls.DENIED.values()
        for name in group
        if name in numbers and name not in SWEEP_EXCLUDED
    }
    uname = {"x86_64": 63, "aarch64": 160}[platform.machine()]
    unlisted = {"openat2": numbers["openat2"], "uname": uname, "unnumbered": 471, "far": 571}

    def call(number: int) -> str:
        return libc_outcome(LIBC.syscall(ctypes.c_long(number), ctypes.c_long(-1), *[0] * 5))

    def probe() -> dict:
        return {
            "denied": {name: call(number) for name, number in denied.items()},
            "unlisted": {name: call(number) for name, number in unlisted.items()},
        }

    report = run_in_child(confined(probe))
    assert LAYER_SECCOMP in report["layers"]
    assert report["denied"] == dict.fromkeys(denied, "EPERM")
    assert report["unlisted"] == dict.fromkeys(unlisted, "ENOSYS")


def run_until_killed(action: Callable[[], object], *, confine_first: bool) -> int:
    """Fork a child that runs `action` and exits 0; return its wait status."""
    pid = os.fork()
    if pid == 0:
        try:
            if confine_first:
                confine()
            action()
        finally:
            os._exit(0)
    return _reap(pid, time.monotonic() + CHILD_DEADLINE_S)


def x32_getpid() -> None:
    LIBC.syscall(ctypes.c_long(0x40000000 | 39))  # getpid through the x32 ABI


def i386_getpid() -> None:
    """getpid through the 32-bit `int 0x80` entry: mov eax, 20; int 0x80; ret."""
    code = mmap.mmap(-1, mmap.PAGESIZE, prot=mmap.PROT_READ | mmap.PROT_WRITE | mmap.PROT_EXEC)
    code.write(b"\xb8\x14\x00\x00\x00\xcd\x80\xc3")
    address = ctypes.addressof(ctypes.c_char.from_buffer(code))
    ctypes.CFUNCTYPE(ctypes.c_int)(address)()


@needs_x86_64
@needs_seccomp
@pytest.mark.parametrize("foreign_call", [x32_getpid, i386_getpid])
def test_a_call_through_another_abi_kills_the_process(foreign_call) -> None:
    unconfined = run_until_killed(foreign_call, confine_first=False)
    if not (os.WIFEXITED(unconfined) and os.WEXITSTATUS(unconfined) == 0):
        pytest.skip(f"this kernel does not serve that ABI (wait status {unconfined})")
    status = run_until_killed(foreign_call, confine_first=True)
    assert os.WIFSIGNALED(status) and os.WTERMSIG(status) == signal.SIGSYS


def _numerics() -> dict:
    """The same computation in the parent and in the child: their results must agree."""
    generator = np.random.default_rng(7)
    # Sizes below OpenBLAS's threading thresholds: a confined child has no threads (this test's
    # BLAS has a thread per core), the sandbox worker's BLAS is single-threaded (test_hostile
    # evaluates a program with large ones there).
    matrix = generator.normal(size=(50, 50)) + 50 * np.eye(50)
    solution = np.linalg.solve(matrix, np.arange(50.0))
    product = generator.normal(size=(60, 60)) @ generator.normal(size=(60, 60))
    spectrum = np.fft.rfft(np.sin(np.linspace(0.0, 20.0, 1024)))
    legacy = np.random.RandomState(3).uniform(size=4)
    big = np.ones(50_000_000, dtype=np.uint8)  # 50 MB: mmap and munmap
    symmetric = matrix[:20, :20] + matrix[:20, :20].T
    return {
        "solution": solution[:5].tolist(),
        "product": float(product.trace()),
        "eigenvalues": np.linalg.eigvalsh(symmetric)[:3].tolist(),
        "spectrum": [abs(value) for value in spectrum[:5]],
        "legacy": legacy.tolist(),
        "big": int(big.sum()),
    }


def _pendulum(model, data) -> list[float]:
    for _ in range(200):
        data.ctrl[0] = 0.1
        mujoco.mj_step(model, data)
    return [float(data.qpos[0]), float(data.qvel[0])]


@needs_seccomp
def test_numpy_and_mujoco_still_work_after_confinement() -> None:
    if mujoco is None:
        pytest.skip("mujoco is not installed")
    model = mujoco.MjModel.from_xml_string(PENDULUM_XML)  # built before fork, as in the zygote
    parent_data, child_data = mujoco.MjData(model), mujoco.MjData(model)
    parent_data.qpos[0] = child_data.qpos[0] = 0.5

    def probe() -> dict:
        return {"numerics": _numerics(), "pendulum": _pendulum(model, child_data)}

    report = run_in_child(confined(probe))
    assert LAYER_SECCOMP in report["layers"]
    expected = _numerics()
    for name, value in expected.items():
        assert np.allclose(report["numerics"][name], value, rtol=1e-9, atol=0), name
    expected_pendulum = _pendulum(model, parent_data)
    assert report["pendulum"] == expected_pendulum
    assert expected_pendulum[0] != 0.5  # it moved


@needs_seccomp
def test_a_mujoco_warning_cannot_write_its_log_file(world_writable_dir: Path) -> None:
    # Unconfined, MuJoCo appends each warning to MUJOCO_LOG.TXT in the working directory.
    if mujoco is None:
        pytest.skip("mujoco is not installed")
    model = mujoco.MjModel.from_xml_string(PENDULUM_XML)
    data = mujoco.MjData(model)

    def probe() -> dict:
        data.ctrl[0] = np.inf
        mujoco.mj_step(model, data)
        return {"warnings": int(data.warning[mujoco.mjtWarning.mjWARN_BADCTRL].number)}

    def body(reply_fd: int) -> dict:
        os.chdir(world_writable_dir)  # before confinement, which refuses chdir
        return confined(probe)(reply_fd)

    report = run_in_child(body)
    assert report["warnings"] >= 1
    assert not (world_writable_dir / "MUJOCO_LOG.TXT").exists()


@needs_seccomp
def test_the_inherited_reply_pipe_takes_a_large_reply() -> None:
    report = run_in_child(confined(lambda: {"payload": "x" * 3_000_000}))  # >> a pipe's buffer
    assert report["payload"] == "x" * 3_000_000


@needs_seccomp
def test_the_capabilities_of_a_user_namespace_of_its_own_are_dropped() -> None:
    """A worker without root that made a user namespace of its own (as the sandbox worker does
    where the kernel lets it) holds every capability in it; its confined child holds none."""

    def body(reply_fd: int) -> dict:
        if os.geteuid() == 0:
            drop_to_nobody()  # an ordinary user's worker
        if LIBC.unshare(0x10000000) != 0:  # CLONE_NEWUSER
            return {"refused": errno.errorcode[ctypes.get_errno()]}
        open_own_status()
        held = status_fields()["CapEff"][0]
        confinement = confine()
        return {"held": held, "layers": confinement.layers, "held after": status_fields()["CapEff"][0]}

    report = run_in_child(body)
    if "refused" in report:
        pytest.skip(f"no user namespace here ({report['refused']})")
    assert int(report["held"], 16) != 0
    assert LAYER_NO_CAPABILITIES in report["layers"] and int(report["held after"], 16) == 0


@needs_seccomp
def test_without_root_the_user_drop_is_skipped_and_the_filter_applies(
    world_writable_dir: Path,
) -> None:
    def body(reply_fd: int) -> dict:
        if os.geteuid() == 0:  # simulate an unprivileged worker
            drop_to_nobody()
        uid = os.getuid()
        open_own_status()
        confinement = confine()
        return {
            "uid": uid,
            "layers": confinement.layers,
            "warnings": confinement.warnings,
            "ids after": os.getresuid(),
            "socket": outcome(socket.socket),
            "create": outcome(lambda: open(world_writable_dir / "new.txt", "w")),
            "seccomp": status_fields()["Seccomp"],
        }

    report = run_in_child(body)
    assert LAYER_USER not in report["layers"]
    others = {LAYER_NO_DUMP, LAYER_NO_NEW_PRIVS, LAYER_PARENT_DEATH_SIGNAL, LAYER_SECCOMP}
    assert others <= set(report["layers"])
    assert report["warnings"] == [f"user: skipped: not root (uid {report['uid']}), ids kept"]
    assert report["ids after"] == [report["uid"]] * 3
    assert report["socket"] == "EPERM"
    assert report["create"] == "EPERM"
    assert report["seccomp"] == ["2"]
    assert not (world_writable_dir / "new.txt").exists()


@pytest.mark.skipif(sys.platform != "linux", reason="Linux only")
def test_an_unsupported_architecture_loses_only_the_filter() -> None:
    def body(reply_fd: int) -> dict:
        platform.machine = lambda: "riscv64"  # this child only
        confinement = confine()
        layers, warnings = confinement.layers, confinement.warnings
        return {"layers": layers, "warnings": warnings, "socket": outcome(socket.socket)}

    report = run_in_child(body)
    assert LAYER_SECCOMP not in report["layers"]
    assert {LAYER_NO_DUMP, LAYER_NO_NEW_PRIVS, LAYER_PARENT_DEATH_SIGNAL} <= set(report["layers"])
    assert "seccomp: unavailable on architecture 'riscv64'" in report["warnings"]
    assert report["socket"] == "ok"


@pytest.mark.skipif(sys.platform != "linux", reason="reads /proc/self/fd")
def test_close_inherited_fds_keeps_only_what_is_asked() -> None:
    extra_read, extra_write = os.pipe()
    null = os.open(os.devnull, os.O_RDONLY)
    try:

        def body(reply_fd: int) -> dict:
            close_inherited_fds({reply_fd, extra_write})
            return {
                "reply": reply_fd,
                "open": sorted(int(name) for name in os.listdir("/proc/self/fd")),
                "null": outcome(lambda: os.fstat(null)),
                "stdout": outcome(lambda: os.fstat(1)),
            }

        report = run_in_child(body)
        # The listing shows the descriptor it reads the directory through, closed since.
        assert {report["reply"], extra_write} <= set(report["open"])
        assert len(set(report["open"]) - {report["reply"], extra_write}) == 1
        assert report["null"] == "EBADF"
        assert report["stdout"] == "EBADF"
    finally:
        for fd in (extra_read, extra_write, null):
            os.close(fd)


def test_close_inherited_fds_rejects_negative_descriptors() -> None:
    with pytest.raises(ValueError):
        close_inherited_fds({-1})


# --- cost ---------------------------------------------------------------------------------------


def round_trips(count: int, *, confined_child: bool) -> tuple[list[float], list[float]]:
    """Fork, (confine,) write to the reply pipe, exit; the parent reads and reaps. Returns the
    round-trip durations and, as timed inside each child, the durations of `confine()`."""
    round_trip_durations, confine_durations = [], []
    for _ in range(count):
        read_fd, write_fd = os.pipe()
        start = time.perf_counter()
        pid = os.fork()
        if pid == 0:
            try:
                confine_start = time.perf_counter()
                if confined_child:
                    confine()
                os.write(write_fd, struct.pack("d", time.perf_counter() - confine_start))
            finally:
                os._exit(0)
        os.close(write_fd)
        (confine_duration,) = struct.unpack("d", os.read(read_fd, 8))
        os.close(read_fd)
        _, status = os.waitpid(pid, 0)
        round_trip_durations.append(time.perf_counter() - start)
        confine_durations.append(confine_duration)
        assert status == 0
    return round_trip_durations, confine_durations


@needs_seccomp
def test_round_trip_works_repeatedly() -> None:
    round_trip_durations, _ = round_trips(10, confined_child=True)
    assert len(round_trip_durations) == 10


if __name__ == "__main__":
    count = 200
    for confined_child in (False, True):
        round_trip_durations, confine_durations = round_trips(count, confined_child=confined_child)
        label = "fork + confine + exit" if confined_child else "fork + exit (baseline)"
        print(
            f"{label}: round trip median {statistics.median(round_trip_durations) * 1e3:.2f} ms, "
            f"p90 {statistics.quantiles(round_trip_durations, n=10)[-1] * 1e3:.2f} ms; "
            f"confine() in the child median {statistics.median(confine_durations) * 1e3:.3f} ms "
            f"(over {count})"
        )
