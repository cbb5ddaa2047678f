"""The namespace a policy program runs in: allowlisted builtins and private module copies.

The program runs with an allowlist of builtins (`print` discards its output) and an
`__import__` that hands out private copies of the allowed modules' public API, made afresh for
every evaluation: whatever a program does to its `np`, the evaluator (which uses the real
numpy) never sees it. Copies are plain modules, so the policy's `np.sin` costs what it costs
on numpy itself. Every evaluation also runs in a process that no earlier program touched
(`colmo.sandbox.worker`), so these copies are a second line, not the only one.

This module runs programs only inside sandbox worker processes; nothing here is called from
the coordinator.
"""

from __future__ import annotations

import builtins
import importlib
import sys
import types
from typing import Any, Callable, Sequence

from colmo.errors import describe_exception
from colmo.sandbox.check import NUMPY_SUBMODULES, ForbiddenProgram, attribute_allowed, check_tree, module_allowed, parse_program


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


def _copy_tree(template_module: types.ModuleType) -> types.ModuleType:
    """A private copy of a module tree: what a program assigns to its copy stays there."""
    copy = types.ModuleType(template_module.__name__)
    namespace = vars(copy)
    namespace.update(vars(template_module))
    for name, value in namespace.items():
        if isinstance(value, types.ModuleType):
            namespace[name] = _copy_tree(value)
    return copy


def _guarded_import(allowed: frozenset[str]) -> Callable[..., types.ModuleType]:
    """`__import__` for one program: allowed modules only, as copies private to the program."""
    copies: dict[str, types.ModuleType] = {}

    def import_(name: str, globals=None, locals=None, fromlist=(), level=0):  # noqa: A002 - mirrors __import__
        if level or not module_allowed(name, allowed):
            raise ForbiddenProgram(f"forbidden: import {name}")
        root = name.split(".")[0]
        if root not in copies or _submodule(copies[root], name) is None:
            copies[root] = _copy_tree(template(name))
        return _submodule(copies[root], name) if fromlist else copies[root]

    return import_


def load_policy(skeleton: str, allowed_imports: Sequence[str], params: Sequence[float]) -> Callable[..., object]:
    """Check the skeleton, run its module code in a fresh namespace of safe builtins and private
    module copies with `params` as its constants, and return its `policy`. Raises
    `ForbiddenProgram` for a refused or policy-less program; whatever the module code raises
    propagates (the caller reports it)."""
    tree = parse_program(skeleton)
    check_tree(tree, allowed_imports)
    code = compile(tree, "<policy>", "exec")  # the tree checked, not a second parse
    builtins_ = dict(_SAFE_BUILTINS, __import__=_guarded_import(frozenset(allowed_imports)))
    namespace = {"__builtins__": builtins_, "__name__": "policy_module", "params": tuple(params)}
    exec(code, namespace)
    policy = namespace.get("policy")
    if not callable(policy):
        raise ForbiddenProgram("invalid: no callable `policy` in the program")
    return policy


def load_or_explain(skeleton: str, allowed_imports: Sequence[str], params: Sequence[float]) -> tuple[Callable[..., object] | None, str | None]:
    """`load_policy`, with a failure turned into its stored reason: `(policy, None)` or `(None, reason)`."""
    try:
        return load_policy(skeleton, allowed_imports, params), None
    except ForbiddenProgram as error:
        return None, str(error)
    except BaseException as error:  # module-level code of an untrusted program
        return None, describe_exception(error, " (at import)")
