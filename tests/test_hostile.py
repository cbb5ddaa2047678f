"""Hostile programs, run end to end through the real sandbox.

For each: the program is marked failed with the right reason, the executor goes on and scores
well-behaved programs exactly as before, its score is never above doing nothing, nothing
outside the sandbox changes, no secret leaks, and no process is left behind. One executor with
one worker, a 3 s limit per evaluation and 512 MB serves the module; the tests through
`colmo-optimize` and a search use the default limits (derived from the task).

`ESCAPED` is the test-only hook for the OS layer: a spec that lets its policies import `os`,
`sys`, `ctypes` and `socket`, which simulates a program that got past the Python level (as an
object-array exploit would): its system calls must be stopped by the kernel layers.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import math
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import children_of, compose, last_json_line, same_outcome, wait_for
from mlflow import MlflowClient

from colmo.evaluation import CANCELLED, FAST, REFEREE, EvalRequest, Evaluation
from colmo.executor import LocalExecutor
from colmo.generate import Generation, Generator
from colmo.generate.mutate import MutateGenerator
from colmo.intake import MAX_ANSWER_CHARS, Unusable, read_program
from colmo.optimize.tune import NONDETERMINISTIC, TAMPERING, judged
from colmo.rollout import episode_seeds
from colmo.search import Search
from colmo.specs import load_spec
from colmo.store import STORE_FILE, ProgramStore
from colmo.track.backend import open_experiment
from colmo.track.runs import MlflowTracker, TrackedRun

TIMEOUT_S = 3
# Filling the memory limit can take seconds on a loaded machine (the kernel finds and zeroes the
# pages): a program that must fail for its memory gets this long, so that it never times out first.
MEMORY_TIMEOUT_S = 20
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
NOTHING = "def policy(obs):\n    return 0.0\n"

ESCAPED = '''"""Pendulum, with policies that may import os, sys, ctypes and socket (a test-only hook:
what a program that escaped the Python-level checks could do)."""

from colmo.environments.pendulum import PendulumSwingup

ALLOWED_IMPORTS = ("os", "sys", "ctypes", "socket")


def make_environment(**options):
    return PendulumSwingup(**options)


def policy(obs):
    return 0.0
'''


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
    executor's temporary directory as cwd)."""
    found = []
    for cwd in Path("/proc").glob("[0-9]*/cwd"):
        try:
            if Path(os.readlink(cwd)).is_relative_to(directory):
                found.append(int(cwd.parent.name))
        except OSError:
            continue
    return found


class Sandbox:
    """The module's executor, recording every worker (session) it has run."""

    def __init__(self, executor: LocalExecutor):
        self.executor = executor
        self.sessions: set[int] = set()

    def evaluate(
        self, code: str, spec: Path = PENDULUM, episodes: int = 1, mode: str = FAST, imports=("numpy", "math"), timeout_s: float = TIMEOUT_S,
    ) -> Evaluation:
        request = EvalRequest(str(spec), (), tuple(episode_seeds(0, episodes)), code, (), imports, mode=mode, timeout_s=timeout_s, memory_mb=MEMORY_MB)
        [evaluation] = self.executor.evaluate([request])
        self.sessions.update(self.executor.worker_pids())
        return evaluation

    @property
    def worker_pid(self) -> int:
        return self.executor.worker_pids()[0]


@pytest.fixture(scope="module")
def canary(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("outside") / "canary.txt"
    path.write_text(CANARY_TEXT)
    return path


@pytest.fixture(scope="module")
def escaped_spec(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("spec") / "escaped.py"
    path.write_text(ESCAPED)
    return path


@pytest.fixture(scope="module")
def sandbox(canary, tmp_path_factory):
    temporary = tmp_path_factory.mktemp("tmp")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("OPENAI_API_KEY", SECRET)  # in the coordinator's environment while workers start
        patch.setattr(tempfile, "tempdir", str(temporary))  # where the workers' directories are made
        executor = LocalExecutor(1, memory_mb=MEMORY_MB, max_retries=0)
        sandbox = Sandbox(executor)
        yield sandbox
        executor.close()
    assert not any(temporary.iterdir()), "a worker's directory was left behind"
    assert all(not live_processes(session) for session in sandbox.sessions), "a process was left behind"
    assert canary.read_text() == CANARY_TEXT


@pytest.fixture(scope="module")
def baseline(sandbox) -> dict[str, Evaluation]:
    scores = {name: sandbox.evaluate(code) for name, code in (("good", GOOD), ("noisy", NOISY), ("nothing", NOTHING))}
    assert all(e.failure is None for e in scores.values()) and scores["good"].score > scores["nothing"].score, scores
    return scores


def assert_unharmed(sandbox: Sandbox, baseline: dict[str, Evaluation]) -> None:
    """Well-behaved programs evaluated after a hostile one score exactly as before."""
    assert same_outcome(sandbox.evaluate(GOOD), baseline["good"])
    assert same_outcome(sandbox.evaluate(NOISY), baseline["noisy"])


def policy_doing(statement: str, imports: str = "import numpy as np") -> str:
    return f"{imports}\n\ndef policy(obs):\n    {statement}\n    return 0.0\n"


HOSTILE = {
    # name: (program, reason prefix); "{canary}" is the path of a file outside the sandbox.
    "infinite loop": (policy_doing("while True:\n        pass"), "timeout: "),
    "C-level loop at import": ("x = sum(range(10 ** 12))\n" + policy_doing("pass"), "timeout: "),
    "C-level factorial": (policy_doing("math.factorial(int(1e8))", "import math"), "timeout: "),
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
    "array ctypes": (policy_doing("obs.ctypes.shape"), "forbidden: .ctypes"),
    # Raw memory: object arrays over buffers, in every form, and freeing a buffer under a view.
    "object array over a buffer": (policy_doing("a = np.ndarray(shape=(4,), dtype='O', buffer=bytearray(32))"), "forbidden: .ndarray"),
    "structured object dtype": (policy_doing("a = np.empty(1, dtype=[('a', 'O')])"), "forbidden: object dtype 'O'"),
    "subarray object dtype": (policy_doing("a = np.zeros(1, dtype=('O', (1,)))"), "forbidden: object dtype 'O'"),
    "buffer keyword": (policy_doing("a = np.zeros(1).view()\n    b = np.asarray(a, like=a)\n    c = np.recarray((1,), buf=a, formats='f8')"), "forbidden: .recarray"),
    "resize under a view": (policy_doing("a = np.zeros(10 ** 6)\n    v = a[:]\n    a.resize(1, refcheck=False)\n    v[:] = 1"), "forbidden: .resize"),
    # str() of its exception raises (too many digits to print): once the child crashed ("exited with code 70")
    # the bytes of an array of objects are their addresses (issue 33 finding 5)
    "bytes of an object array": (policy_doing("bytes(np.array([None, obs[0]]))"), "exception: TypeError: bytes() of an array of objects is refused"),
    "bytearray of an object array": (policy_doing("bytearray(np.array([None, 1.0]))"), "exception: TypeError: bytearray() of an array of objects is refused"),
    "unprintable exception": (policy_doing("raise ValueError(10 ** 5000)"), "exception: ValueError: (its message cannot be printed: ValueError) (step 0)"),
    "decorator rebinding": ("import numpy as np\n@(lambda f: np.poly1d)\ndef policy(obs):\n    pass\npolicy.x = 1\n", "forbidden: decorator on policy"),
}


@pytest.mark.parametrize("name", HOSTILE)
def test_hostile_program_fails_with_its_reason_and_the_sandbox_goes_on(sandbox, baseline, canary, name):
    code, expected = HOSTILE[name]
    timeout_s = MEMORY_TIMEOUT_S if expected.startswith("memory: ") else TIMEOUT_S
    evaluation = sandbox.evaluate(code.replace("{canary}", str(canary)), timeout_s=timeout_s)
    assert evaluation.failure is not None and evaluation.failure.startswith(expected), evaluation.failure
    assert evaluation.failure.isprintable() and len(evaluation.failure) <= 500
    assert SECRET not in evaluation.failure
    assert evaluation.score == -np.inf
    assert_unharmed(sandbox, baseline)


# What a program that escaped the Python level would try, run through the test-only hook spec:
# each attempt must be refused by the kernel, never reach its target, and leave a reason.
ESCAPES = {
    "write a file": "fd = os.open('{canary}', os.O_WRONLY | os.O_TRUNC)",
    "create a file": "fd = os.open('{outside}/new.txt', os.O_WRONLY | os.O_CREAT)",
    "rename a file": "os.rename('{canary}', '{canary}.moved')",
    "delete a file": "os.unlink('{canary}')",
    "read the coordinator's secrets": "data = os.read(os.open('/proc/{coordinator}/environ', os.O_RDONLY), 10 ** 6)",
    "read its worker's memory": "data = os.read(os.open('/proc/' + str(os.getppid()) + '/mem', os.O_RDONLY), 1)",
    "read its worker's pipes": "data = os.read(os.open('/proc/' + str(os.getppid()) + '/fd/0', os.O_RDONLY), 1)",
    # The canary stands for ~/.netrc: a file the user (and so the child) may read.
    "read a user's file with the real open": "data = sys.modules['builtins'].open('{canary}').read()",
    "read a user's file read-only": "data = os.read(os.open('{canary}', os.O_RDONLY), 100)",
    "signal the worker": "os.kill(os.getppid(), 9)",
    "signal the coordinator": "os.kill({coordinator}, 15)",
    "new process": "libc = ctypes.CDLL(None, use_errno=True)\n    libc.fork() == -1 and sys.exit(ctypes.get_errno())",
    "execute a program": "os.execv('/bin/sh', ['sh', '-c', 'touch {canary}'])",
    "open a socket": "socket.socket(socket.AF_INET, socket.SOCK_STREAM)",
    "leave its session": "os.setsid()",
    "become root again": "os.setuid(0)",
}


@pytest.mark.parametrize("name", ESCAPES)
def test_the_os_layer_stops_an_escaped_program(sandbox, baseline, canary, escaped_spec, name):
    statement = ESCAPES[name].format(canary=canary, outside=canary.parent, coordinator=os.getpid())
    code = policy_doing(statement, "import os, sys, ctypes, socket")
    evaluation = sandbox.evaluate(code, spec=escaped_spec, imports=("numpy", "math", "os", "sys", "ctypes", "socket"))
    assert evaluation.failure is not None, f"{name} was not stopped"
    assert evaluation.failure.startswith(("exception: PermissionError", "exception: SystemExit: 1", "exception: OSError")), evaluation.failure
    assert SECRET not in evaluation.failure
    assert canary.read_text() == CANARY_TEXT and sorted(p.name for p in canary.parent.iterdir()) == ["canary.txt"]
    assert_unharmed(sandbox, baseline)


def test_a_forged_score_is_caught_by_the_referee(sandbox, baseline, escaped_spec):
    """An escaped program replaces the evaluator in its own process: the fast path reports what
    it likes, the referee measures what its actions earn."""
    forge = (  # with the real builtins' setattr, as an object-array escape would find them
        "import sys\nR = sys.modules['colmo.rollout']\n"
        "sys.modules['builtins'].setattr(R.Episodes, 'evaluation', lambda self: R.Evaluation((1000.0,) * len(self.seeds), None, 1000 * len(self.seeds)))\n"
        + NOTHING
    )
    imports = ("numpy", "math", "os", "sys", "ctypes", "socket")
    fast = sandbox.evaluate(forge, spec=escaped_spec, imports=imports)
    refereed = sandbox.evaluate(forge, spec=escaped_spec, imports=imports, mode=REFEREE)
    assert fast.failure is None and fast.score == 1000.0  # the forgery, in its own process ...
    assert refereed.failure is None and refereed.score <= baseline["nothing"].score + 1e-9  # ... not with the referee
    assert_unharmed(sandbox, baseline)  # nor in the next process


@pytest.mark.parametrize("statement", ["raise ValueError('x' * 2_000_000)", "raise MemoryError('y' * 2_000_000)"])
def test_a_huge_failure_message_is_the_same_bounded_reason_with_the_referee(sandbox, baseline, statement):
    """A program chooses its exception's message: both modes store the same one-line reason,
    at most 500 characters (a 2 MB message must not break the referee's channel)."""
    fast, refereed = (sandbox.evaluate(policy_doing(statement), mode=mode) for mode in (FAST, REFEREE))
    assert fast.failure == refereed.failure and len(refereed.failure) == 500
    assert refereed.failure.startswith(("exception: ValueError: xxx", "memory: yyy"))
    assert_unharmed(sandbox, baseline)


def test_a_timeout_kills_the_evaluation_and_the_worker_goes_on(sandbox, baseline):
    sandbox.evaluate(GOOD)
    worker = sandbox.worker_pid
    assert sandbox.evaluate(HOSTILE["infinite loop"][0]).failure.startswith("timeout: ")
    assert sandbox.worker_pid == worker and not children_of(worker)  # the evaluation's process is gone
    assert_unharmed(sandbox, baseline)


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


def test_a_program_cannot_carry_state_between_evaluations(sandbox):
    program = "import numpy as np\ncalls = [0]\ndef policy(obs):\n    calls[0] += 1\n    return np.sign(obs[2]) if calls[0] > 1500 else 0.0\n"
    first = sandbox.evaluate(program, episodes=2)
    assert first.failure is None and same_outcome(sandbox.evaluate(program, episodes=2), first)


def test_large_linear_algebra_runs_without_threads(sandbox):
    """A confined child may start no thread: the worker's BLAS is single-threaded (its
    environment says so), else a product or a solve large enough for its thread pool would
    fail to start one and hang until the deadline."""
    program = (
        "import numpy as np\n\ndef policy(obs):\n    if not hasattr(policy, 'value'):\n"
        "        generator = np.random.default_rng(7)\n        product = generator.normal(size=(600, 600)) @ generator.normal(size=(600, 600))\n"
        "        solution = np.linalg.solve(generator.normal(size=(300, 300)) + 300 * np.eye(300), np.ones(300))\n"
        "        policy.value = float(np.tanh(product.trace() * 1e-9 + solution[0]))\n    return policy.value\n"
    )
    evaluation = sandbox.evaluate(program)
    assert evaluation.failure is None and evaluation.steps == 1000, evaluation.failure


def test_printing_megabytes_neither_breaks_nor_blocks_the_protocol(sandbox, baseline):
    program = GOOD.replace("def policy(obs):\n", "print('x' * 10 ** 8)\n\ndef policy(obs):\n    print(obs, 'y' * 10 ** 5)\n")
    assert same_outcome(sandbox.evaluate(program), baseline["good"])


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


def test_workers_die_with_their_coordinator():
    coordinator = subprocess.Popen(
        [sys.executable, "-c", (
            "from colmo.evaluation import EvalRequest\nfrom colmo.executor import LocalExecutor\n"
            "executor = LocalExecutor(1)\n"
            f"executor.evaluate([EvalRequest({str(PENDULUM)!r}, (), (0,), 'def policy(obs):\\n    return 0.0\\n', (), ('numpy',))])\n"
            "print(executor.worker_pids()[0], flush=True)\n"
            "input()\n"
        )],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
    )
    worker = int(coordinator.stdout.readline())
    assert live_processes(worker)
    coordinator.send_signal(signal.SIGKILL)
    coordinator.wait()
    wait_for(lambda: not live_processes(worker), what="the worker to die with its coordinator")


def test_a_huge_answer_is_refused_before_it_is_parsed():
    with pytest.raises(Unusable, match=f"more than the {MAX_ANSWER_CHARS} allowed"):
        read_program("def policy(obs):\n    return 0.0\n" + "#" * 10_000_000, ("numpy",))
    with pytest.raises(Unusable, match="nests brackets more than"):
        read_program("def policy(obs):\n    return " + "(" * 150 + "0" + ")" * 150 + "\n", ("numpy",))


# -- through `colmo-optimize` and a search, with default limits -----------------------------------


@pytest.mark.parametrize("name, exit_code, message", [
    ("infinite loop", 1, "colmo: the policy failed: timeout: "),
    ("C-level factorial", 1, "colmo: the policy failed: timeout: "),
    ("huge array", 1, "colmo: the policy failed: memory: "),
    ("patch np.isfinite", 2, "colmo: error: no usable policy in "),
])
def test_optimize_reports_the_failure_within_its_derived_time_limit(tmp_path, canary, name, exit_code, message):
    code, reason = HOSTILE[name]
    policy_file = tmp_path / "policy.py"
    policy_file.write_text(code)
    tmp = tmp_path / "tmp"  # the sandbox's temporary directory is made in here
    tmp.mkdir()
    start = time.monotonic()
    result = subprocess.run(
        [sys.executable, "-m", "colmo.optimize", f"policy_file={policy_file}", "task.episodes=1", "gfo.budget=3", "executor.workers=1"],
        cwd=tmp_path, capture_output=True, text=True, timeout=300, env={**os.environ, "TMPDIR": str(tmp), "OPENAI_API_KEY": SECRET},
    )
    assert result.returncode == exit_code, result.stderr
    assert message in result.stderr and reason in result.stderr and SECRET not in result.stdout + result.stderr
    if exit_code == 1:
        assert last_json_line(result.stdout)["failure"].startswith(reason)
        assert time.monotonic() - start < 120  # seconds, not the ten minutes a fixed limit once cost
    assert not any(tmp.iterdir()) and not processes_inside(tmp)
    assert canary.read_text() == CANARY_TEXT


SEARCH_HOSTILE = (
    "infinite loop", "huge array", "fork bomb", "write a file", "socket", "raise SystemExit", "deep recursion",
    "os.environ", "patch np.clip", "subclasses", "str.format fields", "generator frame", "object array over a buffer",
)


class HostileGenerator(Generator):
    """Half of what it emits is a hostile program; the rest comes from the mutate generator."""

    def __init__(self, inner: Generator, seed: int, canary: Path):
        super().__init__(inner.cfg, seed)
        self.inner = inner
        self.rng = np.random.default_rng(seed)
        self.hostile = itertools.cycle(HOSTILE[name][0].replace("{canary}", str(canary)) for name in SEARCH_HOSTILE)

    def generate(self, prompt, n):
        return [
            Generation(next(self.hostile), "hostile") if self.rng.random() < 0.5 else generation
            for generation in self.inner.generate(prompt, n)
        ]


def test_a_search_flooded_with_hostile_programs_keeps_running_and_improving(tmp_path, canary, monkeypatch):
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))
    cfg = compose("search", "task.episodes=1", "search.max_samples=24", "llm.batch_size=4", "gfo.budget=8", "tracker=none", "executor.workers=1", "heldout.episodes=2", "finish.render=false", "finish.simplify=false")
    generator = HostileGenerator(MutateGenerator(cfg.llm, cfg.seed), cfg.seed, canary)
    summary = Search(cfg, tmp_path / "run", generator=generator).run()

    assert summary.stop_reason == "max_samples" and summary.samples == 24
    records = list(ProgramStore(tmp_path / "run" / STORE_FILE).records())
    starter = next(r for r in records if r.sample == -1)
    assert summary.best_score > starter.score
    reasons = {HOSTILE[name][0].replace("{canary}", str(canary)): HOSTILE[name][1] for name in SEARCH_HOSTILE}
    hostile = [r for r in records if r.generator == "hostile" and r.status != "duplicate"]
    assert len(hostile) >= 6
    for record in hostile:
        assert record.status == "failed" and record.failure.startswith(reasons[record.raw]), (record.raw, record.failure)
    assert not any(tmp.iterdir()) and not processes_inside(tmp)
    assert canary.read_text() == CANARY_TEXT


# Replies an escaped program forges in place of its evaluation (`Evaluation.to_bytes` replaced
# in its own process, with the real builtins' setattr): the worker believes none of them.
FORGED_REPLIES = {
    "10**400 control steps": '{"returns": [1.0], "failure": null, "steps": 1' + "0" * 400 + ', "raced_out": false, "seconds": 0.0}',
    "a NaN return": '{"returns": [NaN], "failure": null, "steps": 1, "raced_out": false, "seconds": 0.0}',
    "a huge return": '{"returns": [1e300], "failure": null, "steps": 1, "raced_out": false, "seconds": 0.0}',
    "more returns than episodes": '{"returns": [' + ", ".join(["1.0"] * 1000) + '], "failure": null, "steps": 1, "raced_out": false, "seconds": 0.0}',
    "JSON nested 400,000 deep": "[" * 400_000,
    "no return for its episode": '{"returns": [], "failure": null, "steps": 1000, "raced_out": false, "seconds": 0.0}',
    "raced out of a request that does not race": '{"returns": [1.0], "failure": null, "steps": 1, "raced_out": true, "seconds": 0.0}',
    # A pendulum episode is 1000 steps of a reward in [0, 1].
    "more steps than the horizon": '{"returns": [1.0], "failure": null, "steps": 1001, "raced_out": false, "seconds": 0.0}',
    "more than the horizon's rewards": '{"returns": [1000.5], "failure": null, "steps": 1000, "raced_out": false, "seconds": 0.0}',
    "a trace that was not asked for": '{"returns": [1.0], "failure": null, "steps": 1000, "raced_out": false, "seconds": 0.0, "trace": {"x": [0]}}',
}


@pytest.mark.parametrize("name", FORGED_REPLIES)
def test_a_forged_reply_fails_the_program_not_the_worker(sandbox, baseline, escaped_spec, name):
    forge = (
        "import sys\nsys.modules['builtins'].setattr(sys.modules['colmo.evaluation'].Evaluation, 'to_bytes', "
        f"lambda self: {FORGED_REPLIES[name]!r}.encode())\n" + NOTHING
    )
    evaluation = sandbox.evaluate(forge, spec=escaped_spec, imports=("numpy", "math", "os", "sys", "ctypes", "socket"))
    assert evaluation.failure is not None and evaluation.failure.startswith("program: malformed reply: "), evaluation.failure
    assert evaluation.returns == () and evaluation.steps == 0
    assert_unharmed(sandbox, baseline)


def tuned_escaped(sandbox: Sandbox, escaped_spec: Path, code: str):
    """`optimize_program` on an escaped program (2 episodes, 3 evaluations of tuning), and
    the referee's evaluation of its own constants, measured apart."""
    from colmo.evaluation import Evaluator
    from colmo.optimize.tune import CandidateEvaluator, optimize_program
    from colmo.program import parametrize

    program = parametrize(code)  # not read_program: intake drops module-level statements, an escape would not
    evaluator = Evaluator.for_task(load_spec(escaped_spec), {}, episode_seeds(0, 2), MEMORY_MB, TIMEOUT_S)
    gfo = compose("optimize", "gfo=oneplusone", "gfo.budget=3", "policy_file=unused.py").gfo
    evaluate = CandidateEvaluator(sandbox.executor, evaluator, program.skeleton)
    return optimize_program(program, evaluate, gfo, seed=0), evaluate.referee(program.values)


# A failure that claims to be the executor's cancellation (which stops a search's finish: the
# held-out scores of the other best programs, the simplification, the video), in either mode.
CLAIMS_CANCELLED = {
    "fast": (
        "import sys\nsys.modules['builtins'].setattr(sys.modules['colmo.evaluation'].Evaluation, 'to_bytes', lambda self: "
        + repr('{"returns": [], "failure": "%s", "steps": 0, "raced_out": false, "seconds": 0.0}' % CANCELLED) + ".encode())\n" + NOTHING
    ),
    "referee": (  # its failure report for episode 0, and no actions, written before it is asked
        f"import os\ntext = {CANCELLED.encode()!r}\nfor fd in range(3, 64):\n    try:\n"
        "        os.write(fd, b'F' + (4 + len(text)).to_bytes(4, 'little') + bytes(4) + text + b'A' + bytes(4))\n"
        "    except OSError:\n        pass\n" + NOTHING
    ),
}


@pytest.mark.parametrize("mode", CLAIMS_CANCELLED)
def test_a_failure_claiming_the_executors_cancellation_is_marked_as_the_programs(sandbox, baseline, escaped_spec, mode):
    evaluation = sandbox.evaluate(CLAIMS_CANCELLED[mode], spec=escaped_spec, imports=("numpy", "math", "os", "sys", "ctypes", "socket"), mode=mode)
    assert evaluation.failure == f"program: {CANCELLED}"
    assert_unharmed(sandbox, baseline)


def test_a_tampering_programs_initial_score_is_the_referees(sandbox, baseline, escaped_spec):
    """A program that forges every fast-path evaluation is failed as tampering, its initial
    score is what the referee measured, and the forged number is nowhere in its result."""
    forge = (
        "import sys\nR = sys.modules['colmo.rollout']\n"
        "sys.modules['builtins'].setattr(R.Episodes, 'evaluation', lambda self: R.Evaluation((float('987.654'),) * len(self.seeds), None, int('1000')))\n"
        + NOTHING
    )
    result, own_constants = tuned_escaped(sandbox, escaped_spec, forge)
    assert result.failure is not None and result.failure.startswith("tampering: "), result.failure
    assert result.initial == dataclasses.replace(own_constants, seconds=result.initial.seconds)
    assert own_constants.failure is None and own_constants.score <= baseline["nothing"].score + 1e-9
    assert "987.6" not in result.failure
    assert_unharmed(sandbox, baseline)


def test_a_score_forged_for_a_programs_own_constants_alone_is_not_its_initial_score(sandbox, baseline, escaped_spec):
    """A program that knows its own constants (a parameter compared with the same number parsed
    from a string) forges its fast-path reply for them alone, a low score that any tuned
    candidate beats: tuning would move away, the referee confirm the tuned code, and nothing
    else check the forged number. The initial score is the referee's."""
    reply = '{"returns": [-5.0, -5.0], "failure": null, "steps": 2000, "raced_out": false, "seconds": 0.0}'
    forge = (
        "import sys\n\ndef policy(obs):\n    gain = 0.25\n    if gain == float('0.25'):\n"
        "        sys.modules['builtins'].setattr(sys.modules['colmo.evaluation'].Evaluation, 'to_bytes', "
        f"lambda self: {reply!r}.encode())\n    return gain * obs[2]\n"
    )
    result, own_constants = tuned_escaped(sandbox, escaped_spec, forge)
    assert result.failure is None
    assert own_constants.failure is None and own_constants.score > -5.0
    assert result.initial == dataclasses.replace(own_constants, seconds=result.initial.seconds)
    assert_unharmed(sandbox, baseline)


def test_a_child_that_pre_sends_its_actions_and_stops_reading_times_out(sandbox, baseline, escaped_spec):
    """A child of the referee writes a thousand steps' actions for five episodes ahead, then
    never reads: the worker's writes of observations fill the pipe, and its deadline ends the
    evaluation (a `timeout:`, not a worker lost to the coordinator's backstop)."""
    frames = "b'A' + (40).to_bytes(4, 'little') + bytes(40)"  # five episodes' zero actions
    presend = (
        "import os, ctypes\nfor fd in range(3, 64):\n    try:\n        os.write(fd, (" + frames + ") * 1000)\n"
        "    except OSError:\n        pass\nctypes.CDLL(None).pause()\n"
    )
    imports = ("numpy", "math", "os", "sys", "ctypes", "socket")
    evaluation = sandbox.evaluate(presend + NOTHING, spec=escaped_spec, episodes=5, imports=imports, mode=REFEREE)
    assert evaluation.failure is not None and evaluation.failure.startswith("timeout: "), evaluation.failure
    assert_unharmed(sandbox, baseline)


# -- a forged score through a search, its resume and MLflow ---------------------------------------

# Scores an escaped policy forges in its fast-path replies: one a pendulum episode can earn (the
# referee refutes it: tampering), one it cannot (more than the horizon's rewards: a malformed reply).
FORGED_SCORES = (987.654, 400002.6)
NUMBER = re.compile(r"\d+(?:\.\d*)?(?:e[+-]?\d+)?")


def forged_numbers(text: str) -> list[str]:
    """The numbers written in `text` that are one of `FORGED_SCORES`, as printed to any precision."""
    return [n for n in NUMBER.findall(text) if any(math.isclose(float(n), s, rel_tol=1e-4) for s in FORGED_SCORES)]


def forging_answer(score: float, episodes: int) -> str:
    """A model's answer whose policy, once called, replaces its process's evaluation reply with
    one claiming `score` in each episode (inside the policy: intake keeps only imports and
    definitions). The number is split in its source, which is stored and tracked as written."""
    returns = ", ".join([repr(score)] * episodes)
    reply = '{"returns": [%s], "failure": null, "steps": %d, "raced_out": false, "seconds": 0.0}' % (returns, 1000 * episodes)
    source = "'" + reply.replace(repr(score), repr(score)[:3] + "' + '" + repr(score)[3:]) + "'"
    return (
        "import sys\n\n\ndef policy(obs):\n"
        "    sys.modules['builtins'].setattr(sys.modules['colmo.evaluation'].Evaluation, 'to_bytes', "
        f"lambda self: ({source}).encode())\n    return 0.0\n"
    )


class ListedAnswers(Generator):
    """The model's answers, in order, one per sample."""

    def __init__(self, answers: list[str]):
        super().__init__(cfg=None, seed=0)
        self.answers = list(answers)

    def generate(self, prompt, n):
        return [Generation(self.answers.pop(0), "listed") for _ in range(n)]


def tracked_search(cfg, run_dir: Path, uri: str, answers: list[str]) -> str:
    """Run a search with an MLflow run of its own (the observer `colmo` gives it); its run id."""
    client, experiment_id = open_experiment(uri, "forged")
    run = TrackedRun(client, experiment_id, client.create_run(experiment_id).info.run_id, "forged", None, None, None)
    Search(cfg, run_dir, (MlflowTracker(run, table_every_s=0.0),), generator=ListedAnswers(answers)).run()
    return run.run_id


def mlflow_text(client, run_id: str, into: Path) -> str:
    """Everything MLflow shows of a run as text: params, tags, every metric's history and the
    text artifacts (the programs table and page, summary.json, best_policy.py)."""
    run = client.get_run(run_id)
    history = [m.value for key in run.data.metrics for m in client.get_metric_history(run_id, key)]  # repr: every digit
    artifacts = Path(client.download_artifacts(run_id, "", str(into)))
    texts = [path.read_text() for path in artifacts.rglob("*") if path.suffix in (".json", ".html", ".py", ".csv")]
    return "\n".join([json.dumps(run.data.params), json.dumps(run.data.tags), *map(repr, history), *texts])


def test_a_forged_score_is_never_stored_nor_tracked_not_even_after_a_resume(tmp_path, escaped_spec, monkeypatch):
    """Escaped policies forge their fast-path replies through a search tracked in MLflow: a score
    an episode can earn (refuted by the referee), one it cannot, and one return for two episodes
    (which once passed as a raced-out evaluation, the referee's two returns not compared with it).
    The first is failed as tampering; the malformed replies fail every candidate, so the other
    two keep their own constants, which the referee scored. No forged number is in the store,
    summary.json or MLflow, before or after the search is resumed with a well-behaved program."""
    monkeypatch.setenv("MLFLOW_ENABLE_ARTIFACTS_PROGRESS_BAR", "false")
    uri = f"sqlite:///{tmp_path / 'mlruns.db'}"
    run_dir = tmp_path / "run"
    common = (
        f"task.spec={escaped_spec}", "task.episodes=2", "gfo.budget=4", "llm.batch_size=1", "search.queue_size=1",
        "search.duplicate_retries=0", "executor.workers=1", "tracker=none", "search.progress=false", "heldout.episodes=2",
        "finish.render=false", "finish.simplify=false",
    )  # fmt: skip
    forgers = [forging_answer(score, 2) for score in FORGED_SCORES] + [forging_answer(FORGED_SCORES[0], 1)]
    first = tracked_search(compose("search", "search.max_samples=3", *common), run_dir, uri, forgers)
    resumed = tracked_search(compose("search", "search.max_samples=4", f"resume={run_dir}", *common), run_dir, uri, [GOOD])

    records = {record.sample: record for record in ProgramStore(run_dir / STORE_FILE).records()}
    assert records[3].status == "evaluated" and records[3].score > records[-1].score  # the resume went on
    within, beyond, short = records[0], records[1], records[2]
    assert within.status == "failed" and within.failure.startswith("tampering: ") and within.score is None, within.failure
    for record in (beyond, short):
        assert record.status == "evaluated" and record.score == record.initial_score, record.failure
    # Each does nothing: the referee's score of its own constants is the same for all three.
    assert within.initial_score == beyond.initial_score == short.initial_score is not None
    stored = json.dumps([dataclasses.asdict(record) for record in records.values()]) + (run_dir / "summary.json").read_text()
    assert not forged_numbers(stored)
    client = MlflowClient(uri)
    for run_id in (first, resumed):
        text = mlflow_text(client, run_id, tmp_path / run_id)
        assert "tampering: " in text or run_id == resumed  # the programs table shows the failures ...
        assert not forged_numbers(text), run_id  # ... and no forged number


@pytest.mark.parametrize("again, verdict", [((3.0, 4.0), TAMPERING), ((5.0, 6.0), NONDETERMINISTIC)], ids=["tampering", "nondeterministic"])
def test_a_fast_path_the_referee_refutes_is_tampering_unless_the_referee_cannot_repeat_itself(again, verdict):
    fast, referee = Evaluation((1.0, 2.0)), Evaluation((3.0, 4.0))
    judgement = judged(referee, fast, again=lambda: Evaluation(again))
    assert judgement.failure.startswith(verdict) and judgement.returns == referee.returns
    assert judged(referee, Evaluation((3.0, 4.0)), again=lambda: pytest.fail("asked again")) is referee


def test_a_policy_process_that_outlives_the_referees_quit_is_killed_and_failed(sandbox, baseline, escaped_spec):
    # An escaped program makes its process sleep instead of exiting once the referee says quit.
    lingers = "import sys\nsys.modules['builtins'].setattr(sys.modules['os'], '_exit', lambda code: sys.modules['time'].sleep(600))\n" + NOTHING
    evaluation = sandbox.evaluate(lingers, spec=escaped_spec, imports=("numpy", "math", "os", "sys", "ctypes", "socket"), mode=REFEREE)
    assert evaluation.failure == "tampering: the policy process outlived the referee's quit message", evaluation.failure
    assert_unharmed(sandbox, baseline)


def test_an_oversize_frame_is_named_as_the_protocol_break_it_is(sandbox, baseline, escaped_spec):
    # The policy's process writes a frame header announcing 2 MB straight to the referee's pipe.
    oversize = (
        "import os\nimport sys\n\ndef policy(obs):\n"
        "    for fd in range(3, 64):\n"
        "        try:\n            os.write(fd, b'A' + (1 << 21).to_bytes(4, 'little'))\n        except OSError:\n            pass\n"
        "    return 0.0\n"
    )
    evaluation = sandbox.evaluate(oversize, spec=escaped_spec, imports=("numpy", "math", "os", "sys", "ctypes", "socket"), mode=REFEREE)
    assert evaluation.failure.startswith("tampering: the policy process broke the referee protocol: frame of 2097152 bytes"), evaluation.failure
    assert_unharmed(sandbox, baseline)
