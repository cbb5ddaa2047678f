"""The OS layer as an ordinary user: a run without root has no user drop, so the seccomp
filter alone must keep a confined child from the user's files and from same-uid processes'
/proc entries (issue 24).

The test creates a throw-away user with `useradd`. Its interpreter cannot run as that user
from the start (the Python installation here may sit under root's 0700 home), so a root
process imports colmo first and then becomes the user for good (setgroups, setresgid,
setresuid): from there on it is an ordinary process of that uid, the "coordinator", and it
confines a forked child through colmo's own `enter_sandbox`.
"""

from __future__ import annotations

import json
import os
import pwd
import shutil
import subprocess
import sys
import textwrap
import uuid

import pytest

SCRIPT = textwrap.dedent(
    """
    import ctypes, errno, json, os, sys
    from colmo.sandbox.confine import enter_sandbox

    uid, gid, home = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
    os.setgroups([])
    os.setresgid(gid, gid, gid)
    os.setresuid(uid, uid, uid)
    os.environ["OPENAI_API_KEY"] = "sk-coordinator-secret"
    netrc = os.path.join(home, ".netrc")
    with open(netrc, "w") as file:
        file.write("machine example.com password hunter2")
    os.chmod(netrc, 0o600)
    coordinator = os.getpid()
    libc = ctypes.CDLL(None, use_errno=True)

    def outcome(action):
        try:
            action()
        except OSError as error:
            return errno.errorcode.get(error.errno, str(error.errno))
        return "ok"

    def read(path):
        with open(path, "rb") as file:
            return file.read(64)

    def checked(result):
        if result < 0:
            number = ctypes.get_errno()
            raise OSError(number, os.strerror(number))

    def vm_read():
        buffer = ctypes.create_string_buffer(8)
        local = (ctypes.c_void_p * 2)(ctypes.addressof(buffer), 8)
        remote = (ctypes.c_void_p * 2)(id(os.environ), 8)
        checked(libc.process_vm_readv(coordinator, local, 1, remote, 1, 0))

    read_fd, write_fd = os.pipe()
    pid = os.fork()
    if pid == 0:
        try:
            confinement = enter_sandbox((write_fd,), memory_mb=1024, cpu_seconds=10)
            report = {
                "uid": os.getuid(),
                "layers": list(confinement.layers),
                "netrc": outcome(lambda: read(netrc)),
                "coordinator environ": outcome(lambda: read(f"/proc/{coordinator}/environ")),
                "coordinator mem": outcome(lambda: read(f"/proc/{coordinator}/mem")),
                "coordinator fd": outcome(lambda: read(f"/proc/{coordinator}/fd/{read_fd}")),
                "process_vm_readv": outcome(vm_read),
                "unshare user namespace": outcome(lambda: checked(libc.unshare(0x10000000))),
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
    print(b"".join(chunks).decode())
    """
)


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


def test_an_ordinary_users_confined_child_reads_no_file_and_no_proc_entry(ordinary_user) -> None:
    user = ordinary_user
    result = subprocess.run(
        [sys.executable, "-c", SCRIPT, str(user.pw_uid), str(user.pw_gid), user.pw_dir],
        capture_output=True, text=True, timeout=120, env={**os.environ, "PYTHONPATH": os.getcwd()},
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout)
    assert report.pop("uid") == user.pw_uid
    assert "seccomp" in report.pop("layers")
    assert report == dict.fromkeys(report, "EPERM")
