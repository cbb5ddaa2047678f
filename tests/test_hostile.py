"""Hostile programs, run end to end through the real sandbox.

For each: the program is marked failed with the right reason, the worker pool (or
`colmo.optimize`, or a search) goes on and scores a well-behaved program exactly as before,
nothing outside the sandbox's temporary directory changes, and no process is left behind.
One pool with one worker, a 3 s timeout and 512 MB of address space serves the module.
"""

from __future__ import annotations

import itertools
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest
from hydra import compose, initialize_config_module

import colmo.search
from colmo.config import register_schemas, to_objects
from colmo.generate import Generation, Generator, MutateGenerator
from colmo.sandbox import EvalRequest, WorkerPool
from colmo.spec import load_spec
from colmo.store import STORE_FILE, ProgramStore
from colmo.task import Evaluation, episode_seeds

from conftest import last_json_line

TIMEOUT_S = 3
MEMORY_MB = 512
SECRET = "sk-colmo-test-canary-0123456789"
PENDULUM = load_spec("pendulum.py").path
CANARY_TEXT = "the sandbox must not touch this file\n"

GOOD = """import numpy as np

def policy(obs):
    x1 = np.arctan2(-obs[1], obs[0])
    if np.abs(x1) > np.pi / 6.512:
        return np.sign(obs[2])
    return 9.437 * np.sin(x1) - 2.746 * obs[2]
"""
# Its score shows whether an earlier program changed the global random generator (which it
# draws from) or numpy's error state (it would raise on its floating-point warning).
NOISY = """import numpy as np

def policy(obs):
    noise = np.random.normal() * (np.log(0.0) < 0)
    x1 = np.arctan2(-obs[1], obs[0])
    if np.abs(x1) > np.pi / 6.512:
        return np.sign(obs[2]) + noise
    return 9.437 * np.sin(x1) - 2.746 * obs[2] + noise
"""


def live_processes(session: int) -> list[int]:
    """Processes of a session, zombies aside (in a container nobody may reap an orphan)."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rpartition(")")[2].split()
        except OSError:  # it exited while we looked
            continue
        if int(fields[3]) == session and fields[0] != "Z":
            found.append(int(stat.parent.name))
    return found


def processes_inside(directory: Path) -> list[int]:
    """Processes whose working directory lies under `directory` (sandbox workers have their
    pool's temporary directory as cwd)."""
    found = []
    for cwd in Path("/proc").glob("[0-9]*/cwd"):
        try:
            if Path(os.readlink(cwd)).is_relative_to(directory):
                found.append(int(cwd.parent.name))
        except OSError:
            continue
    return found


class Sandbox:
    """The module's pool, recording every worker it starts."""

    def __init__(self, pool: WorkerPool):
        self.pool = pool
        self.sessions: set[int] = set()
        start = pool._start_worker

        def start_and_record():
            worker = start()
            self.sessions.add(worker.process.pid)
            return worker

        pool._start_worker = start_and_record

    def evaluate(self, code: str, spec: Path = PENDULUM, episodes: int = 1) -> Evaluation:
        request = EvalRequest(str(spec), (), tuple(episode_seeds(0, episodes)), code, (), ("numpy", "math"))
        return self.pool.evaluate([request])[0]

    @property
    def worker_pid(self) -> int:
        return self.pool.workers[0].process.pid


@pytest.fixture(scope="module")
def canary(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("outside") / "canary.txt"
    path.write_text(CANARY_TEXT)
    return path


@pytest.fixture(scope="module")
def sandbox(canary):
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("OPENAI_API_KEY", SECRET)  # in the coordinator's environment while workers start
        sandbox = Sandbox(WorkerPool(1, timeout_s=TIMEOUT_S, memory_mb=MEMORY_MB))
        yield sandbox
        tmpdir = Path(sandbox.pool.tmpdir)
        assert not any(tmpdir.iterdir()), "a program wrote into the sandbox directory"
        sandbox.pool.close()
    assert not tmpdir.exists()
    assert all(not live_processes(session) for session in sandbox.sessions), "a process was left behind"
    assert canary.read_text() == CANARY_TEXT


@pytest.fixture(scope="module")
def baseline(sandbox) -> dict[str, Evaluation]:
    scores = {name: sandbox.evaluate(code) for name, code in (("good", GOOD), ("noisy", NOISY))}
    assert all(e.failure is None and e.score > 0 for e in scores.values()), scores
    return scores


def assert_unharmed(sandbox: Sandbox, baseline: dict[str, Evaluation]) -> None:
    """Well-behaved programs evaluated after a hostile one score exactly as before."""
    assert sandbox.evaluate(GOOD) == baseline["good"]
    assert sandbox.evaluate(NOISY) == baseline["noisy"]


def policy_doing(statement: str, imports: str = "import numpy as np") -> str:
    return f"{imports}\n\ndef policy(obs):\n    {statement}\n    return 0.0\n"


HOSTILE = {
    # name: (program, reason prefix); "{canary}" is the path of a file outside the sandbox.
    "infinite loop": (policy_doing("while True:\n        pass"), "timeout: "),
    "C-level loop at import": ("x = sum(range(10 ** 12))\n" + policy_doing("pass"), "timeout: "),
    "huge array": (policy_doing("np.ones(10 ** 11)"), "memory: Unable to allocate"),
    "growing list": ("import numpy as np\nchunks = []\n" + policy_doing("while True:\n        chunks.append(np.ones(10 ** 6))"), "memory: "),
    "huge string": (policy_doing("'x' * 10 ** 10"), "memory: "),
    "fork bomb": (policy_doing("while True:\n        os.fork()", "import os"), "forbidden: import os"),
    "multiprocessing": (policy_doing("multiprocessing.Process().start()", "import multiprocessing"), "forbidden: import multiprocessing"),
    "subprocess": (policy_doing("subprocess.run(['sh'])", "import subprocess"), "forbidden: import subprocess"),
    "write a file": (policy_doing("open('{canary}', 'w').write('pwned')"), "forbidden: open"),
    "numpy writes a file": (policy_doing("np.savetxt('{canary}', obs)"), "forbidden: .savetxt"),
    "array to a file": (policy_doing("obs.tofile('{canary}')"), "forbidden: .tofile"),
    "pickle to a file": (policy_doing("obs.dump('{canary}')"), "forbidden: .dump"),
    "delete a file": (policy_doing("os.remove('{canary}')", "import os"), "forbidden: import os"),
    "delete a tree": (policy_doing("shutil.rmtree('{canary}')", "import shutil"), "forbidden: import shutil"),
    "pathlib": (policy_doing("pathlib.Path('{canary}').unlink()", "import pathlib"), "forbidden: import pathlib"),
    "read a file": (policy_doing("open('{canary}').read()"), "forbidden: open"),
    "numpy reads a file": (policy_doing("np.loadtxt('{canary}')"), "forbidden: .loadtxt"),
    "numpy reads bytes": (policy_doing("np.fromfile('{canary}', dtype=np.uint8)"), "forbidden: .fromfile"),
    "socket": (policy_doing("socket.create_connection(('example.com', 80))", "import socket"), "forbidden: import socket"),
    "urllib": (policy_doing("urllib.request.urlopen('http://example.com')", "import urllib.request"), "forbidden: import urllib.request"),
    "sys.exit": (policy_doing("sys.exit(0)", "import sys"), "forbidden: import sys"),
    "os._exit": (policy_doing("os._exit(0)", "import os"), "forbidden: import os"),
    "exit()": (policy_doing("exit()"), "forbidden: exit"),
    "raise SystemExit": (policy_doing("raise SystemExit(0)"), "exception: SystemExit: 0"),
    "raise KeyboardInterrupt": (policy_doing("raise KeyboardInterrupt"), "exception: KeyboardInterrupt"),
    "escapes in the message": (policy_doing("raise ValueError('\\x1b[2J\\n' * 10 ** 6)"), "exception: ValueError:  [2J  [2J"),
    "deep recursion": ("def policy(obs):\n    return policy(obs)\n", "exception: RecursionError: maximum recursion depth exceeded"),
    "deeply nested source": ("x = " + "-" * 100_000 + "1\n" + policy_doing("pass"), "syntax error: "),
    "os.environ": (policy_doing("return float(len(os.environ['OPENAI_API_KEY']))", "import os"), "forbidden: import os"),
    "/proc/self/environ": (policy_doing("np.fromfile('/proc/self/environ', dtype=np.uint8)"), "forbidden: .fromfile"),
    "patch np.clip": (policy_doing("np.clip = lambda *args, **kwargs: 1.0"), "forbidden: assignment to np.clip"),
    "patch np.isfinite": (policy_doing("np.isfinite = lambda x: True"), "forbidden: assignment to np.isfinite"),
    "patch np.asarray": ("import numpy as np\nnp.asarray = lambda x, dtype=None: np.zeros(1)\n" + policy_doing("pass"), "forbidden: assignment to np.asarray"),
    "patch np.random.seed": (policy_doing("np.random.seed = print"), "forbidden: assignment to np.random.seed"),
    "patch through an alias": (policy_doing("m = np\n    m.isfinite = abs"), "forbidden: assignment to m.isfinite"),
    "patch math": (policy_doing("math.isfinite = abs", "import math"), "forbidden: assignment to math.isfinite"),
    "subclasses": (policy_doing("().__class__.__base__.__subclasses__()"), "forbidden: .__subclasses__"),
    "type()": (policy_doing("type(())"), "forbidden: type"),
    "[].__class__": (policy_doing("[].__class__"), "forbidden: .__class__"),
    "getattr with a built name": (policy_doing("getattr(obs, '__cl' + 'ass__')"), "forbidden: getattr"),
    "vars(np)": (policy_doing("vars(np)['isfinite']"), "forbidden: vars"),
    "np.__dict__": (policy_doing("np.__dict__['isfinite']"), "forbidden: .__dict__"),
    "str.format fields": (policy_doing("'{0.__class__.__base__}'.format(obs)"), "forbidden: .format"),
    "generator frame": (policy_doing("(x for x in obs).gi_frame.f_back.f_globals"), "forbidden: .f_globals"),
    "traceback frame": (policy_doing("try:\n        1 / 0\n    except Exception as e:\n        e.__traceback__.tb_frame"), "forbidden: .tb_frame"),
    "bound method owner": (policy_doing("print.__self__"), "forbidden: .__self__"),
    "array ctypes": (policy_doing("obs.ctypes.data"), "forbidden: .ctypes"),
}


@pytest.mark.parametrize("name", HOSTILE)
def test_hostile_program_fails_with_its_reason_and_the_pool_goes_on(sandbox, baseline, canary, name):
    code, expected = HOSTILE[name]
    evaluation = sandbox.evaluate(code.replace("{canary}", str(canary)))
    assert evaluation.failure is not None and evaluation.failure.startswith(expected), evaluation.failure
    assert evaluation.failure.isprintable() and len(evaluation.failure) <= 500
    assert evaluation.score == -np.inf
    assert_unharmed(sandbox, baseline)


def test_a_timeout_kills_the_worker_and_a_fresh_one_replaces_it(sandbox, baseline):
    sandbox.evaluate(GOOD)
    before = sandbox.worker_pid
    start = time.perf_counter()
    assert sandbox.evaluate(HOSTILE["infinite loop"][0]).failure.startswith("timeout: ")
    assert time.perf_counter() - start < TIMEOUT_S + 2
    assert not live_processes(before)
    assert_unharmed(sandbox, baseline)
    assert sandbox.worker_pid != before


@pytest.mark.parametrize("program", [
    # Every global a policy can reach that the evaluator or the next program also uses.
    "import numpy as np\nnp.seterr(all='raise')\nnp.set_printoptions(precision=1)\n" + policy_doing("np.random.seed(7)"),
    policy_doing("np.random.set_state(np.random.RandomState(1).get_state())"),
    # A suspended generator in a reference cycle: its `finally` runs whenever it is collected.
    "import numpy as np\ndef spoil():\n    try:\n        yield\n    finally:\n        np.random.seed(0)\n        np.seterr(all='raise')\n"
    "g = spoil()\nnext(g)\ncycle = [g]\ncycle.append(cycle)\n" + policy_doing("pass"),
])
def test_a_program_cannot_change_how_the_next_one_is_scored(sandbox, baseline, program):
    assert sandbox.evaluate(program).failure is None
    assert_unharmed(sandbox, baseline)


def test_clean_up_code_runs_within_the_programs_own_time_limit(sandbox, baseline):
    """A generator whose `finally` never ends times out its own evaluation, not the next one."""
    program = "def stall():\n    try:\n        yield\n    finally:\n        while True:\n            pass\ng = stall()\nnext(g)\n" + policy_doing("pass")
    assert sandbox.evaluate(program).failure.startswith("timeout: ")
    assert_unharmed(sandbox, baseline)


def test_a_program_cannot_carry_state_between_evaluations(sandbox):
    program = "import numpy as np\ncalls = [0]\ndef policy(obs):\n    calls[0] += 1\n    return np.sign(obs[2]) if calls[0] > 1500 else 0.0\n"
    first = sandbox.evaluate(program, episodes=2)
    assert first.failure is None and sandbox.evaluate(program, episodes=2) == first


def test_printing_megabytes_neither_breaks_nor_blocks_the_protocol(sandbox, baseline):
    program = GOOD.replace("def policy(obs):\n", "print('x' * 10 ** 8)\n\ndef policy(obs):\n    print(obs, 'y' * 10 ** 5)\n")
    assert sandbox.evaluate(program) == baseline["good"]


def test_the_worker_has_no_secrets_no_inherited_files_and_no_network(sandbox, baseline):
    sandbox.evaluate(GOOD)
    pid = sandbox.worker_pid
    assert os.environ["OPENAI_API_KEY"] == SECRET
    environ = Path(f"/proc/{pid}/environ").read_bytes().decode()
    assert SECRET not in environ and "OPENAI_API_KEY" not in environ
    descriptors = os.listdir(f"/proc/{pid}/fd")
    assert len(descriptors) == 4 and {"0", "1", "2"} <= set(descriptors)  # /dev/null three times, the socket
    if os.readlink(f"/proc/{pid}/ns/net") == os.readlink("/proc/self/ns/net"):
        pytest.skip("no network namespace here (needs root or user namespaces)")
    assert Path(f"/proc/{pid}/net/dev").read_text().count(":") == 1  # the loopback interface only


ESCAPE_SPEC = '''"""Pendulum, but building its environment leaves a process behind, as a program that had
escaped the sandbox could."""

import ctypes
import os
import subprocess
import time
import _posixsubprocess

from colmo.environments.pendulum import PendulumSwingup


def make_environment(**options):
    for function in (os.fork, os.system, os.posix_spawn, os.kill, os.setsid, _posixsubprocess.fork_exec):
        if function.__name__ != "_refuse":
            raise RuntimeError(f"os.{function.__name__} is not disarmed")
    try:
        subprocess.Popen(["true"])
    except PermissionError:
        pass
    else:
        raise RuntimeError("subprocess.Popen is not disarmed")
    pid = ctypes.CDLL(None).fork()  # libc's fork, past the disarmed functions
    if pid < 0:
        raise RuntimeError("fork refused")
    if pid == 0:
        while True:
            time.sleep(1)
    return PendulumSwingup(**options)


def policy(obs):
    return 0.0
'''


def test_an_escaped_process_dies_with_its_worker(sandbox, baseline, tmp_path):
    spec = tmp_path / "escape.py"
    spec.write_text(ESCAPE_SPEC)
    evaluation = sandbox.evaluate(policy_doing("pass"), spec=spec)
    if evaluation.failure and "fork refused" in evaluation.failure:
        assert os.geteuid() != 0  # RLIMIT_NPROC stopped it, which the kernel does not apply to root
        return
    assert evaluation.failure is None, evaluation.failure
    session = sandbox.worker_pid
    assert len(live_processes(session)) == 2  # the worker and what it left behind
    assert sandbox.evaluate(HOSTILE["infinite loop"][0], spec=spec).failure.startswith("timeout: ")
    assert not live_processes(session)
    assert_unharmed(sandbox, baseline)


def test_workers_die_with_their_coordinator(tmp_path):
    coordinator = subprocess.Popen(
        [sys.executable, "-c", (
            "from colmo.sandbox import EvalRequest, WorkerPool\n"
            "pool = WorkerPool(1)\n"
            f"pool.evaluate([EvalRequest({str(PENDULUM)!r}, (), (0,), 'def policy(obs):\\n    return 0.0\\n', (), ('numpy',))])\n"
            "print(pool.workers[0].process.pid, flush=True)\n"
            "input()\n"
        )],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
    )
    worker = int(coordinator.stdout.readline())
    assert live_processes(worker)
    coordinator.send_signal(signal.SIGKILL)
    coordinator.wait()
    deadline = time.monotonic() + 10
    while live_processes(worker) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not live_processes(worker)


# -- through `colmo.optimize` and a search ------------------------------------------------------

SANDBOX_OPTIONS = ("executor.workers=1", f"executor.timeout_s={TIMEOUT_S}", f"executor.memory_mb={MEMORY_MB}")


@pytest.mark.parametrize("name, exit_code, message", [
    ("infinite loop", 1, "colmo: the policy failed: timeout: "),
    ("huge array", 1, "colmo: the policy failed: memory: "),
    ("patch np.isfinite", 2, "colmo: error: no usable policy in "),
])
def test_optimize_reports_the_failure(tmp_path, canary, name, exit_code, message):
    code, reason = HOSTILE[name]
    policy_file = tmp_path / "policy.py"
    policy_file.write_text(code)
    tmp = tmp_path / "tmp"  # the sandbox's temporary directory is made in here
    tmp.mkdir()
    result = subprocess.run(
        [sys.executable, "-m", "colmo.optimize", f"policy_file={policy_file}", "task.episodes=1", "gfo.budget=3", *SANDBOX_OPTIONS],
        cwd=tmp_path, capture_output=True, text=True, timeout=120, env={**os.environ, "TMPDIR": str(tmp)},
    )
    assert result.returncode == exit_code, result.stderr
    assert message in result.stderr and reason in result.stderr
    if exit_code == 1:
        assert last_json_line(result.stdout)["failure"].startswith(reason)
    assert not any(tmp.iterdir()) and not processes_inside(tmp)
    assert canary.read_text() == CANARY_TEXT


SEARCH_HOSTILE = (
    "infinite loop", "huge array", "fork bomb", "write a file", "socket", "raise SystemExit", "deep recursion",
    "os.environ", "patch np.clip", "subclasses", "str.format fields", "generator frame",
)


class HostileGenerator(Generator):
    """Half of what it emits is a hostile program; the rest comes from the mutate generator."""

    def __init__(self, inner: Generator, seed: int, canary: Path):
        self.inner = inner
        self.rng = np.random.default_rng(seed)
        self.hostile = itertools.cycle(HOSTILE[name][0].replace("{canary}", str(canary)) for name in SEARCH_HOSTILE)

    def generate(self, prompt, n):
        return [
            Generation(next(self.hostile), "hostile") if self.rng.random() < 0.5 else generation
            for generation in self.inner.generate(prompt, n)
        ]


def test_a_search_flooded_with_hostile_programs_keeps_running_and_improving(tmp_path, canary, monkeypatch):
    monkeypatch.setattr(colmo.search, "make_generator", lambda cfg, seed, probe: HostileGenerator(MutateGenerator(cfg, seed, probe), seed, canary))
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))
    register_schemas()
    overrides = ["task.episodes=1", "search.max_samples=24", "llm.batch_size=4", "gfo.budget=8", "tracker=none", *SANDBOX_OPTIONS]
    with initialize_config_module(config_module="colmo.conf", version_base="1.3"):
        cfg = to_objects(compose(config_name="search", overrides=overrides))
    summary = colmo.search.Search(cfg, tmp_path / "run").run()

    assert summary["stop_reason"] == "max_samples" and summary["samples"] == 24
    records = list(ProgramStore(tmp_path / "run" / STORE_FILE).records())
    starter = next(r for r in records if r.sample == -1)
    assert summary["best_score"] > starter.score
    reasons = {HOSTILE[name][0].replace("{canary}", str(canary)): HOSTILE[name][1] for name in SEARCH_HOSTILE}
    hostile = [r for r in records if r.generator == "hostile" and r.status != "duplicate"]
    assert len(hostile) >= 6
    for record in hostile:
        assert record.status == "failed" and record.failure.startswith(reasons[record.raw]), (record.raw, record.failure)
    assert not any(tmp.iterdir()) and not processes_inside(tmp)
    assert canary.read_text() == CANARY_TEXT
