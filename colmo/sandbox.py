"""Sandboxed evaluation: untrusted policy code runs only in worker processes, never here.

Every program was written by a model and is treated as hostile. The layers, outermost first:

* **Static check** (`check_program`, run here before submitting and again in the worker): imports
  only of numpy (its `linalg`, `random`, `fft`, `emath` submodules), math and what the spec
  declares; no unsafe builtins (`open`, `exec`, `getattr`, `type`, `vars`, ...); no name
  starting with `__`, no attribute starting with `_` (dunders, internals such as `np._core`); no
  attribute that
  reads or writes files or reaches native code (`np.load`, `arr.tofile`, `arr.ctypes`, ...) or
  leaks frames and code (`gi_frame`, `f_globals`, `tb_frame`, `co_code`, ...); no
  `str.format`/`format_map`, whose `{0.__class__}` fields would walk attributes unchecked; no
  class definitions, `global` or `nonlocal`; no attribute assignment except on the program's
  own functions (`policy.state = ...`), so `np.clip = ...` is refused.
* **Namespace**: the program runs with an allowlist of builtins (`print` discards its output)
  and an `__import__` that hands out private copies of the allowed modules' public API, made
  afresh for every evaluation: whatever a program does to its `np`, the evaluator (which uses
  the real numpy) and every other program never see it. Copies are plain modules, so the
  policy's `np.sin` costs what it costs on numpy itself. The program's module code runs afresh
  for every evaluation too, so nothing it keeps carries over from one evaluation to the next,
  and everything it made is released (its generators' clean-up runs) before the result is sent.
  Each evaluation runs in its own `contextvars` context, so numpy's error and print state
  (`np.seterr`) is restored after it.
* **Process**: each worker is a fresh interpreter (`python -m colmo.sandbox`, never a fork of
  this process, so it holds none of its secrets), started with a clean environment (no API keys
  or tokens), in its own session, its cwd a private temporary directory, with rlimits: address
  space (memory), no core dumps, file size 0 (no file writes; SIGXFSZ ignored so a write fails
  instead of killing it), CPU time per evaluation, and no new processes while program code runs
  (RLIMIT_NPROC, which the kernel does not apply to root). At start-up the worker also asks to
  be killed if its parent dies, moves into a network namespace of its own where it can (root or
  user namespaces: then it has no network at all), and replaces the process-creation and
  signalling functions of `os`, `posix` and `_posixsubprocess` with ones that refuse, as defence
  in depth.
* **Supervision**: an evaluation that outlives the wall-clock timeout gets its worker's whole
  process group killed, and a fresh worker replaces it. The worker's reply is JSON, parsed and
  checked here, never unpickled: even a worker taken over by a program cannot run code here.

Decisions on the ambiguous cases:
* `np.random.seed`, `set_state` and the distribution functions are allowed: the evaluator
  reseeds the global generator at every episode and environments draw their initial states from
  their own generators, so a policy can only fix its own noise. `set_bit_generator` and
  `get_bit_generator` are refused: swapping the global generator's bit generator, or holding its
  lock, would break the evaluator's reseeding for the programs that follow in the worker.
* `print` is allowed and its output discarded; `str.format` and `format_map` are refused
  (f-strings, whose fields the check sees, and `%` formatting are fine).
* Numpy's other submodules (`lib`, `ma`, `testing`, `ctypeslib`, `f2py`, `core`, `rec`, ...) are
  not importable: they read and write files, unpickle, or reach native code.

Failure reasons are one line of printable characters (a program chooses its exception messages;
they must not inject lines or terminal escapes into logs), at most 500 characters: a category and
the details: `syntax error: ...`, `forbidden:
...`, `invalid: ...`, `exception: ZeroDivisionError: ... (step 3)`, `memory: ...`, `timeout:
...`, `cpu time: ...`, `crash: ...`, `environment: ...` (the spec's fault), and the evaluator's
`bad action ...`, `non-finite action ...`, `unstable simulation: ...`.

What crosses to a worker is plain data (`EvalRequest`: spec path, environment options,
episode seeds, skeleton code, parameters), so any executor can carry it.
"""

from __future__ import annotations

import ast
import builtins
import concurrent.futures
import contextvars
import ctypes
import dataclasses
import gc
import importlib
import json
import os
import queue
import resource
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import types
from collections import OrderedDict
from dataclasses import dataclass
from multiprocessing.connection import Connection
from typing import TYPE_CHECKING, Any, Callable, Collection, Optional, Protocol, Sequence

from colmo.task import Evaluation

if TYPE_CHECKING:
    from colmo.spec import Spec

# Builtins a policy cannot use. They are absent from its namespace anyway (it holds only
# `_SAFE_BUILTIN_NAMES`); the check names them for a clear reason, unless the program binds the
# name itself (`dir = np.sign(v)` is a variable, not the builtin).
FORBIDDEN_NAMES = frozenset({
    "open", "exec", "eval", "compile", "globals", "locals", "vars", "getattr", "setattr", "delattr",
    "input", "breakpoint", "exit", "quit", "help", "memoryview", "classmethod", "staticmethod",
    "super", "type", "object", "dir",
})
# Attributes that read or write files, unpickle, reach native code or internals, or change
# state the evaluator relies on: refused on any object.
FORBIDDEN_ATTRIBUTES = frozenset({
    "load", "loads", "loadtxt", "genfromtxt", "fromfile", "fromregex", "tofile", "dump", "save",
    "savez", "savez_compressed", "savetxt", "memmap", "DataSource", "ctypes", "cffi", "ctypeslib",
    "lib", "core", "testing", "test", "f2py", "distutils", "info", "show_config", "show_runtime",
    "setbufsize", "seterrcall", "set_bit_generator", "get_bit_generator", "as_strided", "system",
    "popen", "format", "format_map", "mro",
})
# Generator, coroutine, frame, traceback and code attributes: each leads to the frames (and so
# the globals and locals) of the evaluator that called the policy.
_FRAME_ATTRIBUTE_PREFIXES = ("gi_", "cr_", "ag_", "f_", "tb_", "co_")
# numpy's submodules a policy may import; the others read or write files (lib, ma, rec),
# reach native code (ctypeslib, f2py) or internals (core, testing).
_NUMPY_SUBMODULES = frozenset({"linalg", "random", "fft", "emath"})
# Fields of AST nodes that bind or name an identifier (besides Name, Attribute and imports).
_IDENTIFIER_FIELDS = {
    ast.FunctionDef: "name", ast.AsyncFunctionDef: "name", ast.arg: "arg", ast.keyword: "arg",
    ast.ExceptHandler: "name", ast.MatchAs: "name", ast.MatchStar: "name", ast.MatchMapping: "rest",
}
_MAX_REASON_CHARS = 500
_DEATH_RETRIES = 1
_MAX_REPLY_BYTES = 1 << 20


class ForbiddenProgram(ValueError):
    """The program failed the static check; the message is the stored failure reason."""


def _one_line(reason: str) -> str:
    """A failure reason as stored and logged: bounded, one line, printable."""
    return "".join(c if c.isprintable() else " " for c in reason[:_MAX_REASON_CHARS])


def _module_allowed(name: str, allowed: Collection[str]) -> bool:
    parts = name.split(".")
    if parts[0] not in allowed or any(part.startswith("_") for part in parts):
        return False
    return parts[0] != "numpy" or len(parts) == 1 or (len(parts) == 2 and parts[1] in _NUMPY_SUBMODULES)


def _attribute_allowed(name: str) -> bool:
    return not (name.startswith("_") or name in FORBIDDEN_ATTRIBUTES or name.startswith(_FRAME_ATTRIBUTE_PREFIXES))


def _bindings(tree: ast.AST) -> tuple[set[str], set[str]]:
    """The names the program defines with `def`, and the names it binds any other way."""
    functions, others = set(), set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            functions.add(node.name)
        elif isinstance(node, ast.Name) and not isinstance(node.ctx, ast.Load):
            others.add(node.id)
        elif isinstance(node, ast.alias):
            others.add((node.asname or node.name).split(".")[0])
        elif isinstance(node, (ast.arg, ast.ExceptHandler, ast.MatchAs, ast.MatchStar, ast.MatchMapping)):
            others.add(getattr(node, _IDENTIFIER_FIELDS[type(node)]))
    return functions, others


def _problem(node: ast.AST, allowed: frozenset[str], own_functions: set[str], bound: set[str]) -> str | None:
    """What is forbidden about one AST node, or None. `own_functions`: names that can only refer
    to a function the program defines (a `def` name bound nowhere else); `bound`: all names the
    program binds."""
    if isinstance(node, ast.Import):
        return next((f"import {a.name}" for a in node.names if not _module_allowed(a.name, allowed)), None)
    if isinstance(node, ast.ImportFrom):
        module = "." * node.level + (node.module or "")
        if node.level or not _module_allowed(module, allowed):
            return f"import {module}"
        return next((f"import {module}.{a.name}" for a in node.names if a.name != "*" and not _attribute_allowed(a.name)), None)
    if isinstance(node, ast.Name):
        return node.id if node.id.startswith("__") or (node.id in FORBIDDEN_NAMES and node.id not in bound) else None
    if isinstance(node, ast.Attribute):
        if not _attribute_allowed(node.attr):
            return f".{node.attr}"
        if not isinstance(node.ctx, ast.Load) and not (isinstance(node.value, ast.Name) and node.value.id in own_functions):
            return f"{'deletion of' if isinstance(node.ctx, ast.Del) else 'assignment to'} {ast.unparse(node)}"
        return None
    if isinstance(node, ast.MatchClass):  # `case C(attr=x)` reads C's attribute `attr`
        return next((f".{name}" for name in node.kwd_attrs if not _attribute_allowed(name)), None)
    if isinstance(node, (ast.Global, ast.Nonlocal)):
        return f"{type(node).__name__.lower()} statement"
    if isinstance(node, ast.ClassDef):
        return f"class definition ({node.name})"
    identifier = getattr(node, _IDENTIFIER_FIELDS.get(type(node), ""), None)
    if isinstance(node, ast.alias):
        identifier = node.asname
    return identifier if identifier and identifier.startswith("__") else None


def check_program(code: str, allowed_imports: Sequence[str]) -> None:
    """Reject code that imports or touches what a policy has no business with (module docstring).

    Raises `ForbiddenProgram`, whose message is the failure reason."""
    try:
        tree = ast.parse(code)
    except SyntaxError as error:
        line = f" (line {error.lineno})" if error.lineno else ""
        raise ForbiddenProgram(_one_line(f"syntax error: {error.msg}{line}")) from None
    except (RecursionError, MemoryError, ValueError) as error:  # absurd nesting; null bytes (some versions)
        raise ForbiddenProgram(f"syntax error: {str(error) or 'too deeply nested to parse'}") from None
    allowed = frozenset(allowed_imports)
    functions, others = _bindings(tree)
    for node in ast.walk(tree):
        problem = _problem(node, allowed, functions - others, functions | others)
        if problem:
            raise ForbiddenProgram(_one_line(f"forbidden: {problem}"))


# -- the namespace a program runs in ----------------------------------------------------------

def _discard(*args: object, **kwargs: object) -> None:
    """`print` for policies: allowed, so that a debugging print does not fail a program, but silent."""


_SAFE_BUILTIN_NAMES = (
    "abs", "all", "any", "ascii", "bin", "bool", "bytearray", "bytes", "callable", "chr", "complex",
    "dict", "divmod", "enumerate", "filter", "float", "format", "frozenset", "hasattr", "hash", "hex",
    "int", "isinstance", "issubclass", "iter", "len", "list", "map", "max", "min", "next", "oct",
    "ord", "pow", "range", "repr", "reversed", "round", "set", "slice", "sorted", "str", "sum",
    "tuple", "zip", "Ellipsis", "NotImplemented",
)
_SAFE_BUILTINS: dict[str, Any] = {
    **{name: getattr(builtins, name) for name in _SAFE_BUILTIN_NAMES},
    # Exception classes, so that programs can raise and catch them.
    **{name: value for name, value in vars(builtins).items() if isinstance(value, type) and issubclass(value, BaseException)},
    "print": _discard,
}
# Per process: the public API of each allowed top-level module, as a tree of modules that is
# never handed out; each program gets a copy (`_copy_tree`).
_TEMPLATES: dict[str, types.ModuleType] = {}


def _frozen(value: Any) -> Any:
    """Read-only stand-ins for a module's mutable containers (numpy's `typecodes`, `sctypeDict`)."""
    if isinstance(value, dict):
        return types.MappingProxyType(dict(value))
    if isinstance(value, (list, set)):
        return tuple(value) if isinstance(value, list) else frozenset(value)
    return value


def _public_api(module: types.ModuleType, path: str) -> types.ModuleType:
    """A module holding `module`'s public names a policy may use, allowed submodules included."""
    if path == "numpy":
        for name in _NUMPY_SUBMODULES:
            getattr(module, name)  # numpy imports some of them on first access
    api = types.ModuleType(path, module.__doc__)
    root = path.split(".")[0]
    for name, value in vars(module).items():
        if not _attribute_allowed(name):
            continue
        if isinstance(value, types.ModuleType):
            child = f"{path}.{name}"
            # A submodule, not a module it imported (numpy's `emath` is `numpy.lib.scimath`).
            if _module_allowed(child, {root}) and (value.__name__ == child or root == "numpy"):
                setattr(api, name, _public_api(value, child))
        else:
            setattr(api, name, _frozen(value))
    return api


def _submodule(module: types.ModuleType, name: str) -> types.ModuleType | None:
    for part in name.split(".")[1:]:
        module = vars(module).get(part)
        if not isinstance(module, types.ModuleType):
            return None
    return module


def _template(name: str) -> types.ModuleType:
    root = name.split(".")[0]
    template = _TEMPLATES.get(root)
    if template is None or _submodule(template, name) is None:
        importlib.import_module(root if root == "numpy" else name)  # numpy's are loaded by _public_api
        template = _TEMPLATES[root] = _public_api(sys.modules[root], root)
        if _submodule(template, name) is None:
            raise ModuleNotFoundError(f"no module named {name!r}")
    return template


def _copy_tree(template: types.ModuleType) -> types.ModuleType:
    """A private copy of a module tree: what a program assigns to its copy stays there."""
    copy = types.ModuleType(template.__name__)
    namespace = vars(copy)
    namespace.update(vars(template))
    for name, value in namespace.items():
        if isinstance(value, types.ModuleType):
            namespace[name] = _copy_tree(value)
    return copy


def _guarded_import(allowed: frozenset[str]) -> Callable[..., types.ModuleType]:
    """`__import__` for one program: allowed modules only, as copies private to the program."""
    copies: dict[str, types.ModuleType] = {}

    def import_(name: str, globals=None, locals=None, fromlist=(), level=0):  # noqa: A002 - mirrors __import__
        if level or not _module_allowed(name, allowed):
            raise ForbiddenProgram(f"forbidden: import {name}")
        root = name.split(".")[0]
        if root not in copies or _submodule(copies[root], name) is None:
            copies[root] = _copy_tree(_template(name))
        return _submodule(copies[root], name) if fromlist else copies[root]

    return import_


def _namespace(allowed_imports: Sequence[str], params: Sequence[float]) -> dict[str, Any]:
    safe = dict(_SAFE_BUILTINS, __import__=_guarded_import(frozenset(allowed_imports)))
    return {"__builtins__": safe, "__name__": "policy_module", "params": params}


def _compile(skeleton: str, allowed_imports: Sequence[str]) -> types.CodeType:
    check_program(skeleton, allowed_imports)
    return compile(skeleton, "<policy>", "exec")


def _execute(code: types.CodeType, namespace: dict[str, Any]) -> None:
    exec(code, namespace)
    if not callable(namespace.get("policy")):
        raise ForbiddenProgram("invalid: no callable `policy` in the program")


def compile_policy(skeleton: str, allowed_imports: Sequence[str], params: Sequence[float] = ()) -> dict[str, Any]:
    """Check a skeleton, run it in a namespace of safe builtins and private module copies, and
    return that namespace. The skeleton reads its constants from the global `params`."""
    namespace = _namespace(allowed_imports, params)
    _execute(_compile(skeleton, allowed_imports), namespace)
    return namespace


# -- requests and executors -------------------------------------------------------------------

@dataclass(frozen=True)
class EvalRequest:
    """One candidate evaluation, as plain data."""

    spec: str
    env: tuple[tuple[str, Any], ...]
    seeds: tuple[int, ...]
    skeleton: str
    params: tuple[float, ...]
    allowed_imports: tuple[str, ...]
    steps: Optional[int] = None  # episodes cut to this many control steps (a probe); None: whole


class Executor(Protocol):
    """Anything that evaluates batches of requests, results in request order (a `WorkerPool`,
    a Ray cluster). Thread-safe: several programs' optimizers share one executor."""

    n_workers: int
    closed: bool

    def evaluate(self, requests: Sequence[EvalRequest]) -> list[Evaluation]: ...

    @property
    def busy_seconds(self) -> float: ...

    def close(self, cancel: bool = False) -> None: ...


def batch_evaluator(executor: Executor, spec: "Spec", env: dict[str, Any], seeds: Sequence[int], skeleton: str):
    """The `evaluate_batch(params_list)` callable that GFO methods use for one program."""
    env_items = tuple(sorted(env.items()))

    def evaluate_batch(params_list: Sequence[Sequence[float]]) -> list[Evaluation]:
        return executor.evaluate([
            EvalRequest(str(spec.path), env_items, tuple(seeds), skeleton, tuple(float(p) for p in params), spec.allowed_imports)
            for params in params_list
        ])

    return evaluate_batch


# -- the worker process -----------------------------------------------------------------------

class ProgramProbe:
    """Does a program run on its task? It runs the first `steps` control steps of one episode
    in a sandbox worker of its own (so probes never wait behind evaluations), and passes if it
    returns valid actions there. Generators use it to offer only programs that work."""

    def __init__(self, spec: "Spec", env: dict[str, Any], seed: int, timeout_s: float, memory_mb: int, steps: int = 20):
        self.pool = WorkerPool(1, timeout_s, memory_mb)
        self.request = EvalRequest(str(spec.path), tuple(sorted(env.items())), (seed,), "", (), spec.allowed_imports, steps)

    def __call__(self, code: str) -> bool:
        from colmo.program import ProgramError, parametrize

        try:
            program = parametrize(code)
        except ProgramError:
            return False
        request = dataclasses.replace(self.request, skeleton=program.skeleton, params=program.values)
        return self.pool.evaluate([request])[0].failure is None

    def close(self) -> None:
        self.pool.close()


def _describe(error: BaseException, where: str = "") -> str:
    if isinstance(error, MemoryError):
        return f"memory: {str(error) or 'out of memory'}{where}"
    return f"exception: {type(error).__name__}: {error}{where}"


class _WorkerState:
    """What a worker keeps between requests: built environments and compiled programs."""

    def __init__(self, max_programs: int = 64):
        self.environments: dict[tuple, Any] = {}
        self.programs: OrderedDict[tuple, types.CodeType] = OrderedDict()
        self.max_programs = max_programs

    def environment(self, request: EvalRequest):
        key = (request.spec, request.env)
        if key not in self.environments:
            from colmo.spec import load_spec

            self.environments[key] = load_spec(request.spec).make_environment(**dict(request.env))
            # What exists now lives as long as the worker: keep the collections below cheap.
            gc.freeze()
        return self.environments[key]

    def code(self, request: EvalRequest) -> types.CodeType:
        key = (request.skeleton, request.allowed_imports)
        if key in self.programs:
            self.programs.move_to_end(key)
        else:
            self.programs[key] = _compile(request.skeleton, request.allowed_imports)
            if len(self.programs) > self.max_programs:
                self.programs.popitem(last=False)
        return self.programs[key]

    def evaluate(self, request: EvalRequest) -> Evaluation:
        from colmo.task import evaluate_policy

        try:
            env = self.environment(request)
        except Exception as error:  # the spec is the user's, not the program's: say so
            return Evaluation(failure=f"environment: {type(error).__name__}: {error}")
        namespace = _namespace(request.allowed_imports, request.params)
        # No new processes or threads while program code runs. Only the soft limit: the next
        # environment built may need threads (MuJoCo's compiler uses them).
        nproc = resource.getrlimit(resource.RLIMIT_NPROC)
        resource.setrlimit(resource.RLIMIT_NPROC, (0, nproc[1]))
        try:
            try:
                _execute(self.code(request), namespace)
            except ForbiddenProgram as error:
                return Evaluation(failure=str(error))
            except BaseException as error:  # module-level code of an untrusted program
                return Evaluation(failure=_describe(error, " (at import)"))
            return evaluate_policy(env, namespace["policy"], list(request.seeds), request.steps)
        except BaseException as error:  # SystemExit and friends raised by the policy
            return Evaluation(failure=_describe(error))
        finally:
            # Release everything the program made now, so that its clean-up code (a suspended
            # generator's `finally`) runs here, within its own time limit, not in the next program.
            namespace.clear()
            gc.collect()
            resource.setrlimit(resource.RLIMIT_NPROC, nproc)


def _limit_cpu_time(seconds: float) -> None:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    soft = int(usage.ru_utime + usage.ru_stime + seconds) + 1
    _, hard = resource.getrlimit(resource.RLIMIT_CPU)
    resource.setrlimit(resource.RLIMIT_CPU, (soft if hard == resource.RLIM_INFINITY else min(soft, hard), hard))


_PR_SET_PDEATHSIG = 1
_CLONE_NEWUSER, _CLONE_NEWNET = 0x10000000, 0x40000000
# Functions a worker never needs once started: process creation and signals. Everything that
# starts a process (`subprocess.Popen`, `os.spawn*`, `pty`) ends in one of these. Only functions
# are replaced: a module imported later may subclass a class (`ssl` subclasses `socket.socket`).
_DISARMED = {
    "os": ("fork", "forkpty", "system", "popen", "execv", "execve", "posix_spawn", "posix_spawnp",
           "kill", "killpg", "setsid", "setpgid", "setpgrp"),
    "posix": ("fork", "forkpty", "system", "execv", "execve", "posix_spawn", "posix_spawnp", "kill",
              "killpg", "setsid", "setpgid", "setpgrp"),
    "_posixsubprocess": ("fork_exec",),
    "subprocess": ("_fork_exec",),  # its own reference to _posixsubprocess.fork_exec
}


def _refuse(*args: object, **kwargs: object) -> None:
    raise PermissionError("not permitted in a sandbox worker")


def _isolate(parent_pid: int) -> None:
    """Start-up hardening that needs the worker's own process (see the module docstring)."""
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != parent_pid:  # the coordinator died before prctl took effect
        os._exit(1)
    # Best effort: needs root, or unprivileged user namespaces for the second form.
    if libc.unshare(_CLONE_NEWNET) != 0:
        libc.unshare(_CLONE_NEWUSER | _CLONE_NEWNET)
    for module_name, names in _DISARMED.items():
        module = sys.modules.get(module_name)
        for name in names:
            if module is not None and hasattr(module, name):
                setattr(module, name, _refuse)


def _encode(evaluation: Evaluation) -> bytes:
    failure = _one_line(evaluation.failure) if evaluation.failure else None
    return json.dumps({"returns": [float(r) for r in evaluation.returns], "failure": failure}).encode()


def _decode(data: bytes) -> Evaluation:
    """A worker's reply, checked: the worker runs untrusted code, so its bytes are data only."""
    reply = json.loads(data)
    returns, failure = reply["returns"], reply["failure"]
    if not isinstance(returns, list) or not all(type(r) is float for r in returns) or not isinstance(failure, (str, type(None))):
        raise ValueError("malformed reply")
    return Evaluation(tuple(returns), _one_line(failure) if failure else None)


def _worker_main(fd: int, timeout_s: float, parent_pid: int) -> None:
    _isolate(parent_pid)
    gc.freeze()
    connection = Connection(fd)
    state = _WorkerState()
    connection.send_bytes(b"ready")
    while True:
        try:
            request = connection.recv()
        except (EOFError, OSError):
            return
        if request is None:
            return
        _limit_cpu_time(timeout_s)
        try:
            evaluation = contextvars.copy_context().run(state.evaluate, request)
        except BaseException as error:  # describing the failure failed too (out of memory); memory is free again
            evaluation = Evaluation(failure=_describe(error))
        connection.send_bytes(_encode(evaluation))


# -- the coordinator's side -------------------------------------------------------------------

def _apply_limits(memory_mb: int) -> None:
    """Runs in the child between fork and exec."""
    memory = memory_mb * 1024 * 1024
    resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
    resource.setrlimit(resource.RLIMIT_FSIZE, (0, 0))
    # Writes past RLIMIT_FSIZE then fail with EFBIG instead of killing the worker.
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)


_PASSED_VARIABLES = ("PATH", "PYTHONPATH", "MENAGERIE_ROOT", "MENAGERIE_CACHE_DIR", "LANG", "LC_ALL")


def clean_environment(tmpdir: str) -> dict[str, str]:
    """The worker's environment: what Python and the simulators need, and nothing else."""
    env = {name: os.environ[name] for name in _PASSED_VARIABLES if name in os.environ}
    env.update(
        HOME=tmpdir, TMPDIR=tmpdir, PYTHONDONTWRITEBYTECODE="1", PYTHONNOUSERSITE="1",
        # The same hash() of a string in every worker: a policy's score must not depend on which ran it.
        PYTHONHASHSEED="0",
        # One worker per core: numerical libraries must not spawn thread pools of their own.
        OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1",
    )
    return env


_WORKER_EXITS = {
    -signal.SIGKILL: "crash: the worker was killed (SIGKILL): out of memory, or killed from outside",
    -signal.SIGXCPU: "cpu time: the evaluation exceeded its CPU time limit",
    -signal.SIGSEGV: "crash: segmentation fault",
}


class _Worker:
    def __init__(self, memory_mb: int, timeout_s: float, tmpdir: str):
        parent, child = socket.socketpair()
        self.process = subprocess.Popen(
            [sys.executable, "-m", "colmo.sandbox", str(child.fileno()), str(timeout_s), str(os.getpid())],
            pass_fds=(child.fileno(),), env=clean_environment(tmpdir), cwd=tmpdir,
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            start_new_session=True, preexec_fn=lambda: _apply_limits(memory_mb),
        )
        child.close()
        self.connection = Connection(parent.detach())

    def kill(self) -> None:
        try:
            os.killpg(self.process.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        self.process.wait()
        self.connection.close()

    def exit_reason(self) -> str:
        """Why the worker stopped answering; it may still be running if it broke the protocol."""
        try:
            code = self.process.wait(timeout=5)
        except subprocess.TimeoutExpired:
            return "crash: the worker broke the protocol"
        if code in _WORKER_EXITS:
            return _WORKER_EXITS[code]
        if code < 0:
            return f"crash: the worker was killed by {signal.Signals(-code).name}"
        return f"crash: the worker exited with code {code}"


def drain(jobs: queue.Queue) -> list[Any]:
    """Take every job still queued (stop markers, `None`, dropped), without waiting."""
    taken = []
    while True:
        try:
            job = jobs.get_nowait()
        except queue.Empty:
            return taken
        jobs.task_done()
        if job is not None:
            taken.append(job)


class WorkerPool:
    """`workers` sandboxed processes evaluating `EvalRequest`s; results come back as futures."""

    def __init__(self, workers: int, timeout_s: float = 600.0, memory_mb: int = 4096, startup_timeout_s: float = 120.0):
        self.timeout_s = timeout_s
        self.memory_mb = memory_mb
        self.startup_timeout_s = startup_timeout_s
        self.tmpdir = tempfile.mkdtemp(prefix="colmo-sandbox-")
        self.jobs: queue.Queue = queue.Queue()
        self.closed = False
        self._busy = [0.0] * workers
        self.threads = [threading.Thread(target=self._dispatch, daemon=True, name=f"colmo-worker-{i}") for i in range(workers)]
        self.workers: list[_Worker | None] = [None] * workers
        self.n_workers = workers
        for thread in self.threads:
            thread.start()

    @property
    def busy_seconds(self) -> float:
        """Seconds the workers spent evaluating, summed over workers."""
        return sum(self._busy)

    def submit(self, request: EvalRequest) -> concurrent.futures.Future:
        if self.closed:
            raise RuntimeError("the worker pool is closed")
        future: concurrent.futures.Future = concurrent.futures.Future()
        self.jobs.put((request, future))
        return future

    def evaluate(self, requests: Sequence[EvalRequest]) -> list[Evaluation]:
        return [future.result() for future in [self.submit(request) for request in requests]]

    def _start_worker(self) -> _Worker:
        # Started from the dispatcher thread that uses it: the worker's parent-death signal
        # follows that thread, which lives as long as the pool.
        worker = _Worker(self.memory_mb, self.timeout_s, self.tmpdir)
        if not worker.connection.poll(self.startup_timeout_s):
            worker.kill()
            raise RuntimeError("a sandbox worker did not start in time")
        try:
            worker.connection.recv_bytes(16)
        except (EOFError, OSError):
            raise RuntimeError(f"a sandbox worker failed to start: {worker.exit_reason()}") from None
        return worker

    def _dispatch(self) -> None:
        index = self.threads.index(threading.current_thread())
        while True:
            job = self.jobs.get()
            if job is None:
                break
            request, future = job
            if not future.set_running_or_notify_cancel():
                continue
            start = time.perf_counter()
            try:
                future.set_result(self._run(index, request))
            except BaseException as error:  # the pool itself broke: the caller must hear of it
                future.set_exception(error)
            self._busy[index] += time.perf_counter() - start
        worker = self.workers[index]
        if worker is not None:
            worker.kill()

    def _run(self, index: int, request: EvalRequest) -> Evaluation:
        # A worker that dies mid-evaluation may have been killed from outside (the OOM killer, an
        # operator): the request gets one more try on a fresh worker before it counts as failed.
        for _ in range(_DEATH_RETRIES + 1):
            worker = self.workers[index]
            if worker is None or worker.process.poll() is not None:
                worker = self.workers[index] = self._start_worker()
            died = False
            try:
                worker.connection.send(request)
                if worker.connection.poll(self.timeout_s):
                    return _decode(worker.connection.recv_bytes(_MAX_REPLY_BYTES))
                reason = f"timeout: the evaluation took longer than {self.timeout_s:g} s"
            except (EOFError, OSError):
                reason, died = worker.exit_reason(), True
            except (ValueError, KeyError, TypeError):
                reason = "crash: malformed reply from the worker"
            worker.kill()
            self.workers[index] = None
            if not died or self.closed:
                break
        return Evaluation(failure=reason)

    def close(self, cancel: bool = False) -> None:
        """Stop the workers: after the queued jobs, or at once (`cancel`) with queued jobs cancelled."""
        self.closed = True
        if cancel:
            self._cancel_queued()
            for worker in list(self.workers):
                if worker is not None:
                    worker.kill()
        for _ in self.threads:
            self.jobs.put(None)
        for thread in self.threads:
            thread.join()
        shutil.rmtree(self.tmpdir, ignore_errors=True)

    def _cancel_queued(self) -> None:
        for _, future in drain(self.jobs):
            future.cancel()

    def __enter__(self) -> "WorkerPool":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


if __name__ == "__main__":
    _worker_main(int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3]))
