"""What the names of a policy program refer to, and which of its expressions are pure or fresh.

The simplifier never runs policy code, so it must know from the code alone which calls it may
evaluate (`np.tanh` on literals, for folding), which expressions it may drop unused (no side
effects), and which values are new objects (so writing into them touches nothing else).
`Scope` answers these for one module: it resolves a name to `numpy`, `math` or a builtin only
if the module binds it exactly once, by an import (or, for a builtin, never), so a variable
called `np` or a `def abs` is never mistaken for the library.

"Pure" means free of side effects: no calls except the functions of the tables below (no
`np.random`, no `out=`) and no assignment expressions, yields or awaits. Removing a pure
expression can only remove an exception it would have raised (say an index out of range).
"""

from __future__ import annotations

import ast
import builtins
import math
from typing import Callable, Optional

import numpy as np

from colmo.astutil import bindings, is_number_literal

# Numeric functions without side effects whose results are plain numbers for number arguments:
# the only functions the folder calls, on literals only.
FOLDABLE = {
    "numpy": frozenset({
        "abs", "absolute", "fabs", "sqrt", "cbrt", "square", "sin", "cos", "tan", "arcsin", "arccos",
        "arctan", "arctan2", "sinh", "cosh", "tanh", "arcsinh", "arccosh", "arctanh", "exp", "exp2",
        "expm1", "log", "log2", "log10", "log1p", "sign", "floor", "ceil", "trunc", "rint", "hypot",
        "deg2rad", "rad2deg", "degrees", "radians", "minimum", "maximum", "fmin", "fmax", "clip",
        "copysign", "power",
    }),
    "math": frozenset({
        "fabs", "sqrt", "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh",
        "asinh", "acosh", "atanh", "exp", "expm1", "log", "log2", "log10", "log1p", "floor", "ceil",
        "trunc", "hypot", "degrees", "radians", "copysign", "pow",
    }),
    "builtins": frozenset({"abs", "min", "max", "float"}),
}
NAMED_CONSTANTS = {"numpy.pi": math.pi, "numpy.e": math.e, "math.pi": math.pi, "math.e": math.e, "math.tau": math.tau}
# Calls without side effects (for removing unused code): the foldable functions and these.
_PURE_EXTRA = {
    "numpy": frozenset({
        "array", "asarray", "zeros", "ones", "full", "empty", "zeros_like", "ones_like", "full_like",
        "eye", "identity", "arange", "linspace", "concatenate", "stack", "hstack", "vstack", "dot",
        "matmul", "sum", "mean", "prod", "min", "max", "amin", "amax", "where", "tile", "repeat",
        "reshape", "outer", "cross", "mod", "fmod", "round", "around", "isfinite", "isnan", "copy",
    }),
    "numpy.linalg": frozenset({"norm", "inv", "det", "solve", "pinv"}),
    "math": frozenset({"isfinite", "isnan", "isclose"}),
    "builtins": frozenset({"int", "bool", "round", "len", "sum", "range", "list", "tuple", "enumerate", "zip", "pow", "divmod"}),
}
# Calls whose result is a new object, so writing into it cannot change anything else.
_FRESH = {
    "numpy": frozenset({
        "array", "zeros", "ones", "full", "empty", "zeros_like", "ones_like", "full_like", "eye", "identity", "arange", "linspace",
        "copy", "concatenate", "stack", "hstack", "vstack",
    }),
    "builtins": frozenset({"list", "float", "int"}),
}
_MODULES = {"numpy": np, "math": math, "builtins": builtins}
NOT_A_LITERAL = object()  # what `Scope.value` returns for an operand that is not a known number


class Scope:
    """Which names of a module are numpy, math or a builtin, for folding and purity."""

    def __init__(self, tree: ast.Module):
        counts: dict[str, int] = {}
        for node in ast.walk(tree):
            for name in bindings(node):
                counts[name] = counts.get(name, 0) + 1
        modules: dict[str, str] = {}
        for statement in tree.body:
            if isinstance(statement, ast.Import):
                for alias in statement.names:
                    if alias.asname:
                        modules[alias.asname] = alias.name
                    elif "." not in alias.name:
                        modules[alias.name] = alias.name
            elif isinstance(statement, ast.ImportFrom) and statement.module and not statement.level:
                for alias in statement.names:
                    if alias.name != "*":
                        modules[alias.asname or alias.name] = f"{statement.module}.{alias.name}"
        # A name bound anywhere else (a variable called `np`, a `def abs`) is not the module.
        self.modules = {name: target for name, target in modules.items() if counts.get(name) == 1}
        self.unbound = {name for name in dir(builtins) if name not in counts}

    def resolve(self, node: ast.AST) -> Optional[str]:
        """The dotted name an expression refers to (`np.linalg.norm` -> 'numpy.linalg.norm'), if known."""
        if isinstance(node, ast.Name):
            if node.id in self.modules:
                return self.modules[node.id]
            return f"builtins.{node.id}" if node.id in self.unbound else None
        if isinstance(node, ast.Attribute):
            owner = self.resolve(node.value)
            return f"{owner}.{node.attr}" if owner else None
        return None

    def _function(self, call: ast.Call, table: dict[str, frozenset[str]]) -> Optional[str]:
        dotted = self.resolve(call.func)
        if dotted is None or "." not in dotted:
            return None
        module, name = dotted.rsplit(".", 1)
        return dotted if name in table.get(module, ()) else None

    def foldable(self, call: ast.Call) -> Optional[Callable[..., object]]:
        """The trusted function a call names, if the folder may call it on literals."""
        dotted = self._function(call, FOLDABLE)
        if dotted is None:
            return None
        module, name = dotted.rsplit(".", 1)
        return getattr(_MODULES[module], name)

    def pure_call(self, call: ast.Call) -> bool:
        return (self._function(call, FOLDABLE) or self._function(call, _PURE_EXTRA)) is not None and not any(k.arg == "out" for k in call.keywords)

    def fresh_call(self, call: ast.Call) -> bool:
        # Builtin min and max return one of their arguments; the other foldable functions compute.
        foldable = self._function(call, FOLDABLE)
        return self._function(call, _FRESH) is not None or foldable not in (None, "builtins.min", "builtins.max")

    def value(self, node: ast.AST) -> object:
        """The number a literal operand stands for (`3.2`, `-1`, `True`, `np.pi`), else `NOT_A_LITERAL`."""
        if is_number_literal(node) or (isinstance(node, ast.Constant) and isinstance(node.value, bool)):
            return ast.literal_eval(node)
        if isinstance(node, (ast.Name, ast.Attribute)) and isinstance(node.ctx, ast.Load):
            return NAMED_CONSTANTS.get(self.resolve(node) or "", NOT_A_LITERAL)
        return NOT_A_LITERAL

    def is_pure(self, node: ast.AST) -> bool:
        for inner in ast.walk(node):
            if isinstance(inner, (ast.Await, ast.Yield, ast.YieldFrom, ast.NamedExpr)):
                return False
            if isinstance(inner, ast.Call) and not self.pure_call(inner):
                return False
        return True

    def is_fresh(self, node: ast.expr) -> bool:
        """`node` evaluates to a new object (so in-place writes to it touch nothing else)."""
        if isinstance(node, ast.Call):
            return self.fresh_call(node)
        return is_number_literal(node) or isinstance(node, (ast.BinOp, ast.List, ast.ListComp, ast.Dict, ast.DictComp)) or (
            isinstance(node, ast.UnaryOp) and not isinstance(node.op, ast.Not)
        )
