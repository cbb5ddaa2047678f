"""The system-call data of the seccomp filter (`colmo.sandbox.seccomp`): each supported
architecture's audit value and system-call numbers, the calls the filter allows (an allowlist:
what a confined child needs to compute and reply, grouped by why), the calls it refuses by name
(grouped by what they would let a program do), and the argument values it checks. Numbers come from the
kernel's syscall tables (x86_64: arch/x86/entry/syscalls/syscall_64.tbl; aarch64: the generic
table, include/uapi/asm-generic/unistd.h).
"""

from __future__ import annotations

AUDIT_ARCH = {"x86_64": 0xC000003E, "aarch64": 0xC00000B7}
X32_SYSCALL_BIT = 0x40000000

# Numbers ≥ 424 are shared by all architectures.
COMMON_NEW_SYSCALLS = {
    "pidfd_send_signal": 424, "io_uring_setup": 425, "io_uring_enter": 426,
    "io_uring_register": 427, "open_tree": 428, "move_mount": 429, "fsopen": 430,
    "fsconfig": 431, "fsmount": 432, "fspick": 433, "pidfd_open": 434, "clone3": 435,
    "openat2": 437, "pidfd_getfd": 438, "process_madvise": 440, "mount_setattr": 442,
    "quotactl_fd": 443, "memfd_secret": 447, "process_mrelease": 448, "fchmodat2": 452,
    "lsm_set_self_attr": 460, "setxattrat": 463, "getxattrat": 464, "listxattrat": 465,
    "removexattrat": 466, "open_tree_attr": 467,
    "cachestat": 451, "statmount": 457, "listmount": 458, "file_getattr": 468, "file_setattr": 469,
}  # fmt: skip

# Only the calls this filter names: arch/x86/entry/syscalls/syscall_64.tbl, scripts/syscall.tbl.
SYSCALL_NUMBERS: dict[str, dict[str, int]] = {
    "x86_64": {
        "open": 2, "ioctl": 16, "shmget": 29, "shmat": 30, "shmctl": 31, "socket": 41,
        "connect": 42, "accept": 43, "sendto": 44, "recvfrom": 45, "sendmsg": 46,
        "recvmsg": 47, "shutdown": 48, "bind": 49, "listen": 50, "getsockname": 51,
        "getpeername": 52, "socketpair": 53, "setsockopt": 54, "getsockopt": 55, "clone": 56,
        "fork": 57, "vfork": 58, "execve": 59, "kill": 62, "semget": 64, "semop": 65,
        "semctl": 66, "shmdt": 67, "msgget": 68, "msgsnd": 69, "msgrcv": 70, "msgctl": 71,
        "fcntl": 72, "flock": 73, "truncate": 76, "ftruncate": 77, "rename": 82, "mkdir": 83,
        "rmdir": 84, "creat": 85, "link": 86, "unlink": 87, "symlink": 88, "chmod": 90,
        "fchmod": 91, "chown": 92, "fchown": 93, "lchown": 94, "ptrace": 101, "syslog": 103,
        "setuid": 105, "setgid": 106, "setpgid": 109, "setsid": 112, "setreuid": 113,
        "setregid": 114, "setgroups": 116, "setresuid": 117, "setresgid": 119,
        "setfsuid": 122, "setfsgid": 123, "capset": 126, "rt_sigqueueinfo": 129,
        "utime": 132, "mknod": 133, "uselib": 134, "personality": 135, "setpriority": 141,
        "sched_setparam": 142, "sched_setscheduler": 144, "vhangup": 153, "modify_ldt": 154,
        "pivot_root": 155, "prctl": 157, "adjtimex": 159, "setrlimit": 160, "chroot": 161,
        "acct": 163, "settimeofday": 164, "mount": 165, "umount2": 166, "swapon": 167,
        "swapoff": 168, "reboot": 169, "sethostname": 170, "setdomainname": 171, "iopl": 172,
        "ioperm": 173, "init_module": 175, "delete_module": 176, "quotactl": 179,
        "setxattr": 188, "lsetxattr": 189, "fsetxattr": 190, "removexattr": 197,
        "lremovexattr": 198, "fremovexattr": 199, "tkill": 200, "sched_setaffinity": 203, "sched_getaffinity": 204,
        "semtimedop": 220, "clock_settime": 227, "tgkill": 234, "utimes": 235, "mq_open": 240,
        "mq_unlink": 241, "mq_timedsend": 242, "mq_timedreceive": 243, "mq_notify": 244,
        "mq_getsetattr": 245, "kexec_load": 246, "add_key": 248, "request_key": 249,
        "keyctl": 250, "ioprio_set": 251, "inotify_init": 253, "migrate_pages": 256,
        "openat": 257, "mkdirat": 258, "mknodat": 259, "fchownat": 260, "futimesat": 261,
        "unlinkat": 263, "renameat": 264, "linkat": 265, "symlinkat": 266, "fchmodat": 268,
        "unshare": 272, "move_pages": 279, "utimensat": 280, "fallocate": 285, "accept4": 288,
        "inotify_init1": 294, "rt_tgsigqueueinfo": 297, "perf_event_open": 298,
        "recvmmsg": 299, "fanotify_init": 300, "prlimit64": 302, "mincore": 27, "name_to_handle_at": 303,
        "open_by_handle_at": 304, "clock_adjtime": 305, "sendmmsg": 307, "setns": 308,
        "process_vm_readv": 310, "process_vm_writev": 311, "kcmp": 312, "finit_module": 313,
        "sched_setattr": 314, "renameat2": 316, "seccomp": 317, "memfd_create": 319,
        "kexec_file_load": 320, "bpf": 321, "execveat": 322, "userfaultfd": 323,
        "sync": 162, "syncfs": 306, "fadvise64": 221, "io_setup": 206, "chdir": 80, "fchdir": 81,
        "readlink": 89, "readlinkat": 267, "getxattr": 191, "lgetxattr": 192, "fgetxattr": 193,
        "listxattr": 194, "llistxattr": 195, "flistxattr": 196,
        # allowed
        "read": 0, "write": 1, "close": 3, "fstat": 5, "poll": 7, "lseek": 8, "mmap": 9,
        "mprotect": 10, "munmap": 11, "brk": 12, "rt_sigaction": 13, "rt_sigprocmask": 14,
        "rt_sigreturn": 15, "pread64": 17, "pwrite64": 18, "readv": 19, "writev": 20,
        "select": 23, "sched_yield": 24, "mremap": 25, "madvise": 28, "dup": 32, "dup2": 33,
        "pause": 34, "nanosleep": 35, "getpid": 39, "exit": 60, "gettimeofday": 96,
        "getrlimit": 97, "getrusage": 98, "times": 100, "getuid": 102, "getgid": 104,
        "geteuid": 107, "getegid": 108, "getppid": 110, "getresuid": 118, "getresgid": 120,
        "rt_sigpending": 127, "rt_sigtimedwait": 128, "rt_sigsuspend": 130, "sigaltstack": 131,
        "gettid": 186, "time": 201, "futex": 202, "restart_syscall": 219, "clock_gettime": 228,
        "clock_getres": 229, "clock_nanosleep": 230, "exit_group": 231, "pselect6": 270,
        "ppoll": 271, "dup3": 292, "getrandom": 318,
        # the file system's metadata, refused
        "stat": 4, "lstat": 6, "access": 21, "getdents": 78, "getcwd": 79, "statfs": 137,
        "fstatfs": 138, "getdents64": 217, "newfstatat": 262, "faccessat": 269, "statx": 332,
        "faccessat2": 439,
        **COMMON_NEW_SYSCALLS,
    },
    "aarch64": {
        "io_setup": 0, "sync": 81, "syncfs": 267, "fadvise64": 223, "chdir": 49, "fchdir": 50,
        "readlinkat": 78, "getxattr": 8, "lgetxattr": 9, "fgetxattr": 10, "listxattr": 11,
        "llistxattr": 12, "flistxattr": 13,
        "setxattr": 5, "lsetxattr": 6, "fsetxattr": 7, "removexattr": 14, "lremovexattr": 15,
        "fremovexattr": 16, "fcntl": 25, "inotify_init1": 26, "ioctl": 29, "ioprio_set": 30,
        "flock": 32, "mknodat": 33, "mkdirat": 34, "unlinkat": 35, "symlinkat": 36,
        "linkat": 37, "renameat": 38, "umount2": 39, "mount": 40, "pivot_root": 41,
        "truncate": 45, "ftruncate": 46, "fallocate": 47, "chroot": 51, "fchmod": 52,
        "fchmodat": 53, "fchownat": 54, "fchown": 55, "openat": 56, "vhangup": 58,
        "quotactl": 60, "utimensat": 88, "acct": 89, "capset": 91, "personality": 92,
        "unshare": 97, "kexec_load": 104, "init_module": 105, "delete_module": 106,
        "clock_settime": 112, "syslog": 116, "ptrace": 117, "sched_setparam": 118,
        "sched_setscheduler": 119, "sched_setaffinity": 122, "sched_getaffinity": 123, "kill": 129, "tkill": 130,
        "tgkill": 131, "rt_sigqueueinfo": 138, "setpriority": 140, "reboot": 142,
        "setregid": 143, "setgid": 144, "setreuid": 145, "setuid": 146, "setresuid": 147,
        "setresgid": 149, "setfsuid": 151, "setfsgid": 152, "setpgid": 154, "setsid": 157,
        "setgroups": 159, "sethostname": 161, "setdomainname": 162, "setrlimit": 164,
        "prctl": 167, "settimeofday": 170, "adjtimex": 171, "mq_open": 180, "mq_unlink": 181,
        "mq_timedsend": 182, "mq_timedreceive": 183, "mq_notify": 184, "mq_getsetattr": 185,
        "msgget": 186, "msgctl": 187, "msgrcv": 188, "msgsnd": 189, "semget": 190,
        "semctl": 191, "semtimedop": 192, "semop": 193, "shmget": 194, "shmctl": 195,
        "shmat": 196, "shmdt": 197, "socket": 198, "socketpair": 199, "bind": 200,
        "listen": 201, "accept": 202, "connect": 203, "getsockname": 204, "getpeername": 205,
        "sendto": 206, "recvfrom": 207, "setsockopt": 208, "getsockopt": 209, "shutdown": 210,
        "sendmsg": 211, "recvmsg": 212, "add_key": 217, "request_key": 218, "keyctl": 219,
        "clone": 220, "execve": 221, "swapon": 224, "swapoff": 225, "migrate_pages": 238,
        "move_pages": 239, "rt_tgsigqueueinfo": 240, "perf_event_open": 241, "accept4": 242,
        "recvmmsg": 243, "prlimit64": 261, "mincore": 232, "fanotify_init": 262, "name_to_handle_at": 264,
        "open_by_handle_at": 265, "clock_adjtime": 266, "setns": 268, "sendmmsg": 269,
        "process_vm_readv": 270, "process_vm_writev": 271, "kcmp": 272, "finit_module": 273,
        "sched_setattr": 274, "renameat2": 276, "seccomp": 277, "memfd_create": 279,
        "bpf": 280, "execveat": 281, "userfaultfd": 282, "kexec_file_load": 294,
        # allowed
        "dup": 23, "dup3": 24, "close": 57, "lseek": 62, "read": 63, "write": 64, "readv": 65,
        "writev": 66, "pread64": 67, "pwrite64": 68, "pselect6": 72, "ppoll": 73, "fstat": 80,
        "exit": 93, "exit_group": 94, "futex": 98, "nanosleep": 101, "clock_gettime": 113,
        "clock_getres": 114, "clock_nanosleep": 115, "sched_yield": 124, "restart_syscall": 128,
        "sigaltstack": 132, "rt_sigsuspend": 133, "rt_sigaction": 134, "rt_sigprocmask": 135,
        "rt_sigpending": 136, "rt_sigtimedwait": 137, "rt_sigreturn": 139, "getresuid": 148,
        "getresgid": 150, "times": 153, "getrlimit": 163, "getrusage": 165, "gettimeofday": 169,
        "getpid": 172, "getppid": 173, "getuid": 174, "geteuid": 175, "getgid": 176,
        "getegid": 177, "gettid": 178, "brk": 214, "munmap": 215, "mremap": 216, "mmap": 222,
        "mprotect": 226, "madvise": 233, "getrandom": 278,
        # the file system's metadata, refused
        "getcwd": 17, "statfs": 43, "fstatfs": 44, "faccessat": 48, "getdents64": 61,
        "newfstatat": 79, "statx": 291, "faccessat2": 439,
        **COMMON_NEW_SYSCALLS,
    },
}  # fmt: skip

# Allowed, and nothing else: what a confined child needs to run Python and numpy on memory it
# holds, and to write its reply down the pipe it kept. Found by tracing every call the children of
# the sandbox tests make after the filter (`strace -f` over tests/test_sandbox.py,
# test_episode_state.py, test_coverage.py, test_evaluation.py, test_hostile.py: brk, mmap,
# munmap, mprotect, madvise, futex, getrandom, getppid, read, write, clock_nanosleep, pause,
# exit_group), then completed with what the C library and the interpreter call on paths those
# tests do not take (a realloc's mremap, a signal's return, a retried sleep). Calls that exist on
# one architecture only (`poll`, `dup2`, `time`, ... on x86_64) are in that architecture's filter.
ALLOWED: dict[str, tuple[str, ...]] = {
    # The hot ones first: the filter compares them in this order.
    "descriptors it holds": (
        "read", "write", "readv", "writev", "pread64", "pwrite64", "lseek", "close", "fstat",
        "dup", "dup2", "dup3", "poll", "ppoll", "select", "pselect6",
    ),
    "memory": ("futex", "brk", "mmap", "munmap", "mremap", "mprotect", "madvise"),
    "time": ("clock_gettime", "clock_getres", "gettimeofday", "time", "nanosleep", "clock_nanosleep"),
    "signals to itself": (
        "rt_sigaction", "rt_sigprocmask", "rt_sigreturn", "sigaltstack", "rt_sigpending",
        "rt_sigsuspend", "rt_sigtimedwait", "pause", "restart_syscall",
    ),
    # What it is and what it used: its own ids, limits and CPU time, randomness (Python's hash
    # seed, numpy's default generator).
    "itself": (
        "getpid", "gettid", "getppid", "getuid", "geteuid", "getgid", "getegid", "getresuid",
        "getresgid", "getrlimit", "getrusage", "times", "getrandom", "sched_yield",
    ),
    "exit": ("exit", "exit_group"),
}  # fmt: skip

# Refused with EPERM, so that the program sees the refusal and reports it, grouped as in the
# module docstring. Every other call is refused with ENOSYS (as a kernel without it would).
DENIED: dict[str, tuple[str, ...]] = {
    "file system writes": (
        "creat", "truncate", "ftruncate", "fallocate", "rename", "renameat", "renameat2",
        "unlink", "unlinkat", "rmdir", "mkdir", "mkdirat", "link", "linkat", "symlink",
        "symlinkat", "mknod", "mknodat", "chmod", "fchmod", "fchmodat", "fchmodat2", "chown",
        "fchown", "lchown", "fchownat", "utime", "utimes", "futimesat", "utimensat",
        "setxattr", "lsetxattr", "fsetxattr", "setxattrat", "removexattr", "lremovexattr",
        "fremovexattr", "removexattrat", "file_setattr", "flock", "sync", "syncfs",
    ),
    # A confined child needs no file system after the fork: every file it reads was opened
    # (or imported) in the zygote before it, so opening anything, read-only included, is
    # refused (a program with the real `open` cannot read ~/.netrc nor /proc/<pid>/environ).
    # Nor what a file holds besides its contents (extended attributes: a browser keeps the
    # address a download came from in user.xdg.origin.url), nor the names behind links and
    # working directories: /proc/<pid>/fd/N, cwd and exe of every process of the same uid
    # that is dumpable (the coordinator, the user's editor and shells) name the files it has
    # open and where it works; chdir there and getcwd would too.
    "file system reads": (
        "open", "openat", "fadvise64", "cachestat", "io_setup", "getxattr", "lgetxattr",
        "fgetxattr", "getxattrat", "listxattr", "llistxattr", "flistxattr", "listxattrat",
        "readlink", "readlinkat", "chdir", "fchdir",
    ),
    # Which paths exist, who owns them, when they changed, what a directory lists, where the
    # process works: a program could probe the user's files and the coordinator's run directory.
    "file system metadata": (
        "stat", "lstat", "newfstatat", "statx", "access", "faccessat", "faccessat2", "getdents",
        "getdents64", "getcwd", "statfs", "fstatfs",
    ),
    "networking": (
        "socket", "socketpair", "connect", "bind", "listen", "accept", "accept4", "sendto",
        "sendmsg", "sendmmsg", "recvfrom", "recvmsg", "recvmmsg", "shutdown", "getsockname",
        "getpeername", "setsockopt", "getsockopt",
    ),
    # clone and clone3 with any flags, threads included: every thread counts against the
    # user's process limit and takes one of the system's PIDs (32768 by default), so a child
    # starting thousands would make every fork of the user fail (other workers' evaluations,
    # the coordinator), and threads would spread one evaluation's CPU-time limit over every
    # core. The worker's numerical libraries are single-threaded (its environment says so).
    "processes": (
        "clone", "clone3", "execve", "execveat", "fork", "vfork", "ptrace", "process_vm_readv",
        "process_vm_writev", "process_madvise", "process_mrelease", "kcmp", "migrate_pages",
        "move_pages", "kill", "tkill", "tgkill", "rt_sigqueueinfo", "rt_tgsigqueueinfo",
        "pidfd_open", "pidfd_send_signal", "pidfd_getfd", "setpgid", "setsid",
    ),
    "privileges": (
        "setuid", "setgid", "setreuid", "setregid", "setresuid", "setresgid", "setfsuid",
        "setfsgid", "setgroups", "capset", "prctl", "seccomp", "personality",
        "lsm_set_self_attr",
    ),
    # What the system and the page cache hold, which no policy needs: the mount table without
    # /proc (listmount, statmount), a file's attributes by path (file_getattr), and which pages
    # of a mapping are resident (mincore: a side channel on what other processes read).
    "metadata": ("listmount", "statmount", "file_getattr", "mincore"),
    "limits and scheduling": (
        "setrlimit", "setpriority", "sched_setparam", "sched_setscheduler", "sched_setattr",
        "sched_setaffinity", "ioprio_set",
    ),
    "channels": (
        "memfd_create", "memfd_secret", "mq_open", "mq_unlink", "mq_timedsend",
        "mq_timedreceive", "mq_notify", "mq_getsetattr", "shmget", "shmat", "shmctl", "shmdt",
        "semget", "semop", "semtimedop", "semctl", "msgget", "msgsnd", "msgrcv", "msgctl",
        "keyctl", "add_key", "request_key", "inotify_init", "inotify_init1", "fanotify_init",
    ),
    "kernel surfaces": (
        "bpf", "perf_event_open", "userfaultfd", "io_uring_setup", "io_uring_enter",
        "io_uring_register", "unshare", "setns", "mount", "umount2", "pivot_root", "chroot",
        "open_tree", "open_tree_attr", "move_mount", "fsopen", "fsconfig", "fsmount", "fspick",
        "mount_setattr", "name_to_handle_at", "open_by_handle_at", "init_module",
        "finit_module", "delete_module", "kexec_load", "kexec_file_load", "reboot", "swapon",
        "swapoff", "sethostname", "setdomainname", "syslog", "acct", "quotactl", "quotactl_fd",
        "settimeofday", "clock_settime", "adjtimex", "clock_adjtime", "vhangup", "iopl",
        "ioperm", "modify_ldt", "uselib",
    ),
}  # fmt: skip

ALLOWED_NAMES = tuple(name for group in ALLOWED.values() for name in group)
DENIED_NAMES = tuple(name for group in DENIED.values() for name in group)

DENIED_FCNTL_COMMANDS = (
    6,  # F_SETLK
    7,  # F_SETLKW
    8,  # F_SETOWN
    10,  # F_SETSIG
    15,  # F_SETOWN_EX
    37,  # F_OFD_SETLK
    38,  # F_OFD_SETLKW
    1024,  # F_SETLEASE
    1026,  # F_NOTIFY
    1031,  # F_SETPIPE_SZ: pins kernel memory, and resizes the reply pipe the worker reads
)
# Every other ioctl is refused (FS_IOC_SETFLAGS, FS_IOC_SETVERSION set inode attributes even
# through a read-only descriptor; TIOCSTI injects terminal input). These only ask: Python's
# io probes TCGETS on each stream it opens (isatty), and FIONREAD/FIONBIO/FIOCLEX are harmless
# on the descriptors the child holds.
ALLOWED_IOCTL_COMMANDS = (
    0x5401,  # TCGETS
    0x541B,  # FIONREAD
    0x5421,  # FIONBIO
    0x5451,  # FIOCLEX
    0x5450,  # FIONCLEX
)
