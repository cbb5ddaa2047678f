"""The namespace a policy program runs in: allowlisted builtins and private module copies.

The program runs with an allowlist of builtins (`print` discards its output) and an
`__import__` that hands out private copies of the allowed modules' public API, made afresh for
every episode: whatever a program does to its `np`, the evaluator (which uses the real
numpy) never sees it. Copies are plain modules, so the policy's `np.sin` costs what it costs
on numpy itself. Every evaluation also runs in a process that no earlier program touched
(`colmo.sandbox.worker`), so these copies are a second line, not the only one.

A `Program` is checked and compiled once; `Program.new_policy(seed)` runs its module code anew
for each episode, so state a policy keeps (a function attribute, a module global, a closure, a
mutable default) lives for one episode only: a score cannot depend on which episodes ran
before in the same process, that is, on the worker count, the chunking, racing or the order of
episodes. Each instance's `np.random` draws from a generator of its own, seeded with the
episode's seed exactly as `np.random.seed(seed)` seeds the global one, so that instances
stepped side by side (the referee's lockstep) draw what they would draw one after another.

This module runs programs only inside sandbox worker processes; nothing here is called from
the coordinator.
"""

from __future__ import annotations

import builtins
import importlib
import sys
import types
from typing import Any, Callable, Sequence

import numpy as np

from colmo.coverage import Probe, instrument
from colmo.environments.base import PolicyFailure
from colmo.errors import describe_exception
from colmo.sandbox.check import NUMPY_SUBMODULES, ForbiddenProgram, attribute_allowed, check_tree, module_allowed, parse_program


def _discard(*args: object, **kwargs: object) -> None:
    """`print` for policies: allowed, so that a debugging print does not fail a program, but silent."""


_SAFE_BUILTIN_NAMES = (
    "abs", "all", "any", "ascii", "bin", "bool", "callable", "chr", "complex",
    "dict", "divmod", "enumerate", "filter", "float", "format", "frozenset", "hasattr", "hash", "hex",
    "int", "isinstance", "issubclass", "iter", "len", "list", "map", "max", "min", "next", "oct",
    "ord", "pow", "range", "repr", "reversed", "round", "set", "slice", "sorted", "str", "sum",
    "tuple", "zip", "Ellipsis", "NotImplemented",
)


def _without_object_buffers(kind: type) -> Callable[..., Any]:
    """`bytes` or `bytearray`, refusing an array that holds objects: its buffer is their
    addresses (`np.array([None, x])` is such an array), half of every raw-memory escape."""

    def make(*args: Any, **kwargs: Any) -> Any:
        if args and isinstance(args[0], np.ndarray) and args[0].dtype.hasobject:
            raise TypeError(f"{kind.__name__}() of an array of objects is refused: its bytes are their addresses")
        return kind(*args, **kwargs)

    return make


_SAFE_BUILTINS: dict[str, Any] = {
    **{name: getattr(builtins, name) for name in _SAFE_BUILTIN_NAMES},
    "bytes": _without_object_buffers(bytes),
    "bytearray": _without_object_buffers(bytearray),
    # Exception classes, so that programs can raise and catch them.
    **{name: value for name, value in vars(builtins).items() if isinstance(value, type) and issubclass(value, BaseException)},
    "print": _discard,
}
# The names a program may read without binding them: the builtins above and its constants.
PREDEFINED_NAMES = frozenset(_SAFE_BUILTINS) | {"params"}
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
        for name in NUMPY_SUBMODULES:
            getattr(module, name)  # numpy imports some of them on first access
    api = types.ModuleType(path, module.__doc__)
    root = path.split(".")[0]
    for name, value in vars(module).items():
        if not attribute_allowed(name):
            continue
        if isinstance(value, types.ModuleType):
            child = f"{path}.{name}"
            # A submodule, not a module it imported (numpy's `emath` is `numpy.lib.scimath`).
            if module_allowed(child, {root}) and (value.__name__ == child or root == "numpy"):
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


def template(name: str) -> types.ModuleType:
    """The public-API template of the top-level module of `name`, built once per process
    (workers build the allowed ones before they serve, so a program never waits for it)."""
    root = name.split(".")[0]
    cached = _TEMPLATES.get(root)
    if cached is None or _submodule(cached, name) is None:
        importlib.import_module(root if root == "numpy" else name)  # numpy's are loaded by _public_api
        cached = _TEMPLATES[root] = _public_api(sys.modules[root], root)
        if _submodule(cached, name) is None:
            raise ModuleNotFoundError(f"no module named {name!r}")
    return cached


# Per template module (by id: templates live as long as the process): the names of its
# submodules, found once, so that a copy per episode is a dictionary copy and not a scan.
_SUBMODULE_NAMES: dict[int, tuple[str, ...]] = {}


def _copy_tree(template_module: types.ModuleType) -> types.ModuleType:
    """A private copy of a module tree: what a program assigns to its copy stays there."""
    copy = types.ModuleType(template_module.__name__)
    namespace = vars(copy)
    namespace.update(vars(template_module))
    names = _SUBMODULE_NAMES.get(id(template_module))
    if names is None:
        names = _SUBMODULE_NAMES[id(template_module)] = tuple(name for name, value in namespace.items() if isinstance(value, types.ModuleType))
    for name in names:
        namespace[name] = _copy_tree(namespace[name])
    return copy


# numpy.random's module-level functions that are not bound methods of its global generator
# but use it, and the generator's method each stands for.
_GLOBAL_RANDOM_FUNCTIONS = {"seed": "seed", "ranf": "random_sample", "sample": "random_sample"}


_RANDOM_METHODS: dict[str, str] = {}


def _random_methods(namespace: dict[str, Any]) -> dict[str, str]:
    """The names of a `numpy.random` copy that draw from the global generator, each with the
    generator's method it stands for (found once per process)."""
    if not _RANDOM_METHODS:
        global_generator = np.random.mtrand._rand
        for name, value in namespace.items():
            if getattr(value, "__self__", None) is global_generator:
                _RANDOM_METHODS[name] = value.__name__
            elif name in _GLOBAL_RANDOM_FUNCTIONS:
                _RANDOM_METHODS[name] = _GLOBAL_RANDOM_FUNCTIONS[name]
    return _RANDOM_METHODS


def _private_random(random_copy: types.ModuleType, seed: int) -> None:
    """Bind a copy of `numpy.random` to a generator of its own, seeded as `np.random.seed(seed)`
    seeds the global one (same draws), instead of the process's global generator. Seeding costs
    as much as a short episode's steps, so the generator is made at the first draw: until then
    each function is a stand-in that makes it, rebinds the copy and draws."""
    namespace = vars(random_copy)
    methods = _random_methods(namespace)
    generator: list[np.random.RandomState] = []

    def bound(method: str) -> Callable[..., Any]:
        if not generator:
            generator.append(np.random.RandomState(seed % 2**32))
            for name, each in methods.items():
                if namespace[name] is stand_ins[name]:  # not one the program replaced
                    namespace[name] = getattr(generator[0], each)
        return getattr(generator[0], method)

    def stand_in(method: str) -> Callable[..., Any]:
        return lambda *args, **kwargs: bound(method)(*args, **kwargs)

    stand_ins = {name: stand_in(method) for name, method in methods.items()}
    namespace.update(stand_ins)


def _guarded_import(allowed: frozenset[str], seed: int) -> Callable[..., types.ModuleType]:
    """`__import__` for one program instance: allowed modules only, as copies private to it."""
    copies: dict[str, types.ModuleType] = {}

    def import_(name: str, globals=None, locals=None, fromlist=(), level=0):  # noqa: A002 - mirrors __import__
        if level or not module_allowed(name, allowed):
            raise ForbiddenProgram(f"forbidden: import {name}")
        root = name.split(".")[0]
        if root not in copies or _submodule(copies[root], name) is None:
            copies[root] = _copy_tree(template(name))
            if root == "numpy":
                _private_random(copies[root].random, seed)
        return _submodule(copies[root], name) if fromlist else copies[root]

    return import_


# numpy's process-wide settings a program can set and read back (print options, floating-point
# error handling), as the worker has them before any program runs: every program instance starts
# from them, so that no episode learns what an earlier one in the same process did.
_NUMPY_PRINT_OPTIONS = np.get_printoptions()
_NUMPY_ERRORS = np.geterr()


def reset_numpy_state() -> None:
    """Put numpy's print options and error handling back to what a fresh process has."""
    np.set_printoptions(**_NUMPY_PRINT_OPTIONS)
    np.seterr(**_NUMPY_ERRORS)


class Program:
    """A checked, compiled program: `new_policy` runs its module code anew for each episode."""

    def __init__(self, skeleton: str, allowed_imports: Sequence[str], params: Sequence[float], coverage: bool = False):
        """Raises `ForbiddenProgram` for a refused program. With `coverage`, the checked tree
        is instrumented (`colmo.coverage`) and `probe` counts what its branches do."""
        tree = parse_program(skeleton)
        check_tree(tree, allowed_imports)
        self.probe = Probe(instrument(tree)) if coverage else None
        self.code = compile(tree, "<policy>", "exec")  # the tree checked, not a second parse
        self.allowed_imports = frozenset(allowed_imports)
        self.params = tuple(params)

    def load(self, seed: int = 0) -> Callable[..., object]:
        """Run the module code in a fresh namespace of safe builtins and private module copies
        (`np.random` seeded with `seed`), with `params` as its constants; return its `policy`.
        Raises `ForbiddenProgram` for a policy-less program; whatever the module code raises
        propagates."""
        reset_numpy_state()
        builtins_ = dict(_SAFE_BUILTINS, __import__=_guarded_import(self.allowed_imports, seed))
        namespace = {"__builtins__": builtins_, "__name__": "policy_module", "params": self.params}
        if self.probe is not None:
            namespace.update(self.probe.names())
        exec(self.code, namespace)
        policy = namespace.get("policy")
        if not callable(policy):
            raise ForbiddenProgram("invalid: no callable `policy` in the program")
        return policy

    def new_policy(self, seed: int) -> Callable[..., object]:
        """A fresh instance of the policy for the episode of `seed`; raises `PolicyFailure`
        with the stored reason if the module code fails (an untrusted program's)."""
        try:
            return self.load(seed)
        except ForbiddenProgram as error:
            raise PolicyFailure(str(error)) from None
        except BaseException as error:  # module-level code of an untrusted program
            raise PolicyFailure(describe_exception(error, " (at import)")) from None


def load_policy(skeleton: str, allowed_imports: Sequence[str], params: Sequence[float]) -> Callable[..., object]:
    """One instance of a program's policy (`Program.load`); for trusted in-process callers."""
    return Program(skeleton, allowed_imports, params).load()


def compile_or_explain(
    skeleton: str, allowed_imports: Sequence[str], params: Sequence[float], coverage: bool = False,
) -> tuple[Program | None, str | None]:
    """`Program`, with a refusal turned into its stored reason: `(program, None)` or `(None, reason)`."""
    try:
        return Program(skeleton, allowed_imports, params, coverage), None
    except ForbiddenProgram as error:
        return None, str(error)
