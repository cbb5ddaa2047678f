"""Turning a policy program into a parametric skeleton, its structure key, and back into readable code.

A policy program is a Python module (imports, constants, helpers) that defines `policy(obs)`.
`parametrize` replaces every tunable numeric literal with `params[i]` (i in source order) so a
gradient-free optimizer can tune the constants (paper Sec. IV-C), and `instantiate` writes values
back. The skeleton reads `params` as a free global: `exec(skeleton, {"params": values, ...})`.
The structure key is the sha256 of the AST dump of the skeleton's canonical form
(`colmo.canonical`), so programs that differ only in tunable constants, comments, docstrings,
unused imports or formatting share a key, and so do programs whose constants reach the same
functions when tuned (`c * (a * x + b * y)` and `a * x + b * y`); a changed index, name or
operator gives a new one.

Which literals are tunable
--------------------------
Every int or float literal is a parameter, sign included (`-3.2` and `+3` are one parameter
each), except where the program needs an exact integer: a tuned 6.03 there would crash the
program or change its structure. Integer literals are structural when they appear
  * anywhere in a subscript: `obs[47]`, `obs[0:12]`, `x[0::3]`, `obs[-1]`, `a[0, 1]`, `obs[n - 1]`;
  * anywhere in the arguments of calls that take shapes, counts, indices or digits, by the last
    name of the callee (`_INTEGER_CALLS`: `np.zeros`, `np.full`, `np.eye`, `.reshape`, `range`,
    `np.tile`, `np.repeat`, `np.roll`, `round`, `pow`, `enumerate`, `np.linspace`,
    `np.random.normal`, ...);
  * as direct arguments of attribute calls that take an axis (`np.sum(x, 0)`, `x.max(1)`); the
    builtins `max(x, 0)`, `min`, `sum` take values, so their literals stay tunable;
  * in keyword arguments that name a shape, size, axis, count or precision (`_INTEGER_KEYWORDS`);
  * as exponents (`x ** 2`), divisors of `%` and `//` (`i % 2`), operands of bitwise operators,
    repetition counts (`[0.0] * 12`), operands of `==`, `!=`, `in`, `not in`, and dict keys;
  * as values bound to a variable that is itself used in such a position (`n = 12; obs[:n]`),
    followed to a fixpoint. Names are tracked across the whole module, not per scope, which errs
    on the structural side.
Float literals stay tunable in all those places (a float is never a shape, index or count):
`np.full(12, 0.5)` tunes 0.5, `x ** 0.5` tunes 0.5, `np.random.normal(scale=0.04, size=12)` tunes
0.04. Never tunable: booleans, strings, None, complex numbers, and anything in decorators, type
annotations, f-strings, match patterns and imports.

Values are floats, and `instantiate` always writes float literals (`2` comes back as `2.0`),
which is exactly what running the skeleton with `params` computes.

The placeholder is always the global `params`. A program that uses the name `params` itself
keeps it under a fresh name (`params_`, or more underscores until unused) in the skeleton.
"""

from __future__ import annotations

import ast
import hashlib
from dataclasses import dataclass
from typing import Sequence

from colmo import astutil
from colmo.astutil import (
    bound_names,
    identifiers,
    is_number_literal,
    node_count,
    number_literal,
    rename,
    replace_nodes,
    stored_names,
    strip_docstrings,
)
from colmo.canonical import canonical_form

PARAMS_NAME = "params"
# The definition of `structure_key`, recorded in a run's store: a store of another version has its
# keys computed again when it is resumed, else the structures it holds would be met as new ones.
STRUCTURE_KEY_VERSION = 2  # 2: the canonical form (constants that add no freedom are one)
DISPLAY_DIGITS = 4  # significant digits of the constants in the code a person reads

# Callees whose integer arguments are shapes, counts, indices or digits (matched by last name).
_INTEGER_CALLS = frozenset({
    "zeros", "ones", "empty", "full", "eye", "identity", "reshape", "resize", "range", "arange",
    "linspace", "logspace", "geomspace", "slice", "tile", "repeat", "roll", "round", "around",
    "pow", "power", "enumerate", "normal", "uniform", "randint", "rand", "randn", "random",
    "standard_normal", "choice", "seed", "default_rng", "diag", "split", "array_split", "take",
})
# Attribute calls whose bare integer arguments are axes: np.sum(x, 0), x.max(1).
_AXIS_CALLS = frozenset({
    "sum", "mean", "max", "min", "amax", "amin", "argmax", "argmin", "prod", "std", "var",
    "median", "cumsum", "cumprod", "any", "all", "concatenate", "stack", "expand_dims",
    "squeeze", "flip", "sort", "argsort", "diff", "norm", "transpose", "swapaxes", "moveaxis",
})
_INTEGER_KEYWORDS = frozenset({
    "size", "shape", "newshape", "axis", "axes", "num", "ndmin", "ndigits", "decimals",
    "start", "repeats", "reps", "shift", "k", "n", "ord", "seed", "minlength",
})
_BITWISE_OPS = (ast.LShift, ast.RShift, ast.BitAnd, ast.BitOr, ast.BitXor)
_DISCRETE_COMPARISONS = (ast.Eq, ast.NotEq, ast.In, ast.NotIn)


class ProgramError(ValueError):
    """The program cannot be parametrized or instantiated; the message is one line."""


@dataclass(frozen=True)
class ParametricProgram:
    skeleton: str  # the module with each tunable literal replaced by params[i]
    values: tuple[float, ...]  # the replaced literals, in source order
    key: str  # sha256 of the skeleton's AST: equal for programs that differ only in constants

    @property
    def n_params(self) -> int:
        return len(self.values)


def parametrize(code: str, function_name: str = "policy") -> ParametricProgram:
    """Split `code` into a skeleton over `params` and the values of its tunable literals."""
    try:
        return _parametrize(code, function_name)
    except (RecursionError, MemoryError):  # the parser and AST visitors recurse per nesting level
        raise ProgramError("the program is nested too deeply to parse") from None


def _parametrize(code: str, function_name: str) -> ParametricProgram:
    tree = _parse(code)
    if astutil.function(tree, function_name) is None:
        raise ProgramError(f"no function named '{function_name}'")
    strip_docstrings(tree)
    _drop_unused_imports(tree)
    names = identifiers(tree)
    if PARAMS_NAME in names:
        fresh = PARAMS_NAME + "_"
        while fresh in names:
            fresh += "_"
        rename(tree, {PARAMS_NAME: fresh})
    literals = _tunable_literals(tree)
    slots = {id(node): _slot(i) for i, node in enumerate(literals)}
    skeleton = ast.unparse(replace_nodes(tree, slots))
    return ParametricProgram(skeleton, tuple(float(_value(node)) for node in literals), structure_key(skeleton))


def _drop_unused_imports(tree: ast.Module) -> None:
    """Module-level imports nothing uses are not structure: a copy of a program that leaves out
    its unused `import numpy as np` is the same program."""
    used = {node.id for node in ast.walk(tree) if isinstance(node, ast.Name)}
    tree.body = [s for s in tree.body if not isinstance(s, (ast.Import, ast.ImportFrom)) or set(bound_names(s)) & used]


def instantiate(skeleton: str, values: Sequence[float], digits: int | None = None) -> str:
    """The skeleton with `params[i]` replaced by `values[i]` as a float literal.

    digits=None writes each value's repr, so running the result is bit-identical to running the
    skeleton with `params = values`; digits=4 rounds to 4 significant digits for display
    (9.437, -12.24, 0.0004321, 1234.0: `round_significant`)."""
    if digits is not None:
        values = round_significant(values, digits)
    tree = _parse(skeleton)
    slots = [node for node in ast.walk(tree) if _is_slot(node)]
    needed = 1 + max((slot.slice.value for slot in slots), default=-1)
    if needed != len(values):
        raise ProgramError(f"skeleton takes {needed} parameters, got {len(values)} values")
    literals = {id(slot): number_literal(float(values[slot.slice.value])) for slot in slots}
    return ast.unparse(replace_nodes(tree, literals))


def _line_count(tree: ast.Module) -> int:
    return sum(1 for line in ast.unparse(tree).splitlines() if line.strip())


@dataclass(frozen=True)
class ProgramSize:
    """How big a program is to read: lines (non-blank, once docstrings and comments are gone, as
    `ast.unparse` lays it out, so the count does not depend on the author's wrapping), AST nodes
    (`astutil.node_count`, docstrings excluded; a signed literal is one node) and tunable
    constants. The one size colmo reports: the store, the search, `colmo.optimize` and
    `colmo.simplify` all use `measure`."""

    lines: int
    nodes: int
    params: int


def measure(code: str) -> ProgramSize:
    tree = _parse(code)
    strip_docstrings(tree)
    return ProgramSize(_line_count(tree), node_count(tree), len(_tunable_literals(tree)))


def structure_key(skeleton: str) -> str:
    """sha256 hex of the AST dump (positions excluded, so formatting does not count) of the
    skeleton's canonical form (`colmo.canonical`: constants that add no freedom merged)."""
    tree = canonical_form(_parse(skeleton), _is_slot)
    strip_docstrings(tree)
    _drop_unused_imports(tree)  # `np.pi * c` became `c`
    return hashlib.sha256(ast.dump(tree).encode()).hexdigest()


def _parse(code: str) -> ast.Module:
    try:
        return astutil.parse(code)
    except SyntaxError as error:
        raise ProgramError(f"syntax error at line {error.lineno}: {error.msg}") from None
    except ValueError as error:  # e.g. null bytes in the source
        raise ProgramError(f"unparseable source: {error}") from None


def _value(node: ast.expr) -> int | float:
    if isinstance(node, ast.UnaryOp):
        return -node.operand.value if isinstance(node.op, ast.USub) else node.operand.value
    return node.value


def _is_int_literal(node: ast.AST) -> bool:
    return is_number_literal(node) and isinstance(_value(node), int)


def _is_sequence(node: ast.AST) -> bool:
    return isinstance(node, (ast.List, ast.Tuple, ast.ListComp)) or (isinstance(node, ast.Constant) and isinstance(node.value, str))


class _Literals(ast.NodeVisitor):
    """One pass over a module: the tunable literals, and the names met in integer positions."""

    def __init__(self, integer_names: set[str]):
        self.integer_names = integer_names  # names known (from earlier passes) to hold integers
        self.seen_names: set[str] = set()
        self.tunable: list[ast.expr] = []
        self._integer_depth = 0

    def _integral(self, node: ast.AST) -> None:
        self._integer_depth += 1
        self.visit(node)
        self._integer_depth -= 1

    def _bound_value(self, names: set[str], value: ast.AST) -> None:
        if names & self.integer_names:
            self._integral(value)
        else:
            self.visit(value)

    def _literal(self, node: ast.expr) -> None:
        if not (self._integer_depth and isinstance(_value(node), int)):
            self.tunable.append(node)

    def visit_Constant(self, node: ast.Constant) -> None:
        if is_number_literal(node):
            self._literal(node)

    def visit_UnaryOp(self, node: ast.UnaryOp) -> None:
        if is_number_literal(node):
            self._literal(node)
        else:
            self.generic_visit(node)

    def visit_Name(self, node: ast.Name) -> None:
        if self._integer_depth:
            self.seen_names.add(node.id)

    def visit_Subscript(self, node: ast.Subscript) -> None:
        self.visit(node.value)
        self._integral(node.slice)

    def visit_Call(self, node: ast.Call) -> None:
        self.visit(node.func)
        callee = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", None)
        takes_axis = isinstance(node.func, ast.Attribute) and callee in _AXIS_CALLS
        for arg in node.args:
            if callee in _INTEGER_CALLS:
                self._integral(arg)
            elif not (takes_axis and (_is_int_literal(arg) or isinstance(arg, ast.Tuple) and all(map(_is_int_literal, arg.elts)))):
                self.visit(arg)
        for keyword in node.keywords:
            if callee in _INTEGER_CALLS or keyword.arg in _INTEGER_KEYWORDS:
                self._integral(keyword.value)
            else:
                self.visit(keyword.value)

    def visit_BinOp(self, node: ast.BinOp) -> None:
        if isinstance(node.op, (ast.Pow, ast.Mod, ast.FloorDiv)):
            self.visit(node.left)
            self._integral(node.right)
        elif isinstance(node.op, _BITWISE_OPS):
            self._integral(node.left)
            self._integral(node.right)
        elif isinstance(node.op, ast.Mult) and _is_sequence(node.left):
            self.visit(node.left)
            self._integral(node.right)
        elif isinstance(node.op, ast.Mult) and _is_sequence(node.right):
            self._integral(node.left)
            self.visit(node.right)
        else:
            self.generic_visit(node)

    def visit_Compare(self, node: ast.Compare) -> None:
        for i, operand in enumerate([node.left, *node.comparators]):
            if any(isinstance(op, _DISCRETE_COMPARISONS) for op in node.ops[max(i - 1, 0) : i + 1]):
                self._integral(operand)
            else:
                self.visit(operand)

    def visit_Dict(self, node: ast.Dict) -> None:
        for key, value in zip(node.keys, node.values):
            if key is not None:  # None: a **mapping entry
                self._integral(key)
            self.visit(value)

    def visit_Assign(self, node: ast.Assign) -> None:
        for target in node.targets:
            self.visit(target)
        self._bound_value(stored_names(node.targets), node.value)

    def visit_AugAssign(self, node: ast.AugAssign) -> None:
        self.visit(node.target)
        self._bound_value(stored_names([node.target]), node.value)

    def visit_AnnAssign(self, node: ast.AnnAssign) -> None:
        self.visit(node.target)
        if node.value is not None:
            self._bound_value(stored_names([node.target]), node.value)

    def visit_NamedExpr(self, node: ast.NamedExpr) -> None:
        self._bound_value({node.target.id}, node.value)

    def visit_For(self, node: ast.For | ast.AsyncFor) -> None:
        self.visit(node.target)
        self._bound_value(stored_names([node.target]), node.iter)
        for statement in node.body + node.orelse:
            self.visit(statement)

    visit_AsyncFor = visit_For

    def visit_comprehension(self, node: ast.comprehension) -> None:
        self.visit(node.target)
        self._bound_value(stored_names([node.target]), node.iter)
        for condition in node.ifs:
            self.visit(condition)

    def visit_arguments(self, node: ast.arguments) -> None:
        positional = node.posonlyargs + node.args
        with_defaults = list(zip(positional[len(positional) - len(node.defaults) :], node.defaults))
        with_defaults += [(arg, d) for arg, d in zip(node.kwonlyargs, node.kw_defaults) if d is not None]
        for arg, default in with_defaults:
            self._bound_value({arg.arg}, default)

    def visit_FunctionDef(self, node: ast.FunctionDef | ast.AsyncFunctionDef) -> None:
        # Decorators and annotations configure the program; they are not control constants.
        self.visit(node.args)
        for statement in node.body:
            self.visit(statement)

    visit_AsyncFunctionDef = visit_FunctionDef

    def visit_ClassDef(self, node: ast.ClassDef) -> None:
        for statement in node.body:
            self.visit(statement)

    def visit_match_case(self, node: ast.match_case) -> None:
        # Patterns must stay literals to remain valid syntax.
        if node.guard is not None:
            self.visit(node.guard)
        for statement in node.body:
            self.visit(statement)

    def visit_arg(self, node: ast.arg) -> None:
        pass  # only an annotation inside

    def visit_JoinedStr(self, node: ast.JoinedStr) -> None:
        pass  # f-string contents only format text


def _tunable_literals(tree: ast.Module) -> list[ast.expr]:
    """Tunable literal nodes in source order; integer names are followed until nothing changes."""
    integer_names: set[str] = set()
    while True:
        finder = _Literals(integer_names)
        finder.visit(tree)
        if finder.seen_names <= integer_names:
            return sorted(finder.tunable, key=lambda node: (node.lineno, node.col_offset))
        integer_names |= finder.seen_names


def _slot(index: int) -> ast.Subscript:
    return ast.Subscript(ast.Name(PARAMS_NAME, ast.Load()), ast.Constant(index), ast.Load())


def _is_slot(node: ast.AST) -> bool:
    return (
        isinstance(node, ast.Subscript)
        and isinstance(node.value, ast.Name)
        and node.value.id == PARAMS_NAME
        and isinstance(node.slice, ast.Constant)
        and type(node.slice.value) is int
    )


def round_significant(values: Sequence[float], digits: int = DISPLAY_DIGITS) -> tuple[float, ...]:
    """`values` rounded to `digits` significant digits, as `instantiate` writes them for display."""
    return tuple(float(f"{v:.{digits}g}") for v in values)
