"""The seccomp filter that `colmo.sandbox.confine` installs in a policy process: a classic-BPF
program written here by hand (no libseccomp), for x86_64 and aarch64 (little-endian); on any
other architecture `compiled_filter` returns None and the layer is reported unavailable.

The filter, installed with the seccomp() system call and SECCOMP_FILTER_FLAG_TSYNC so every
thread gets it (threads and children inherit it, and it cannot be removed):

* kills the process when the system call's architecture is not the native one (i386
  `int 0x80` or AArch32 calls on a 64-bit kernel, whose numbers mean other calls) and, on
  x86_64, for x32-ABI numbers (bit 0x40000000 set, or any number above it);
* allows the calls of `syscalls.ALLOWED` and nothing else: reading and writing descriptors the
  child already holds (`read`, `write`, their vector and positioned forms, `lseek`, `close`,
  `fstat`, `dup*`, `poll`/`select`), memory (`brk`, `mmap`, `munmap`, `mremap`, `mprotect`,
  `madvise`, `futex`), clocks and sleeps, signals to itself (`rt_sig*`, `sigaltstack`,
  `pause`, `restart_syscall`), its own ids, limits and CPU time, `getrandom`, `sched_yield`,
  `exit`, `exit_group`; and, with their arguments checked, `fcntl` (no locks, leases, owners or
  pipe sizes), `ioctl` (only TCGETS, FIONREAD, FIONBIO, FIOCLEX, FIONCLEX), `prlimit64` and
  `sched_getaffinity` (reading its own only);
* answers ENOSYS to every other call (as a kernel without it would: C libraries fall back),
  among them every call a future kernel adds, `openat2` (glibc falls back to `openat`), new
  descriptors (`pipe2`, `eventfd2`, `epoll_create1`, `timerfd_create`), timers
  (`timer_create`, `setitimer`, `alarm`), `uname`, `sysinfo`, `capget`, `landlock_*`;
* answers EPERM, so that the program sees an error and reports it, to the calls it names
  (`syscalls.DENIED`), all of which would do harm:

  - the file system, reads included: `open` and `openat` with any flags (the child runs on
    what the zygote opened and imported before the fork, so a program that reached the real
    `open` reads neither ~/.netrc nor /proc/<pid>/environ, mem or fd of a same-uid process),
    `posix_fadvise`, `cachestat`, `io_setup`; extended attributes, `getxattr`, `lgetxattr`,
    `fgetxattr`, `getxattrat`, `listxattr`, `llistxattr`, `flistxattr`, `listxattrat` (data a
    file holds besides its contents); the names behind links and working directories,
    `readlink`, `readlinkat`, `chdir`, `fchdir` (/proc/<pid>/fd/N and cwd of every dumpable
    process of the same uid name its open files and where it works); metadata: `stat`,
    `lstat`, `newfstatat`, `statx`, `access`, `faccessat`, `faccessat2`, `getdents`,
    `getdents64`, `getcwd`, `statfs`, `fstatfs` (which of the user's paths exist, whose they
    are, when they changed); and writes: `creat`, `sync`, `syncfs`,
    `truncate`, `ftruncate`, `fallocate`, `rename`, `renameat`, `renameat2`, `unlink`,
    `unlinkat`, `rmdir`, `mkdir`, `mkdirat`, `link`, `linkat`, `symlink`, `symlinkat`,
    `mknod`, `mknodat`, `chmod`, `fchmod`, `fchmodat`, `fchmodat2`, `chown`, `fchown`,
    `lchown`, `fchownat`, `utime`, `utimes`, `futimesat`, `utimensat`, `setxattr`,
    `lsetxattr`, `fsetxattr`, `setxattrat`, `removexattr`, `lremovexattr`, `fremovexattr`,
    `removexattrat`, `file_setattr`; and locks, which would let a child stall the
    coordinator's database while it lives: `flock`, `fcntl` F_SETLK, F_SETLKW, F_OFD_SETLK,
    F_OFD_SETLKW, F_SETLEASE, F_NOTIFY, F_SETPIPE_SZ; every `ioctl` but TCGETS (isatty),
    FIONREAD, FIONBIO, FIOCLEX, FIONCLEX (FS_IOC_SETFLAGS and FS_IOC_SETVERSION change inode
    attributes through a read-only descriptor);
  - networking, all of the socket API: `socket`, `socketpair`, `connect`, `bind`, `listen`,
    `accept`, `accept4`, `sendto`, `sendmsg`, `sendmmsg`, `recvfrom`, `recvmsg`, `recvmmsg`,
    `shutdown`, `getsockname`, `getpeername`, `setsockopt`, `getsockopt` (the reply goes
    down a pipe with write(); an inherited socket, if any, still takes read/write, but
    cannot pass descriptors);
  - new processes, threads and other processes: `clone` and `clone3` whatever their flags
    (a thread takes one of the system's PIDs and counts against the user's process limit,
    so thousands of them would make the user's other forks fail, the other workers' and the
    coordinator's, and they would spread one evaluation's CPU-time limit over every core),
    `execve`, `execveat`, `fork`, `vfork`, `ptrace`,
    `process_vm_readv`, `process_vm_writev`, `process_madvise`, `process_mrelease`, `kcmp`,
    `migrate_pages`, `move_pages`, `kill`, `tkill`, `tgkill`, `rt_sigqueueinfo`,
    `rt_tgsigqueueinfo`, `pidfd_open`, `pidfd_send_signal`, `pidfd_getfd`, `setpgid`,
    `setsid` (it stays in the group its supervisor kills), and signal delivery through
    descriptors: `fcntl` F_SETOWN, F_SETOWN_EX, F_SETSIG;
  - privileges: `setuid`, `setgid`, `setreuid`, `setregid`, `setresuid`, `setresgid`,
    `setfsuid`, `setfsgid`, `setgroups`, `capset`, `prctl` (all of it: PR_SET_DUMPABLE
    back to 1 would reopen /proc and ptrace), `seccomp` (no further filters),
    `personality`, `lsm_set_self_attr`;
  - metadata of the system that no policy needs: `listmount`, `statmount` (the mount table
    without /proc), `file_getattr` (a file's attributes by path), `mincore` (which pages of a
    mapping are resident: a side channel on what other processes read);
  - limits and scheduling, which would let a child undo the worker's rlimits (soft up to
    hard) or slow the other children of its uid: `setrlimit`, `prlimit64` with a new limit
    (reading its own limits stays allowed), `setpriority`, `sched_setparam`,
    `sched_setscheduler`, `sched_setattr`, `sched_setaffinity`, `ioprio_set`; and what they
    would read of another process (what runs beside the child): `prlimit64` and
    `sched_getaffinity` naming any process but itself (pid 0);
  - channels to other processes or to later evaluations: `memfd_create`, `memfd_secret`,
    `mq_open`, `mq_unlink`, `mq_timedsend`, `mq_timedreceive`, `mq_notify`,
    `mq_getsetattr`, `shmget`, `shmat`, `shmctl`, `shmdt`, `semget`, `semop`,
    `semtimedop`, `semctl`, `msgget`, `msgsnd`, `msgrcv`, `msgctl`, `keyctl`, `add_key`,
    `request_key` (the session keyring is shared with the parent), `inotify_init`,
    `inotify_init1`, `fanotify_init`;
  - kernel surfaces (exploit material, or root-only): `bpf`, `perf_event_open`,
    `userfaultfd`, `io_uring_setup`, `io_uring_enter`, `io_uring_register` (io_uring does
    file and network operations that seccomp never sees), `unshare`, `setns`, `mount`,
    `umount2`, `pivot_root`, `chroot`, `open_tree`, `open_tree_attr`, `move_mount`,
    `fsopen`, `fsconfig`, `fsmount`, `fspick`, `mount_setattr`, `name_to_handle_at`,
    `open_by_handle_at`, `init_module`, `finit_module`, `delete_module`, `kexec_load`,
    `kexec_file_load`, `reboot`, `swapon`, `swapoff`, `sethostname`, `setdomainname`,
    `syslog`, `acct`, `quotactl`, `quotactl_fd`, `settimeofday`, `clock_settime`,
    `adjtimex`, `clock_adjtime`, `vhangup`, `iopl`, `ioperm`, `modify_ldt`, `uselib`.

  Calls that exist on one architecture only (`open`, `creat`, `fork`, `vfork`, ... on
  x86_64) are in that architecture's filter only.

No threads: a numerical library that starts a thread pool in the child fails (OpenBLAS calls
exit(), which then hangs until the deadline), so the worker runs with one thread per library
(`OPENBLAS_NUM_THREADS=1`, ... in its environment). mmap/mprotect with PROT_EXEC stay allowed: a
program that reaches native code can already make any allowed call, so shellcode would gain
nothing, and refusing executable memory breaks libffi closures.
"""

from __future__ import annotations

import ctypes
import dataclasses
import errno
import functools
import os
import platform
import sys

from colmo.sandbox import syscalls

# prctl(2) options and seccomp(2) constants (include/uapi/linux/prctl.h, seccomp.h, filter.h).
_SECCOMP_SET_MODE_FILTER = 1
_SECCOMP_FILTER_FLAG_TSYNC = 1
SECCOMP_RET_KILL_PROCESS = 0x80000000
SECCOMP_RET_ERRNO = 0x00050000
SECCOMP_RET_ALLOW = 0x7FFF0000

# Classic BPF opcodes.
BPF_LD_W_ABS = 0x00 | 0x00 | 0x20
BPF_JEQ_K = 0x05 | 0x10 | 0x00
BPF_JGE_K = 0x05 | 0x30 | 0x00
BPF_RET_K = 0x06 | 0x00
_BPF_MAXINSNS = 4096
_BPF_MAX_JUMP = 255

# struct seccomp_data: int nr; u32 arch; u64 instruction_pointer; u64 args[6]. Both supported
# architectures are little-endian, so an argument's low word comes first.
_NR_OFFSET = 0
_ARCH_OFFSET = 4


def _arg_low(index: int) -> int:
    return 16 + 8 * index


def _arg_high(index: int) -> int:
    return 16 + 8 * index + 4


Instruction = tuple[int, int, int, int]  # (code, jt, jf, k), as in struct sock_filter


def _statement(code: int, k: int) -> Instruction:
    return (code, 0, 0, k)


def _jump(code: int, k: int, jump_true: int, jump_false: int) -> Instruction:
    return (code, jump_true, jump_false, k)


def _errno(number: int) -> int:
    return SECCOMP_RET_ERRNO | (number & 0xFFFF)


def _return_if_equal(values: list[int], action: int) -> list[Instruction]:
    """Compare the accumulator with each value; on a match return `action`, else fall through."""
    program: list[Instruction] = []
    chunk_size = _BPF_MAX_JUMP  # a jump offset is one byte
    for start in range(0, len(values), chunk_size):
        chunk = values[start : start + chunk_size]
        for position, value in enumerate(chunk):
            is_last = position == len(chunk) - 1
            program.append(_jump(BPF_JEQ_K, value, len(chunk) - 1 - position, 1 if is_last else 0))
        program.append(_statement(BPF_RET_K, action))
    return program


def _deny_commands(command_argument: int, commands: tuple[int, ...]) -> list[Instruction]:
    return [
        _statement(BPF_LD_W_ABS, _arg_low(command_argument)),
        *_return_if_equal(list(commands), _errno(errno.EPERM)),
        _statement(BPF_RET_K, SECCOMP_RET_ALLOW),
    ]


def _allow_commands(command_argument: int, commands: tuple[int, ...]) -> list[Instruction]:
    # The kernel reads an ioctl command as 32 bits, so the high word is irrelevant.
    return [
        _statement(BPF_LD_W_ABS, _arg_low(command_argument)),
        *_return_if_equal(list(commands), SECCOMP_RET_ALLOW),
        _statement(BPF_RET_K, _errno(errno.EPERM)),
    ]


def _only_own(pid_argument: int) -> list[Instruction]:
    """Refuse (EPERM) unless the call names the calling process itself (pid 0); falls through
    otherwise. Reading another process's affinity or limits tells what runs beside the child."""
    return [
        _statement(BPF_LD_W_ABS, _arg_low(pid_argument)),
        _jump(BPF_JEQ_K, 0, 0, 2),
        _statement(BPF_LD_W_ABS, _arg_high(pid_argument)),
        _jump(BPF_JEQ_K, 0, 1, 0),
        _statement(BPF_RET_K, _errno(errno.EPERM)),
    ]


def _deny_setting_limits() -> list[Instruction]:
    # prlimit64(pid, resource, new_limit, old_limit): reading its own (new_limit NULL) stays allowed.
    return [
        *_only_own(0),
        _statement(BPF_LD_W_ABS, _arg_low(2)),
        _jump(BPF_JEQ_K, 0, 0, 2),
        _statement(BPF_LD_W_ABS, _arg_high(2)),
        _jump(BPF_JEQ_K, 0, 1, 0),
        _statement(BPF_RET_K, _errno(errno.EPERM)),
        _statement(BPF_RET_K, SECCOMP_RET_ALLOW),
    ]


def argument_checks() -> dict[str, list[Instruction]]:
    return {
        "fcntl": _deny_commands(1, syscalls.DENIED_FCNTL_COMMANDS),
        "ioctl": _allow_commands(1, syscalls.ALLOWED_IOCTL_COMMANDS),
        "prlimit64": _deny_setting_limits(),
        "sched_getaffinity": [*_only_own(0), _statement(BPF_RET_K, SECCOMP_RET_ALLOW)],
    }


def filter_program(machine: str) -> list[Instruction]:
    """The seccomp filter for `machine` (an `os.uname().machine` value) as BPF instructions."""
    numbers = syscalls.SYSCALL_NUMBERS[machine]
    program = [
        _statement(BPF_LD_W_ABS, _ARCH_OFFSET),
        _jump(BPF_JEQ_K, syscalls.AUDIT_ARCH[machine], 1, 0),
        _statement(BPF_RET_K, SECCOMP_RET_KILL_PROCESS),
        _statement(BPF_LD_W_ABS, _NR_OFFSET),
    ]
    if machine == "x86_64":
        program += [
            _jump(BPF_JGE_K, syscalls.X32_SYSCALL_BIT, 0, 1),
            _statement(BPF_RET_K, SECCOMP_RET_KILL_PROCESS),
        ]
    allowed = [numbers[name] for name in syscalls.ALLOWED_NAMES if name in numbers]
    program += _return_if_equal(allowed, SECCOMP_RET_ALLOW)
    for name, check in argument_checks().items():
        if name in numbers:
            program.append(_jump(BPF_JEQ_K, numbers[name], 0, len(check)))
            program += check
    denied = [numbers[name] for name in syscalls.DENIED_NAMES if name in numbers]
    program += _return_if_equal(denied, _errno(errno.EPERM))
    program.append(_statement(BPF_RET_K, _errno(errno.ENOSYS)))
    assert len(program) <= _BPF_MAXINSNS
    return program


class _SockFilter(ctypes.Structure):
    _fields_ = [
        ("code", ctypes.c_uint16),
        ("jt", ctypes.c_uint8),
        ("jf", ctypes.c_uint8),
        ("k", ctypes.c_uint32),
    ]


class _SockFprog(ctypes.Structure):
    _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.POINTER(_SockFilter))]


@dataclasses.dataclass(frozen=True)
class CompiledFilter:
    instructions: ctypes.Array[_SockFilter]  # kept alive for as long as `program` points to it
    program: _SockFprog
    seccomp_syscall: int


@functools.cache
def compiled_filter(machine: str) -> CompiledFilter | None:
    if machine not in syscalls.SYSCALL_NUMBERS:
        return None
    instructions = filter_program(machine)
    array = (_SockFilter * len(instructions))(*(_SockFilter(*i) for i in instructions))
    program = _SockFprog(len(instructions), ctypes.cast(array, ctypes.POINTER(_SockFilter)))
    return CompiledFilter(array, program, syscalls.SYSCALL_NUMBERS[machine]["seccomp"])


_LIBC = ctypes.CDLL(None, use_errno=True)
if sys.platform == "linux":
    # Built in the zygote, before any fork, so a child pays nothing for it.
    compiled_filter(platform.machine())


def install_filter(compiled: CompiledFilter) -> None:
    result = _LIBC.syscall(
        ctypes.c_long(compiled.seccomp_syscall), ctypes.c_long(_SECCOMP_SET_MODE_FILTER),
        ctypes.c_long(_SECCOMP_FILTER_FLAG_TSYNC), ctypes.byref(compiled.program),
    )  # fmt: skip
    if result < 0:
        number = ctypes.get_errno()
        raise OSError(number, os.strerror(number))
    if result > 0:  # TSYNC names a thread it could not synchronise
        raise OSError(errno.EAGAIN, f"thread {result} could not take the filter")


