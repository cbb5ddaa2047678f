"""The static check: what a policy program may not contain, decided on its AST before it runs.

It runs in the coordinator before a program is submitted and again in the worker before the
program is compiled. It is the first layer, not the last: numpy can hand a program raw memory
in ways no AST check can enumerate, so the worker's OS confinement (`colmo.sandbox.confine`)
and the referee (`colmo.sandbox.referee`) hold when it misses something.

Refused:
- imports other than numpy (its `linalg`, `random`, `fft`, `emath` submodules), math and what
  the spec declares; relative imports;
- unsafe builtins (`open`, `exec`, `getattr`, `type`, `vars`, `object`, ...), unless the program
  binds the name itself (`dir = np.sign(v)` is a variable);
- names starting with `__`; attributes starting with `_` (dunders, internals such as `np._core`);
- attributes that read or write files, unpickle, reach native code or internals, or change
  state the evaluator relies on (`np.load`, `arr.tofile`, `arr.ctypes`, `set_bit_generator`,
  ...), and frame, generator and code attributes (`gi_frame`, `f_globals`, `co_code`, ...);
- `str.format`/`format_map`, whose `{0.__class__}` fields walk attributes unchecked;
- raw-memory primitives: object dtypes in any literal form (any string numpy reads as a dtype
  holding objects: `'O'`, `'object'`, `[('a', 'O')]`, `('O', (1,))`; `object`, `object_`), the
  `buffer=` keyword and the array constructors that take a buffer (`np.ndarray(...)`,
  `recarray`, `chararray`, `matrix`, `memmap`; `isinstance(x, np.ndarray)` stays allowed),
  `resize` (frees a buffer under live views with `refcheck=False`), `setflags`; byte views of
  a buffer (`.data`, `.cast`, `.tobytes`, `memoryview`: of an object array they expose its
  pointers) and arrays over one (`frombuffer`: over an object array, a writable array of its
  pointers); the `isinstance` exception holds only while `isinstance` is the builtin, and
  `ndarray` is never a name of its own (`from numpy import ndarray`, or `*`);
- decorators (a decorator can rebind a function's name to a shared object, whose attributes
  the assignment rule below would then allow), class definitions, `global`, `nonlocal`;
- attribute assignment or deletion except on the program's own functions (`policy.state = 0`),
  so `np.clip = ...` is refused.
"""

from __future__ import annotations

import ast
import warnings
from typing import Collection, Sequence

import numpy as np

from colmo import astutil
from colmo.astutil import IDENTIFIER_FIELDS, bindings
from colmo.errors import failure_reason

FORBIDDEN_NAMES = frozenset({
    "open", "exec", "eval", "compile", "globals", "locals", "vars", "getattr", "setattr", "delattr",
    "input", "breakpoint", "exit", "quit", "help", "memoryview", "classmethod", "staticmethod",
    "super", "type", "object", "dir",
})
FORBIDDEN_ATTRIBUTES = frozenset({
    "load", "loads", "loadtxt", "genfromtxt", "fromfile", "fromregex", "tofile", "dump", "save",
    "savez", "savez_compressed", "savetxt", "memmap", "DataSource", "ctypes", "cffi", "ctypeslib",
    "lib", "core", "testing", "test", "f2py", "distutils", "info", "show_config", "show_runtime",
    "setbufsize", "seterrcall", "set_bit_generator", "get_bit_generator", "as_strided", "system",
    "popen", "format", "format_map", "mro",
    # raw memory
    "object_", "resize", "setflags", "recarray", "chararray", "matrix", "record",
    # byte views of an array's buffer, and arrays over one: of an object array, they read and
    # write its pointers (np.frombuffer(np.array([None, x]), np.uint64) is writable)
    "data", "cast", "tobytes", "tostring", "getbuffer", "frombuffer",
})
# Array constructors that take a buffer: allowed only as the class in isinstance(x, np.ndarray).
_BUFFER_CLASSES = frozenset({"ndarray"})
FORBIDDEN_KEYWORDS = frozenset({"buffer", "refcheck"})
_FRAME_ATTRIBUTE_PREFIXES = ("gi_", "cr_", "ag_", "f_", "tb_", "co_")
NUMPY_SUBMODULES = frozenset({"linalg", "random", "fft", "emath"})
_MAX_DTYPE_TEXT = 200  # longer strings are not dtypes numpy would read: no need to ask it


class ForbiddenProgram(ValueError):
    """The program failed the static check; the message is the stored failure reason."""


def module_allowed(name: str, allowed: Collection[str]) -> bool:
    parts = name.split(".")
    if parts[0] not in allowed or any(part.startswith("_") for part in parts):
        return False
    return parts[0] != "numpy" or len(parts) == 1 or (len(parts) == 2 and parts[1] in NUMPY_SUBMODULES)


def attribute_allowed(name: str) -> bool:
    return not (name.startswith("_") or name in FORBIDDEN_ATTRIBUTES or name.startswith(_FRAME_ATTRIBUTE_PREFIXES))


def _is_object_dtype(text: str) -> bool:
    """Whether numpy reads `text` as a dtype that holds Python objects."""
    if len(text) > _MAX_DTYPE_TEXT:
        return False
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return np.dtype(text).hasobject
        except (TypeError, ValueError, SyntaxError):
            return False


def _bindings(tree: ast.AST) -> tuple[set[str], set[str]]:
    """The names the program defines with `def`, and the names it binds any other way (assignment,
    `for`, `with ... as`, `:=`, imports, parameters, `except ... as`, match captures, `global`,
    comprehension targets): a builtin's name is the builtin only where neither binds it."""
    functions, others = set(), set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            functions.add(node.name)
        else:
            others.update(bindings(node))
    return functions, others


class _Checker(ast.NodeVisitor):
    """Finds the first forbidden node, in source order of a depth-first walk."""

    def __init__(self, allowed: frozenset[str], own_functions: set[str], bound: set[str]):
        self.allowed = allowed
        self.own_functions = own_functions  # names that can only refer to a function the program defines
        self.bound = bound  # every name the program binds
        self.problem: str | None = None

    def visit(self, node: ast.AST) -> None:
        if self.problem is None:
            self.problem = self._problem(node)
        if self.problem is None:
            super().visit(node)

    def visit_Call(self, node: ast.Call) -> None:
        # isinstance(x, np.ndarray): the class is only compared against, never called; only the
        # builtin isinstance does that, so the exception holds only while the program leaves the
        # name unbound, and everything else in the call (keywords included) is checked as usual.
        if isinstance(node.func, ast.Name) and node.func.id == "isinstance" and "isinstance" not in self.bound and len(node.args) == 2:
            self.visit(node.func)
            self.visit(node.args[0])
            classes = node.args[1].elts if isinstance(node.args[1], ast.Tuple) else [node.args[1]]
            for cls in classes:
                self.visit(cls.value if isinstance(cls, ast.Attribute) and cls.attr in _BUFFER_CLASSES else cls)
            for keyword in node.keywords:
                self.visit(keyword)
            return
        self.generic_visit(node)

    def _problem(self, node: ast.AST) -> str | None:
        if isinstance(node, ast.Import):
            return next((f"import {a.name}" for a in node.names if not module_allowed(a.name, self.allowed)), None)
        if isinstance(node, ast.ImportFrom):
            module = "." * node.level + (node.module or "")
            if node.level or not module_allowed(module, self.allowed):
                return f"import {module}"
            refused = (a.name for a in node.names if a.name != "*" and (not attribute_allowed(a.name) or a.name in _BUFFER_CLASSES))
            return next((f"import {module}.{name}" for name in refused), None)
        if isinstance(node, ast.Name):
            # A buffer class under a name of its own comes from a star import (`def f(ndarray=ndarray)`
            # binds the name, and its default is the class): refused whatever the program binds.
            if node.id.startswith("__") or node.id in _BUFFER_CLASSES or (node.id in FORBIDDEN_NAMES and node.id not in self.bound):
                return node.id
            return None
        if isinstance(node, ast.Attribute):
            if not attribute_allowed(node.attr) or node.attr in _BUFFER_CLASSES:
                return f".{node.attr}"
            if not isinstance(node.ctx, ast.Load) and not (isinstance(node.value, ast.Name) and node.value.id in self.own_functions):
                return f"{'deletion of' if isinstance(node.ctx, ast.Del) else 'assignment to'} {ast.unparse(node)}"
            return None
        if isinstance(node, ast.keyword) and node.arg in FORBIDDEN_KEYWORDS:
            return f"keyword {node.arg}="
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and _is_object_dtype(node.value):
            return f"object dtype {node.value!r}"
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.decorator_list:
            return f"decorator on {node.name}"
        if isinstance(node, ast.MatchClass):  # `case C(attr=x)` reads C's attribute `attr`
            return next((f".{name}" for name in node.kwd_attrs if not attribute_allowed(name)), None)
        if isinstance(node, (ast.Global, ast.Nonlocal)):
            return f"{type(node).__name__.lower()} statement"
        if isinstance(node, ast.ClassDef):
            return f"class definition ({node.name})"
        identifier = getattr(node, IDENTIFIER_FIELDS.get(type(node), ""), None)
        if isinstance(node, ast.alias):
            identifier = node.asname
        return identifier if isinstance(identifier, str) and identifier.startswith("__") else None


def check_tree(tree: ast.Module, allowed_imports: Sequence[str]) -> None:
    """Reject a parsed program that imports or touches what a policy has no business with
    (module docstring). Raises `ForbiddenProgram`, whose message is the failure reason."""
    functions, others = _bindings(tree)
    checker = _Checker(frozenset(allowed_imports), functions - others, functions | others)
    try:
        checker.visit(tree)
    except RecursionError:
        raise ForbiddenProgram("syntax error: too deeply nested to check") from None
    if checker.problem:
        raise ForbiddenProgram(failure_reason(f"forbidden: {checker.problem}"))


def parse_program(code: str) -> ast.Module:
    """The program's AST; `ForbiddenProgram` with a `syntax error: ...` reason if it has none."""
    try:
        return astutil.parse(code)
    except SyntaxError as error:
        line = f" (line {error.lineno})" if error.lineno else ""
        raise ForbiddenProgram(failure_reason(f"syntax error: {error.msg}{line}")) from None
    except (RecursionError, MemoryError, ValueError) as error:  # absurd nesting; null bytes (some versions)
        raise ForbiddenProgram(f"syntax error: {str(error) or 'too deeply nested to parse'}") from None


def check_program(code: str, allowed_imports: Sequence[str]) -> None:
    """`check_tree` for source code."""
    check_tree(parse_program(code), allowed_imports)
