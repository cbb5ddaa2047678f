"""The OS layer in every mode a run meets (issue 24): as root and as an ordinary user, with
unprivileged user namespaces allowed and refused. A run without root has no user drop and,
where user namespaces are refused (Docker's default seccomp profile, RHEL's
`user.max_user_namespaces=0`), no namespace of its own either: the seccomp filter alone must
keep a confined child from the user's files and from the coordinator's, its worker's and
other workers' /proc entries.

Each test runs a script in a fresh interpreter in one of the four modes:
- the ordinary user is a throw-away `useradd` user; the script starts as root, in a mount
  namespace of its own where the interpreter's installation is reachable by that user (it may
  sit under root's 0700 home), and becomes the user for good before it does anything else;
- user namespaces are refused the way Docker refuses them: a seccomp filter on the script's
  process tree (inherited by the sandbox workers it starts) answers EPERM to `unshare` and
  `clone` with CLONE_NEWUSER and ENOSYS to `clone3`. The script checks the mode it is in.

The corpus of the red-team passes, written anew: isinstance rebinding, object-array byte
views and pointer arrays, unchecked keywords, forged step counts, pre-sent actions, cubic
extraction, ioctl metadata writes, /proc reads of the coordinator, the worker and the other
worker, and the resources the kernel counts per user (threads, POSIX timers, descriptors),
which a child shares with the coordinator and the other worker; each one runs beside a
well-behaved program on the other worker, which must score as it does alone. Programs that keep
state across episodes (their own, numpy's settings) score each episode as if it ran alone.
"""

from __future__ import annotations

import json
import os
import pwd
import shlex
import shutil
import subprocess
import sys
import textwrap
import uuid
from pathlib import Path

import pytest
from test_check_attacks import ATTACK
from test_episode_state import COUNTER, NUMPY_SETTINGS_COUNTER
from test_hostile import ESCAPED, FORGED_REPLIES, GOOD, NOTHING, policy_doing

API_KEY = "sk-coordinator-secret"
NETRC_PASSWORD = "hunter2-netrc-password"
NEW_USER_NAMESPACE = 0x10000000  # CLONE_NEWUSER

# Run first in every script, as root: enter the mode, then become the user (if one is asked).
ENTER_MODE = textwrap.dedent(
    """
    import ctypes, errno, json, os, platform, struct, sys

    libc = ctypes.CDLL(None, use_errno=True)
    mode = json.loads(os.environ.pop("COLMO_TEST_MODE"))

    def checked(result):
        if result < 0:
            number = ctypes.get_errno()
            raise OSError(number, os.strerror(number))
        return result

    if mode["refuse_user_namespaces"]:
        from colmo.sandbox.syscalls import SYSCALL_NUMBERS

        numbers = SYSCALL_NUMBERS[platform.machine()]
        allow, eperm, enosys = 0x7FFF0000, 0x00050000 | errno.EPERM, 0x00050000 | errno.ENOSYS
        program = [  # (code, jt, jf, k): load nr; clone3 -> ENOSYS; unshare, clone with NEWUSER -> EPERM
            (0x20, 0, 0, 0), (0x15, 0, 1, numbers["clone3"]), (0x06, 0, 0, enosys),
            (0x15, 1, 0, numbers["unshare"]), (0x15, 0, 3, numbers["clone"]),
            (0x20, 0, 0, 16), (0x45, 0, 1, 0x10000000), (0x06, 0, 0, eperm), (0x06, 0, 0, allow),
        ]
        instructions = ctypes.create_string_buffer(b"".join(struct.pack("HBBI", *i) for i in program))
        fprog = struct.pack("HxxxxxxQ", len(program), ctypes.addressof(instructions))
        checked(libc.prctl(38, 1, 0, 0, 0))  # PR_SET_NO_NEW_PRIVS
        checked(libc.prctl(22, 2, ctypes.c_char_p(fprog), 0, 0))  # PR_SET_SECCOMP, SECCOMP_MODE_FILTER
    if mode["uid"] is not None:
        os.setgroups([])
        os.setresgid(mode["gid"], mode["gid"], mode["gid"])
        os.setresuid(mode["uid"], mode["uid"], mode["uid"])
        checked(libc.prctl(4, 1, 0, 0, 0))  # PR_SET_DUMPABLE, as in a process the user started (the uid change cleared it)
    os.environ["HOME"] = mode["home"]

    def can_make_a_user_namespace():
        pid = os.fork()
        if pid == 0:
            os._exit(0 if libc.unshare(0x10000000) == 0 else 1)
        return os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1]) == 0

    USER_NAMESPACES = can_make_a_user_namespace()
    """
)

# One confined child, through colmo's own `enter_sandbox`, tries the user's and the
# coordinator's secrets directly.
CONFINED_CHILD = ENTER_MODE + textwrap.dedent(
    """
    from colmo.sandbox.confine import enter_sandbox

    os.environ["OPENAI_API_KEY"] = "%(api_key)s"
    netrc = os.path.join(os.environ["HOME"], ".netrc")
    with open(netrc, "w") as file:
        file.write("machine example.com password %(password)s")
    os.chmod(netrc, 0o600)
    try:  # where the file system keeps them: data a file holds besides its contents
        os.setxattr(netrc, "user.xdg.origin.url", b"https://example.com/?token=%(password)s")
    except OSError:
        pass
    coordinator = os.getpid()

    def where_it_works():
        os.chdir(f"/proc/{coordinator}/cwd")
        return os.getcwd()

    def outcome(action):
        try:
            action()
        except OSError as error:
            return errno.errorcode.get(error.errno, str(error.errno))
        return "ok"

    def read(path):  # not blocking: /proc/<pid>/fd/N of a pipe would reopen the pipe itself
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
        try:
            return os.read(fd, 64)
        finally:
            os.close(fd)

    def vm_read():
        buffer = ctypes.create_string_buffer(8)
        local = (ctypes.c_void_p * 2)(ctypes.addressof(buffer), 8)
        remote = (ctypes.c_void_p * 2)(id(os.environ), 8)
        checked(libc.process_vm_readv(coordinator, local, 1, remote, 1, 0))

    def start_a_thread():
        number = libc.pthread_create(ctypes.byref(ctypes.c_ulong()), None, libc.getpid, None)
        if number:
            raise OSError(number, os.strerror(number))

    def posix_timer():
        checked(libc.timer_create(1, None, ctypes.byref(ctypes.c_void_p())))  # CLOCK_MONOTONIC

    import mmap, resource
    from colmo.sandbox.syscalls import SYSCALL_NUMBERS

    numbers = SYSCALL_NUMBERS[platform.machine()]
    page = mmap.mmap(-1, mmap.PAGESIZE)

    def resident_pages():  # mincore: a side channel on what other processes read
        address = ctypes.addressof(ctypes.c_char.from_buffer(page))
        checked(libc.syscall(ctypes.c_long(numbers["mincore"]), ctypes.c_void_p(address), ctypes.c_size_t(mmap.PAGESIZE), ctypes.create_string_buffer(1)))

    def mount_table():  # listmount(req, buf, nr, flags): invalid arguments, EINVAL were it allowed
        checked(libc.syscall(ctypes.c_long(numbers["listmount"]), ctypes.c_long(0), ctypes.c_long(0), ctypes.c_long(0), ctypes.c_long(0)))

    read_fd, write_fd = os.pipe()
    pid = os.fork()
    if pid == 0:
        try:
            confinement = enter_sandbox((write_fd,), memory_mb=1024, cpu_seconds=10)
            report = {
                "layers": list(confinement.layers),
                "netrc": outcome(lambda: read(netrc)),
                "netrc's extended attributes": outcome(lambda: os.listxattr(netrc) + [os.getxattr(netrc, "user.xdg.origin.url")]),
                # The names of the coordinator's open files and of where it works (so of any
                # dumpable process of the same uid: the user's editor, shells).
                "coordinator cwd name": outcome(lambda: os.readlink(f"/proc/{coordinator}/cwd")),
                "coordinator fd name": outcome(lambda: os.readlink(f"/proc/{coordinator}/fd/{read_fd}")),
                "coordinator cwd by chdir": outcome(where_it_works),
                "coordinator environ": outcome(lambda: read(f"/proc/{coordinator}/environ")),
                "coordinator mem": outcome(lambda: read(f"/proc/{coordinator}/mem")),
                "coordinator fd": outcome(lambda: read(f"/proc/{coordinator}/fd/{read_fd}")),
                "process_vm_readv": outcome(vm_read),
                "unshare user namespace": outcome(lambda: checked(libc.unshare(0x10000000))),
                # What runs beside it (issue 33 finding 7):
                "coordinator's CPUs": outcome(lambda: os.sched_getaffinity(coordinator)),
                "coordinator's limits": outcome(lambda: resource.prlimit(coordinator, resource.RLIMIT_NOFILE)),
                "resident pages": outcome(resident_pages),
                "mount table": outcome(mount_table),
                # What the kernel counts per user, shared with the coordinator and its workers:
                "a thread": outcome(start_a_thread),
                "a POSIX timer": outcome(posix_timer),
                "64 pipes": outcome(lambda: [os.pipe() for _ in range(64)]),
            }
            os.write(write_fd, json.dumps(report).encode())
        except BaseException as error:
            os.write(write_fd, json.dumps({"child error": repr(error)}).encode())
        finally:
            os._exit(0)
    os.close(write_fd)
    chunks = []
    while chunk := os.read(read_fd, 65536):
        chunks.append(chunk)
    os.waitpid(pid, 0)
    report = json.loads(b"".join(chunks).decode())
    print(json.dumps({"uid": os.getuid(), "user namespaces": USER_NAMESPACES, **report}))
    """
) % {"api_key": API_KEY, "password": NETRC_PASSWORD}

# A coordinator with two sandbox workers evaluates the corpus (read from stdin), each case
# beside a well-behaved program on the other worker.
CORPUS_RUN = ENTER_MODE + textwrap.dedent(
    """
    from colmo.evaluation import EvalRequest
    from colmo.executor import LocalExecutor
    from colmo.intake import Unusable, read_program
    from colmo.rollout import episode_seeds
    from colmo.specs import load_spec

    corpus = json.load(sys.stdin)
    os.environ["OPENAI_API_KEY"] = "%(api_key)s"
    home = os.environ["HOME"]
    netrc = os.path.join(home, ".netrc")
    with open(netrc, "w") as file:
        file.write("machine example.com password %(password)s")
    os.chmod(netrc, 0o600)
    escaped_spec = os.path.join(home, "escaped.py")
    with open(escaped_spec, "w") as file:
        file.write(corpus["escaped spec"])
    pendulum = str(load_spec("pendulum.py").path)
    escaped_imports = ("numpy", "math", "os", "sys", "ctypes", "socket")

    def request(code, escaped=False, mode="fast", episodes=1, seeds=None, timeout_s=3):
        return EvalRequest(
            escaped_spec if escaped else pendulum, (), seeds or tuple(episode_seeds(0, episodes)), code, (),
            escaped_imports if escaped else ("numpy", "math"), mode=mode, timeout_s=timeout_s, memory_mb=512,
        )

    report = {"uid": os.getuid(), "user namespaces": USER_NAMESPACES, "cases": {}}
    try:  # in the coordinator: the policy before the repeated lines, read in linear time
        read = read_program(corpus["cubic extraction"], ("numpy", "math")).skeleton == read_program(corpus["good"], ("numpy", "math")).skeleton
        report["cubic extraction"] = "the policy read" if read else "another program read"
    except Unusable as error:
        report["cubic extraction"] = f"refused: {error}"
    executor = LocalExecutor(2, memory_mb=512, max_retries=0)
    try:
        good = request(corpus["good"])
        [baseline] = executor.evaluate([good])
        workers = executor.worker_pids()
        for name, case in corpus["cases"].items():
            code = case["code"].replace("{coordinator}", str(os.getpid())).replace("{workers}", str(workers)).replace("{netrc}", netrc)
            attack, beside = executor.evaluate([request(code, case["escaped"], case["mode"], case["episodes"]), good])
            report["cases"][name] = {
                "failure": attack.failure,
                "the program beside it unharmed": beside.failure is None and beside.returns == baseline.returns,
            }
        # A program that keeps state (its own, numpy's settings) across episodes: its returns in
        # one request, fast and through the referee, and with each episode a request of its own.
        report["stateful"] = {}
        seeds = tuple(episode_seeds(0, 4))
        for name, code in corpus["stateful"].items():
            runs = executor.evaluate([request(code, seeds=seeds, timeout_s=60), request(code, mode="referee", seeds=seeds, timeout_s=60)])
            runs += executor.evaluate([request(code, seeds=(seed,), timeout_s=60) for seed in seeds])
            report["stateful"][name] = {
                "failures": [run.failure for run in runs if run.failure],
                "returns": [list(runs[0].returns), list(runs[1].returns), [value for run in runs[2:] for value in run.returns]],
            }
        report["workers kept"] = executor.worker_pids() == workers
    finally:
        executor.close()
    print(json.dumps(report))
    """
) % {"api_key": API_KEY, "password": NETRC_PASSWORD}

REFUSED = "exception: PermissionError: [Errno 1] "  # EPERM: seccomp's answer, not the file's mode (EACCES)
PRESEND = (  # five episodes' zero actions, a thousand steps ahead; then it never reads
    "import os, ctypes\nfor fd in range(3, 64):\n    try:\n"
    "        os.write(fd, (b'A' + (40).to_bytes(4, 'little') + bytes(40)) * 1000)\n"
    "    except OSError:\n        pass\nctypes.CDLL(None).pause()\n"
)


def opens_nothing(paths: str) -> str:
    """An escaped policy that tries to open each of `paths` (a Python expression) and raises
    EPERM's PermissionError only if every open was refused with EPERM."""
    return policy_doing(
        f"for path in {paths}:\n"
        "        try:\n            os.close(os.open(path, os.O_RDONLY))\n"
        "        except PermissionError as error:\n            if error.errno != 1:\n                raise\n"
        "        else:\n            raise SystemExit('opened ' + path)\n"
        "    raise PermissionError(1, 'every open refused')",
        "import os, sys, ctypes, socket",
    )


def libc_call(call: str) -> str:
    """An escaped policy making one libc call; it exits with the call's errno if it fails."""
    return policy_doing(
        f"libc = ctypes.CDLL(None, use_errno=True)\n    buffer = ctypes.create_string_buffer(64)\n"
        f"    {call} == -1 and sys.exit(ctypes.get_errno())",
        "import os, sys, ctypes, socket",
    )


OTHER_WORKERS = "[w for w in {workers} if w != os.getppid()]"
VM_READ = (
    "libc.process_vm_readv({pid}, (ctypes.c_void_p * 2)(ctypes.addressof(buffer), 8), 1, "
    "(ctypes.c_void_p * 2)(4194304, 8), 1, 0)"
)
# name: (program, escaped spec, mode, episodes, the failure's prefix)
CORPUS = {
    "isinstance rebinding": (ATTACK.format(binding="isinstance = lambda a, b: b"), False, "fast", 1, "forbidden: .ndarray"),
    "object-array byte view": (policy_doing("a = np.array([None, obs])\n    b = a.data.cast('B')"), False, "fast", 1, "forbidden: "),
    "unchecked keyword": ("import numpy as np\ndef policy(obs):\n    return float(isinstance(obs, np.ndarray, key=np.load))", False, "fast", 1, "forbidden: "),
    "forged step count": (
        "import sys\nsys.modules['builtins'].setattr(sys.modules['colmo.evaluation'].Evaluation, 'to_bytes', "
        f"lambda self: {FORGED_REPLIES['10**400 control steps']!r}.encode())\n" + NOTHING, True, "fast", 1, "program: malformed reply: ",
    ),
    "pre-sent actions": (PRESEND + NOTHING, True, "referee", 5, "timeout: "),
    "a policy process that outlives the quit": (
        "import sys\nsys.modules['builtins'].setattr(sys.modules['os'], '_exit', lambda code: sys.modules['time'].sleep(600))\n" + NOTHING,
        True, "referee", 1, "tampering: the policy process outlived the referee's quit message",
    ),
    "bytes of an object array": (policy_doing("bytes(np.array([None, obs[0]]))"), False, "fast", 1, "exception: TypeError: bytes() of an array of objects is refused"),
    "whether ~/.netrc exists": (libc_call("libc.access('{netrc}'.encode(), 0)"), True, "fast", 1, "exception: SystemExit: 1"),  # EPERM, not ENOENT or 0
    "ioctl FS_IOC_SETFLAGS": (libc_call("libc.ioctl(0, 0x40086602, buffer)"), True, "fast", 1, "exception: SystemExit: 1"),
    "ioctl FS_IOC_SETVERSION": (libc_call("libc.ioctl(0, 0x40087602, buffer)"), True, "fast", 1, "exception: SystemExit: 1"),
    "~/.netrc with the real open": (policy_doing("data = sys.modules['builtins'].open('{netrc}').read()", "import os, sys"), True, "fast", 1, REFUSED),
    "~/.netrc read-only": (opens_nothing("['{netrc}']"), True, "fast", 1, REFUSED),
    "the coordinator's /proc": (opens_nothing("['/proc/{coordinator}/' + name for name in ('environ', 'mem', 'fd/0', 'fd/3')]"), True, "fast", 1, REFUSED),
    "the coordinator's memory": (libc_call(VM_READ.format(pid="{coordinator}")), True, "fast", 1, "exception: SystemExit: 1"),
    "its worker's /proc": (opens_nothing("['/proc/%d/%s' % (os.getppid(), name) for name in ('environ', 'mem', 'fd/0', 'fd/3', 'fd/4', 'fd/5')]"), True, "fast", 1, REFUSED),
    "the other worker's /proc": (
        opens_nothing(f"['/proc/%d/%s' % (w, name) for w in {OTHER_WORKERS} for name in ['environ', 'mem'] + ['fd/%d' % n for n in range(12)]]"),
        True, "fast", 1, REFUSED,
    ),
    "the other worker's memory": (
        libc_call(VM_READ.format(pid=f"{OTHER_WORKERS}[0]")), True, "fast", 1, "exception: SystemExit: 1",
    ),
    "the other worker's descriptors": (
        libc_call(f"libc.syscall(434, {OTHER_WORKERS}[0], 0)"), True, "fast", 1, "exception: SystemExit: 1",  # pidfd_open
    ),
    "a user namespace of its own": (libc_call(f"libc.unshare({NEW_USER_NAMESPACE})"), True, "fast", 1, "exception: SystemExit: 1"),
    "object-array pointer view": (policy_doing("a = np.array([None, obs])\n    b = np.frombuffer(a, np.uint64)"), False, "fast", 1, "forbidden: .frombuffer"),
    # Per-user resources (the coordinator's and the other worker's too, where nobody is shared
    # or there is no user drop): threads, POSIX timers, descriptors.
    "a hundred threads": (
        policy_doing("lock = sys.modules['_thread'].allocate_lock()\n    lock.acquire()\n"
                     "    for _ in range(100):\n        sys.modules['_thread'].start_new_thread(lock.acquire, ())", "import sys"),
        True, "fast", 1, "exception: RuntimeError: can't start new thread",
    ),
    "POSIX timers": (libc_call("libc.timer_create(1, None, buffer)"), True, "fast", 1, "exception: SystemExit: 38"),  # ENOSYS
    "a hundred pipes": (policy_doing("pipes = [os.pipe() for _ in range(100)]", "import os"), True, "fast", 1, "exception: OSError: [Errno 38] "),
}
# Programs whose returns would depend on the episodes run before them in the same process.
STATEFUL = {"counter": COUNTER, "numpy settings": NUMPY_SETTINGS_COUNTER}
CUBIC_EXTRACTION = GOOD + "@x\n" * 600  # a policy followed by 600 lines of `@x`: 2 kB

USERS = ("root", "ordinary user")
USER_NAMESPACE_MODES = ("user namespaces allowed", "user namespaces refused")


@pytest.fixture
def ordinary_user():
    if sys.platform != "linux" or os.geteuid() != 0:
        pytest.skip("needs root to create a throw-away user with useradd")
    if shutil.which("useradd") is None or shutil.which("userdel") is None:
        pytest.skip("useradd/userdel not installed")
    name = f"colmo{uuid.uuid4().hex[:8]}"
    created = subprocess.run(["useradd", "--create-home", name], capture_output=True, text=True)
    if created.returncode != 0:
        pytest.skip(f"useradd refused: {created.stderr.strip()}")
    try:
        yield pwd.getpwnam(name)
    finally:
        subprocess.run(["userdel", "--remove", name], capture_output=True)


def _closed_ancestor(path: Path) -> Path | None:
    """The outermost directory above `path` that other users cannot enter, if any."""
    for ancestor in reversed(path.parents):
        if ancestor != Path("/") and not ancestor.stat().st_mode & 0o001:
            return ancestor
    return None


def _reachable_interpreter(stash: Path) -> list[str]:
    """Shell commands, for a fresh mount namespace, that let any user reach the interpreter's
    installation: each closed directory above it is covered with an open tmpfs in which the
    installation is bind-mounted back where it was."""
    commands: list[str] = []
    covered: set[Path] = set()
    for index, prefix in enumerate(sorted({Path(sys.base_prefix).resolve(), Path(sys.prefix).resolve()})):
        closed = _closed_ancestor(prefix)
        if closed is None:
            continue
        kept = stash / str(index)
        kept.mkdir(parents=True)
        commands.append(f"mount --bind {shlex.quote(str(prefix))} {shlex.quote(str(kept))}")
        if closed not in covered:
            covered.add(closed)
            commands.append(f"mount -t tmpfs -o mode=755 tmpfs {shlex.quote(str(closed))}")
        commands += [f"mkdir -p {shlex.quote(str(prefix))}", f"mount --bind {shlex.quote(str(kept))} {shlex.quote(str(prefix))}"]
    return commands


MODES = [(user, namespaces) for user in USERS for namespaces in USER_NAMESPACE_MODES]
HARDEST_MODE = ("ordinary user", "user namespaces refused")  # no user drop, no namespace of its own


def in_every_mode(slow_but: tuple[str, str] | None = None) -> pytest.MarkDecorator:
    """Run a test in each mode (`run_in_mode`); all but `slow_but` marked slow if it is given."""
    marks = lambda mode: [pytest.mark.slow] if slow_but is not None and mode != slow_but else []  # noqa: E731
    modes = [pytest.param(mode, marks=marks(mode), id=", ".join(mode)) for mode in MODES]
    return pytest.mark.parametrize("run_in_mode", modes, indirect=True)


@pytest.fixture
def run_in_mode(request, tmp_path):
    """Run a script (one that starts with `ENTER_MODE`) in the mode of the parameter; its last
    line of output, as JSON. Skips where the mode cannot be made here."""
    user_kind, namespaces = request.param
    if sys.platform != "linux" or os.geteuid() != 0:
        pytest.skip("needs root: to set up an ordinary user, and to compare with a root run")
    refuse = namespaces == "user namespaces refused"
    command = [sys.executable, "-c"]
    if user_kind == "root":
        home = tmp_path / "home"
        home.mkdir()
        mode = {"uid": None, "gid": None, "home": str(home), "refuse_user_namespaces": refuse}
        prefix: list[str] = []
    else:
        if shutil.which("unshare") is None or shutil.which("mount") is None:
            pytest.skip("unshare/mount not installed (util-linux): the interpreter cannot be made reachable")
        user = request.getfixturevalue("ordinary_user")
        mode = {"uid": user.pw_uid, "gid": user.pw_gid, "home": user.pw_dir, "refuse_user_namespaces": refuse}
        setup = _reachable_interpreter(tmp_path / "stash")
        prefix = ["unshare", "--mount", "--propagation", "private", "sh", "-ec", " && ".join([*setup, 'exec "$@"']), "sh"]

    def run(script: str, stdin: str = "") -> dict:
        result = subprocess.run(
            [*prefix, *command, script], input=stdin, capture_output=True, text=True, timeout=600,
            env={**os.environ, "PYTHONPATH": os.getcwd(), "COLMO_TEST_MODE": json.dumps(mode)},
        )  # fmt: skip
        if result.returncode != 0 and "unshare failed" in result.stderr:
            pytest.skip(f"no mount namespace here: {result.stderr.strip().splitlines()[-1]}")
        assert result.returncode == 0, result.stderr
        report = json.loads(result.stdout.strip().splitlines()[-1])
        if not refuse and not report["user namespaces"]:
            pytest.skip("this kernel refuses unprivileged user namespaces: only the refused mode exists here")
        assert report["user namespaces"] is not refuse  # the mode is the one asked for
        assert report["uid"] == (0 if mode["uid"] is None else mode["uid"])
        return report

    return run


@in_every_mode()
def test_a_confined_child_reads_no_file_and_no_proc_entry_and_takes_no_per_user_resource(run_in_mode) -> None:
    """Per-user resources: a thread counts against the user's processes and takes a PID, a POSIX
    timer reserves a queued signal of the user's, a descriptor can hold pipe buffers and epoll
    watches of the user's; a child that took them all made the coordinator's forks, timers and
    pipes fail while it ran."""
    report = run_in_mode(CONFINED_CHILD)
    for field in ("uid", "user namespaces"):
        report.pop(field)
    assert "seccomp" in report.pop("layers")
    # Timers and new pipes are not on the filter's allowlist: refused before any limit binds.
    per_user = {"a thread": "EPERM", "a POSIX timer": "ENOSYS", "64 pipes": "ENOSYS"}
    assert report == {**dict.fromkeys(report, "EPERM"), **per_user}


@in_every_mode(slow_but=HARDEST_MODE)  # half a minute each; root's is also test_hostile's default mode
def test_the_corpus_is_refused_and_harms_no_program_beside_it(run_in_mode) -> None:
    corpus = {
        "escaped spec": ESCAPED, "good": GOOD, "cubic extraction": CUBIC_EXTRACTION,
        "cases": {name: dict(zip(("code", "escaped", "mode", "episodes"), case[:4])) for name, case in CORPUS.items()},
        "stateful": STATEFUL,
    }  # fmt: skip
    report = run_in_mode(CORPUS_RUN, json.dumps(corpus))
    assert report["workers kept"]  # no attack cost a worker, and none was retried
    assert report["cubic extraction"] == "the policy read"
    for name, (*_, expected) in CORPUS.items():
        outcome = report["cases"][name]
        assert outcome["failure"] is not None and outcome["failure"].startswith(expected), (name, outcome)
        assert API_KEY not in outcome["failure"] and NETRC_PASSWORD not in outcome["failure"], name
        assert outcome["the program beside it unharmed"], name
    for name, outcome in report["stateful"].items():  # issue 33 finding 4: its episodes cannot see each other
        assert not outcome["failures"], (name, outcome)
        together, refereed, apart = outcome["returns"]
        assert together == refereed == apart and len(together) == 4 and len(set(together)) > 1, (name, outcome)
