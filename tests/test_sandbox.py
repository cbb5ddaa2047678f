"""The sandbox's static check, the namespace a program runs in, and the worker protocol.

No worker processes here (see test_hostile.py for hostile programs run end to end): these are
the rules themselves, each with the program that would break it. The programs that run here
(`load_policy`) are the tests' own.
"""

from __future__ import annotations

import json
import math
import os
import pickle
import threading
import time

import numpy as np
import pytest

from colmo.environments.base import PolicyFailure
from colmo.environments.pendulum import PendulumSwingup
from colmo.evaluation import REFEREE, EvalRequest, Evaluation
from colmo.program import parametrize
from colmo.rollout import as_action, evaluate_policy
from colmo.sandbox import ForbiddenProgram, check_program
from colmo.sandbox.namespace import Program, load_policy
from colmo.sandbox.referee import RefereeTimeout, frame, referee_evaluation, write_all

IMPORTS = ("numpy", "math")


def reason(code: str, imports=IMPORTS) -> str | None:
    try:
        check_program(code, imports)
    except ForbiddenProgram as error:
        return str(error)
    return None


@pytest.mark.parametrize("name", ["paper_pendulum", "paper_ball_in_cup", "paper_cheetah", "paper_quadruped", "paper_a1", "pendulum_mistuned"])
def test_the_paper_policies_pass(examples, name):
    assert reason(parametrize((examples / f"{name}.py").read_text()).skeleton) is None


@pytest.mark.parametrize("code", [
    "import numpy.linalg as la\nfrom numpy.random import normal\nfrom numpy import *\nimport math\n",
    "import numpy as np\nfrom numpy import fft, emath\nx = np.random.default_rng(0).normal()\n",
    # State on the program's own function, and builtin names used as variables.
    "def policy(obs):\n    if not hasattr(policy, 'n'):\n        policy.n = 0\n    policy.n += 1\n    return 0.0\n",
    "def policy(obs):\n    dir = 1 if obs[0] > 0 else -1\n    type = 'pd'\n    return dir\n",
    "import numpy as np\ndef policy(obs):\n    with np.errstate(all='ignore'):\n        return f'{obs!r}' and np.sign(obs[0]) * (lambda v: v)(1.0)\n",
    "def policy(obs):\n    match obs.shape:\n        case (3,):\n            return 0.0\n    try:\n        pass\n    except ValueError as error:\n        return error.args\n",
    # Arrays of numbers built every ordinary way, and the class used only to test against.
    "import numpy as np\ndef policy(obs):\n    a = np.zeros(3, dtype='float32') + np.array([1, 2, 3], dtype=np.int64)\n"
    "    b = np.asarray(obs).astype('f8').reshape(3)\n    return float(a @ b) if isinstance(obs, (np.ndarray, list)) else 0.0\n",
    "def policy(obs):\n    mode = 'Object' if obs[0] > 0 else 'ok'\n    return 0.0\n",  # strings that are no dtype
])
def test_ordinary_policies_pass(code):
    assert reason(code) is None


@pytest.mark.parametrize("code, expected", [
    # Modules a policy has no business with, however they are reached.
    ("import os", "forbidden: import os"),
    ("import sys", "forbidden: import sys"),
    ("import subprocess", "forbidden: import subprocess"),
    ("import socket", "forbidden: import socket"),
    ("import ctypes", "forbidden: import ctypes"),
    ("import importlib", "forbidden: import importlib"),
    ("import pickle", "forbidden: import pickle"),
    ("import multiprocessing", "forbidden: import multiprocessing"),
    ("from os import path", "forbidden: import os"),
    ("from . import x", "forbidden: import ."),
    ("import numpy.testing", "forbidden: import numpy.testing"),
    ("import numpy.ctypeslib", "forbidden: import numpy.ctypeslib"),
    ("import numpy.lib.npyio", "forbidden: import numpy.lib.npyio"),
    ("import numpy._core", "forbidden: import numpy._core"),
    ("import numpy.random.mtrand", "forbidden: import numpy.random.mtrand"),
    ("from numpy import load", "forbidden: import numpy.load"),
    ("from numpy import _core", "forbidden: import numpy._core"),
    # Builtins that execute code, reach objects by name, or do I/O.
    ("open('/etc/passwd')", "forbidden: open"),
    ("exec('1')", "forbidden: exec"),
    ("eval('1')", "forbidden: eval"),
    ("compile('1', '', 'eval')", "forbidden: compile"),
    ("__import__('os')", "forbidden: __import__"),
    ("globals()", "forbidden: globals"),
    ("getattr(1, '__cl' + 'ass__')", "forbidden: getattr"),
    ("vars(np)", "forbidden: vars"),
    ("type(())", "forbidden: type"),
    ("breakpoint()", "forbidden: breakpoint"),
    ("__builtins__['open']", "forbidden: __builtins__"),
    # Object-graph walks to builtins, globals and frames.
    ("().__class__.__base__.__subclasses__()", "forbidden: .__subclasses__"),
    ("[].__class__", "forbidden: .__class__"),
    ("np.__dict__", "forbidden: .__dict__"),
    ("'{0.__class__}'.format(1)", "forbidden: .format"),
    ("'{x}'.format_map({})", "forbidden: .format_map"),
    ("int.mro()", "forbidden: .mro"),
    ("g = (x for x in []); g.gi_frame", "forbidden: .gi_frame"),
    ("g.gi_code", "forbidden: .gi_code"),
    ("c.cr_frame", "forbidden: .cr_frame"),
    ("frame.f_back", "forbidden: .f_back"),
    ("frame.f_globals", "forbidden: .f_globals"),
    ("frame.f_builtins", "forbidden: .f_builtins"),
    ("tb.tb_frame", "forbidden: .tb_frame"),
    ("policy.co_code", "forbidden: .co_code"),
    ("try:\n    1 / 0\nexcept Exception as e:\n    e.__traceback__", "forbidden: .__traceback__"),
    ("match x:\n    case int(ctypes=c):\n        pass", "forbidden: .ctypes"),
    # Numpy's file, pickle and native-code paths.
    ("np.load('x.npy')", "forbidden: .load"),
    ("np.fromfile('/proc/self/environ')", "forbidden: .fromfile"),
    ("np.loadtxt('/etc/passwd')", "forbidden: .loadtxt"),
    ("np.genfromtxt('/etc/passwd')", "forbidden: .genfromtxt"),
    ("np.save('x', obs)", "forbidden: .save"),
    ("obs.tofile('x')", "forbidden: .tofile"),
    ("obs.dump('x')", "forbidden: .dump"),
    ("obs.ctypes.shape", "forbidden: .ctypes"),  # `.data` is refused on its own too
    ("np.ctypeslib.load_library('libc', '/lib')", "forbidden: .ctypeslib"),
    ("np.lib.stride_tricks", "forbidden: .lib"),
    ("np.core.multiarray", "forbidden: .core"),
    ("np._core", "forbidden: ._core"),
    ("np.testing.assert_equal", "forbidden: .testing"),
    ("np.random.set_bit_generator(g)", "forbidden: .set_bit_generator"),
    # Monkeypatching, directly or through an alias, and what else changes shared objects.
    ("np.clip = lambda *a, **k: 0", "forbidden: assignment to np.clip"),
    ("np.isfinite = lambda x: True", "forbidden: assignment to np.isfinite"),
    ("np.random.seed = print", "forbidden: assignment to np.random.seed"),
    ("m = np\nm.asarray = list", "forbidden: assignment to m.asarray"),
    ("del np.clip", "forbidden: deletion of np.clip"),
    ("def policy(obs):\n    pass\npolicy = np\npolicy.clip = 0", "forbidden: assignment to policy.clip"),
    ("def f(policy):\n    policy.clip = 0", "forbidden: assignment to policy.clip"),
    ("class A:\n    pass", "forbidden: class definition (A)"),
    ("def f():\n    global np", "forbidden: global statement"),
    ("def __del__():\n    pass", "forbidden: __del__"),
    ("import numpy as __builtins__", "forbidden: __builtins__"),
    # Raw memory: object arrays over buffers hand a program fake objects, hence the real builtins.
    ("np.ndarray(shape=(1,), dtype='O', buffer=bytearray(8))", "forbidden: .ndarray"),
    ("x = np.zeros(2, buffer=b)", "forbidden: keyword buffer="),
    ("a = np.zeros(2, dtype='O')", "forbidden: object dtype 'O'"),
    ("a = np.zeros(2, dtype='|O8')", "forbidden: object dtype '|O8'"),
    ("a = np.empty(1, dtype=[('a', 'O')])", "forbidden: object dtype 'O'"),
    ("a = np.empty(1, dtype='object')", "forbidden: object dtype 'object'"),
    ("a = np.array([1]).astype(object)", "forbidden: object"),
    ("a = np.empty(1, np.object_)", "forbidden: .object_"),
    ("obs.resize((100,), refcheck=False)", "forbidden: .resize"),
    ("np.zeros(2).setflags(write=True)", "forbidden: .setflags"),
    ("a = np.recarray((1,), formats='f8')", "forbidden: .recarray"),
    ("f = np.ndarray\nf((1,), 'f8', b)", "forbidden: .ndarray"),
    # A decorator can rebind a function's name to a shared object, whose attributes the
    # assignment rule would then let through.
    ("@(lambda f: np.poly1d)\ndef policy(obs):\n    pass\npolicy.x = 1", "forbidden: decorator on policy"),
])
def test_forbidden(code, expected):
    assert reason("import numpy as np\n" + code) == expected


@pytest.mark.parametrize("code, expected", [
    ("def policy(obs)\n    return 0", "syntax error: expected ':' (line 1)"),
    ("x = " + "-" * 100_000 + "1", "syntax error: too deeply nested to parse"),
    ("x = 1" + " + 1" * 200_000, "syntax error: maximum recursion depth exceeded during ast construction"),
    ("x = 1\0", "syntax error: source code string cannot contain null bytes"),
])
def test_unparsable_programs_are_rejected_without_crashing(code, expected):
    assert reason(code) == expected


def test_spec_declared_imports_are_allowed():
    assert reason("import json\nfrom json import dumps", IMPORTS + ("json",)) is None
    assert reason("import json", IMPORTS) == "forbidden: import json"


def namespace(code: str) -> dict:
    return load_policy("import numpy as np\nimport math\n" + code + "\ndef policy(obs):\n    return 0.0\n", IMPORTS, ()).__globals__


def test_builtins_are_an_allowlist_and_print_is_silent(capsys):
    builtins = namespace("print('x' * 1000)")["__builtins__"]
    assert capsys.readouterr().out == ""
    assert {"abs", "min", "range", "ZeroDivisionError", "SystemExit", "print"} <= set(builtins)
    assert not {"open", "getattr", "type", "vars", "id", "object", "help", "input", "__build_class__"} & set(builtins)


def test_numpy_is_a_copy_of_its_safe_public_api():
    np_ = namespace("")["np"]
    assert np_ is not np and np_.sin is np.sin and np_.random.normal is not np.random.normal  # see test_each_instance_draws_from_its_own_generator
    for name in ("linalg", "random", "fft", "emath"):
        assert getattr(np_, name).__name__.startswith("numpy.")
    for name in ("lib", "ma", "testing", "ctypeslib", "f2py", "core", "rec", "load", "save", "fromfile", "memmap", "info"):
        assert not hasattr(np_, name), name
    assert not hasattr(np_.random, "mtrand") and not hasattr(np_.random, "set_bit_generator")
    with pytest.raises(TypeError):
        np_.typecodes["All"] = ""  # shared containers are read-only copies


def test_a_programs_monkeypatching_stays_in_its_own_copy():
    """Even if a program got past the check and patched its numpy, neither the evaluator nor the
    next program would see it: each program gets private copies of the modules."""
    patched = namespace("")
    patched["np"].isfinite = lambda x: True  # what `np.isfinite = ...` would do, past the check
    patched["np"].random.seed = lambda seed: None
    patched["math"].pi = 3.0
    assert np.isfinite is not patched["np"].isfinite and np.random.seed is not patched["np"].random.seed
    with pytest.raises(PolicyFailure, match="non-finite action"):
        as_action(float("nan"), 1)
    fresh = namespace("")
    assert fresh["np"].isfinite is np.isfinite and fresh["math"].pi == math.pi
    fresh["np"].random.seed(3)
    assert fresh["np"].random.normal() == np.random.RandomState(3).normal()


@pytest.mark.parametrize("raw, size", [
    (0.25, 1), (np.float64(-3.5), 1), (np.array([0.5]), 1), (np.arange(6.0), 6), (np.arange(12.0)[::2], 6),
    (np.array([1e308, 1e308]), 2),  # finite values whose sum is not
    (np.float32(0.5), 1), (True, 1), (3, 1), (np.array(2.0), 1), ([1, 2.5], 2), ((np.float64(1.5),), 1),
])
def test_an_action_is_a_new_float_array_of_what_the_policy_returned(raw, size):
    action = as_action(raw, size)
    assert action.dtype == np.float64 and action.shape == (size,) and action.flags.writeable
    assert action.tolist() == np.ravel(np.asarray(raw, dtype=np.float64)).tolist()
    assert not np.shares_memory(action, np.asarray(raw))  # the policy may keep and change what it returned


@pytest.mark.parametrize("raw, size", [
    (math.inf, 1), (np.float64("nan"), 1), (np.array([1.0, -np.inf]), 2), (np.array([np.nan]), 1), (float("-inf"), 1),
])
def test_a_non_finite_action_fails(raw, size):
    with pytest.raises(PolicyFailure, match="non-finite action"):
        as_action(raw, size)


def test_a_policy_that_returns_nothing_is_told_so():
    with pytest.raises(PolicyFailure, match=r"the policy returned None \(it reached no return statement\)"):
        as_action(None, 1)


def test_each_instance_draws_from_its_own_generator():
    """An instance's np.random draws what the global generator seeded with its episode's seed
    draws, whatever other instances or the evaluator draw in between (the referee steps
    instances side by side), and leaves the global generator alone."""
    program = Program("import numpy as np\ndef policy(obs):\n    return np.random.normal()\n", IMPORTS, ())
    np.random.seed(7)
    expected = [np.random.normal() for _ in range(3)]
    first, second = program.new_policy(7), program.new_policy(7)
    np.random.seed(1)
    rows = [(first(None), second(None), np.random.normal()) for _ in range(3)]
    assert [row[0] for row in rows] == [row[1] for row in rows] == expected
    np.random.seed(1)
    assert [np.random.normal() for _ in range(3)] != expected


def test_every_instance_starts_from_the_module_code():
    """State a policy keeps (function attribute, module global, mutable default) lives in one instance."""
    program = Program("COUNT = [0]\ndef policy(obs, seen=[]):\n    seen.append(1)\n    COUNT[0] += 1\n"
                      "    policy.calls += 1\n    return float(COUNT[0] + len(seen) + policy.calls)\npolicy.calls = 0\n", IMPORTS, ())
    first = program.new_policy(0)
    assert [first(None) for _ in range(3)] == [3.0, 6.0, 9.0]
    assert program.new_policy(0)(None) == 3.0


def test_a_failing_module_code_is_the_episodes_failure():
    program = Program("import numpy as np\nif np.random.uniform() < 0.5:\n    raise ValueError('unlucky')\ndef policy(obs):\n    return 0.0\n", IMPORTS, ())
    reasons = set()
    for seed in range(20):
        try:
            program.new_policy(seed)
            reasons.add(None)
        except PolicyFailure as failure:
            reasons.add(str(failure))
    assert reasons == {None, "exception: ValueError: unlucky (at import)"}
    with pytest.raises(PolicyFailure, match="^invalid: no callable `policy`"):
        Program("x = 1\n", IMPORTS, ()).new_policy(0)


def test_the_policy_gets_a_copy_of_the_observation():
    """Writing to `obs` must not reach the simulation, even for an environment whose
    observation is a view of its state."""

    class ViewingPendulum(PendulumSwingup):
        def observation(self):
            return self.data.qpos  # a view into MjData

    code = "def policy(obs):\n    obs[0] = 0.0\n    return 0.0\n"  # holding the pole upright: 1000 points
    env = ViewingPendulum()
    honest = evaluate_policy(env, load_policy("def policy(obs):\n    return 0.0\n", IMPORTS, ()), [3])
    assert evaluate_policy(env, load_policy(code, IMPORTS, ()), [3]) == honest


def test_module_level_constants_read_params():
    program = parametrize("GAIN = 2.5\ndef policy(obs):\n    return GAIN * obs[2]\n")
    assert load_policy(program.skeleton, IMPORTS, program.values).__globals__["GAIN"] == 2.5


def test_a_program_without_policy_is_invalid():
    with pytest.raises(ForbiddenProgram, match="^invalid: no callable `policy`"):
        load_policy("x = 1\n", IMPORTS, ())


def round_trip(evaluation: Evaluation) -> Evaluation:
    return Evaluation.from_bytes(evaluation.to_bytes())


def test_replies_round_trip_and_reasons_are_truncated():
    evaluation = Evaluation((1.0, 2.5), None, steps=2000, raced_out=True, seconds=0.25)
    assert round_trip(evaluation) == evaluation
    failed = round_trip(Evaluation((), "exception: ValueError: " + "x" * 10_000))
    assert failed.failure.startswith("exception: ValueError: x") and len(failed.failure) == 500
    # A program chooses its exception messages: no line breaks or terminal escapes reach the logs.
    assert round_trip(Evaluation((), "exception: ValueError: a\nb\x1b[2J")).failure == "exception: ValueError: a b [2J"


@pytest.mark.parametrize("reply", [
    pickle.dumps(Evaluation((1e9,), None)),  # never unpickled: a worker could send any object
    b"not json",
    json.dumps([1.0]).encode(),
    json.dumps({"returns": ["1"], "failure": None}).encode(),
    json.dumps({"returns": [], "failure": 3}).encode(),
    json.dumps({"returns": []}).encode(),
    json.dumps({"returns": [float("nan")], "failure": None, "steps": 1, "raced_out": False, "seconds": 0.0}).encode(),
    json.dumps({"returns": [1.0], "failure": None, "steps": -1, "raced_out": False, "seconds": 0.0}).encode(),
])
def test_malformed_replies_are_refused(reply):
    with pytest.raises(ValueError):
        Evaluation.from_bytes(reply)


def test_a_write_the_reader_never_takes_ends_at_the_deadline():
    """The referee's writes to its child are bounded by the request's deadline: a child that
    stops reading cannot block the worker (the pipe fills, then the deadline passes)."""
    read_fd, write_fd = os.pipe()
    try:
        with pytest.raises(RefereeTimeout):
            write_all(write_fd, b"x" * (4 << 20), deadline=time.monotonic() + 0.2)
        assert len(os.read(read_fd, 1 << 20)) > 0  # it wrote what the pipe could hold
    finally:
        os.close(read_fd)
        os.close(write_fd)


# -- the referee's checks of what its child answers ----------------------------------------------

def _scripted_child(read_fd: int, write_fd: int, answer) -> None:
    """A referee child written from the wire format (colmo.sandbox.referee's docstring): for the
    k-th `O` frame (the live episodes' indices), it writes `answer(k, live)`."""
    def read_exactly(size: int) -> bytes:
        data = b""
        while len(data) < size:
            chunk = os.read(read_fd, size - len(data))
            if not chunk:
                raise EOFError
            data += chunk
        return data

    step = 0
    try:
        while True:
            tag, length = bytes(read_exactly(1)), int.from_bytes(read_exactly(4), "little")
            payload = read_exactly(length)
            if tag == b"O":
                count = int.from_bytes(payload[:4], "little")
                os.write(write_fd, answer(step, np.frombuffer(payload, dtype="<u4", count=count, offset=4).tolist()))
                step += 1
            elif tag != b"S":
                return
    except EOFError:
        return


def _refereed(answer, episodes: int = 4, steps: int = 10) -> Evaluation:
    """`referee_evaluation` of pendulum episodes against `_scripted_child(answer)` in a thread."""
    envs = [PendulumSwingup() for _ in range(episodes)]
    request = EvalRequest("pendulum", (), tuple(range(episodes)), "", (), (), steps=steps, mode=REFEREE)
    observations_read, observations_write = os.pipe()
    actions_read, actions_write = os.pipe()
    child = threading.Thread(target=_scripted_child, args=(observations_read, actions_write, answer))
    child.start()
    try:
        return referee_evaluation(envs, request, actions_read, observations_write, time.monotonic() + 60)
    finally:
        os.close(observations_write)
        child.join()
        for fd in (observations_read, actions_read, actions_write):
            os.close(fd)


def _zero_actions(live: list[int]) -> bytes:
    return frame(b"A", np.zeros(len(live)).tobytes())


def _zero_policy_returns(episodes: int, steps: int) -> tuple[float, ...]:
    return evaluate_policy(PendulumSwingup(), lambda obs: 0.0, range(episodes), steps).returns


def test_the_referee_runs_an_honest_childs_actions():
    assert _refereed(lambda step, live: _zero_actions(live)) == Evaluation(_zero_policy_returns(4, 10), None, 40)


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_a_non_finite_action_from_the_child_fails_its_episode_as_tampering(bad):
    """Episode 2 gets a non-finite action at step 3: the evaluation fails with its reason, and
    the episodes before it run to their end, as one after another."""
    def answer(step, live):
        if step != 3 or 2 not in live:
            return _zero_actions(live)
        actions = np.zeros(len(live))
        actions[live.index(2)] = bad
        return frame(b"A", actions.tobytes())

    evaluation = _refereed(answer)
    assert evaluation.failure == "tampering: the policy process sent a malformed action"
    assert evaluation.returns == _zero_policy_returns(2, 10)


def test_a_failure_the_child_reports_fails_its_episode_with_its_reason():
    """The child reports episode 1's policy failing at step 5 and acts for the others: the
    evaluation fails with that reason after episode 0's whole return."""
    def answer(step, live):
        if step != 5 or 1 not in live:
            return _zero_actions(live)
        return frame(b"F", (1).to_bytes(4, "little") + b"exception: ValueError: x (step 5)") + _zero_actions([i for i in live if i != 1])

    evaluation = _refereed(answer)
    assert (evaluation.returns, evaluation.failure) == (_zero_policy_returns(1, 10), "exception: ValueError: x (step 5)")


@pytest.mark.parametrize("answer", [
    lambda step, live: frame(b"F", (7).to_bytes(4, "little") + b"no such episode") + _zero_actions(live),
    lambda step, live: frame(b"A", np.zeros(len(live) + 1).tobytes()),  # one action too many
    lambda step, live: frame(b"X", np.zeros(len(live)).tobytes()),
], ids=["failure of an episode not live", "too many actions", "unknown tag"])
def test_a_malformed_answer_fails_the_evaluation_as_tampering(answer):
    evaluation = _refereed(answer)
    assert (evaluation.returns, evaluation.failure) == ((), "tampering: the policy process sent a malformed action")


def test_a_worker_keeps_the_simulators_of_its_last_few_tasks_only():
    # A robustness report asks for ~36 tasks (one per perturbation); a worker that kept every one's
    # simulators ran out of address space and failed to build the environments after the first dozen.
    from colmo.config import PerturbConfig
    from colmo.environments.perturb import with_perturbation
    from colmo.sandbox.worker import KEPT_TASKS, Worker

    worker = Worker()
    tasks = [tuple(sorted(with_perturbation({}, PerturbConfig(mass=0.05 * (k + 1))).items())) for k in range(KEPT_TASKS + 3)]
    for env in tasks:
        simulators = worker.environments_for(EvalRequest("pendulum.py", env, (0, 1, 2), "", (), (), mode=REFEREE))
        assert len(simulators) == 3
    assert list(worker.environments) == [("pendulum.py", env) for env in tasks[-KEPT_TASKS:]]
    again = worker.environments_for(EvalRequest("pendulum.py", tasks[-1], (5,), "", (), (), mode=REFEREE))
    assert again[0] is worker.environments[("pendulum.py", tasks[-1])][0]  # the last task's simulators are reused
