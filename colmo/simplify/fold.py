"""Constant folding: numeric subexpressions whose operands are all literals become one literal.

`np.abs(4.4)` -> `4.4`, `2.0 * 3.0` -> `6.0`, `np.pi / 6` -> one literal, `2 > 1` -> `True`,
`x if True else y` -> `x`; `-(-x)` -> `x` where only the value is used (an operand of
arithmetic or of a comparison); `a - -2.5 * x` -> `a + 2.5 * x` (a tuned constant's sign taken
into the operation before it); and an accumulator started from its identity element,
`x = 0.0` then `x += e` (`-=`, or `x = 1.0` then `x *= e`), written `x = e` (`-e`) where nothing
later changes `x` in place (so `x` may be `e` itself). Folding evaluates only literals, with the trusted functions of
`colmo.simplify.scope.FOLDABLE` (never `exec`/`eval`), and follows Python's number semantics,
so integer literals (indices, sizes) stay integers. What would raise or warn at run time
(`1.0 / 0.0`, `np.log(0.0)`), overflow, or give something other than a finite number of
modest size is left for the program to do.
"""

from __future__ import annotations

import ast
import collections
import math
import operator
from typing import Callable, Optional

import numpy as np

from colmo.astutil import is_number_literal, number_literal
from colmo.simplify.scope import NOT_A_LITERAL, Scope

_BINARY = {
    ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
    ast.FloorDiv: operator.floordiv, ast.Mod: operator.mod, ast.Pow: operator.pow,
}
_UNARY = {ast.USub: operator.neg, ast.UAdd: operator.pos, ast.Not: operator.not_, ast.Invert: operator.invert}
_COMPARE = {ast.Lt: operator.lt, ast.LtE: operator.le, ast.Gt: operator.gt, ast.GtE: operator.ge, ast.Eq: operator.eq, ast.NotEq: operator.ne}
_MAX_EXACT_INT = 2**53


def _plain_number(value: object) -> object:
    """`value` as a Python int, float or bool if it is an exact, finite, modest one, else `NOT_A_LITERAL`."""
    if isinstance(value, np.generic) and value.shape == ():
        value = value.item()
    if isinstance(value, bool):
        return value
    if isinstance(value, int):
        return value if abs(value) <= _MAX_EXACT_INT else NOT_A_LITERAL
    if isinstance(value, float):
        return value if math.isfinite(value) else NOT_A_LITERAL
    return NOT_A_LITERAL


def _safe_power(base: object, exponent: object) -> object:
    # Integer powers grow without bound: refuse what could exceed the exact-integer range.
    if isinstance(base, int) and isinstance(exponent, int) and exponent > 0 and abs(base) > 1 and exponent * abs(base).bit_length() > 53:
        return NOT_A_LITERAL
    return operator.pow(base, exponent)


def undouble(node: ast.expr) -> ast.expr:
    """`-(-x)` -> `x`, for an operand whose value is all that is used."""
    while isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub) and isinstance(node.operand, ast.UnaryOp) and isinstance(node.operand.op, ast.USub):
        node = node.operand.operand
    return node


class Fold(ast.NodeTransformer):
    """Bottom-up constant folding of a module whose names `scope` resolves (module docstring)."""

    def __init__(self, scope: Scope, named: bool = True):
        """`named`: also fold the named constants (`np.pi`); without, literals only, so that
        `2 * math.pi` stays as a person wrote it."""
        self.scope, self.named = scope, named

    def _evaluate(self, function: Callable[..., object], *operands: ast.AST) -> Optional[ast.expr]:
        if not self.named and not all(is_number_literal(o) or isinstance(o, ast.Constant) for o in operands):
            return None
        values = [self.scope.value(operand) for operand in operands]
        if any(value is NOT_A_LITERAL for value in values):
            return None
        try:
            with np.errstate(all="raise"):
                result = _plain_number(function(*values))
        except (ArithmeticError, ValueError, TypeError, FloatingPointError):
            return None  # the program raises or warns here at run time: leave that to it
        return None if result is NOT_A_LITERAL else number_literal(result)

    def visit_BinOp(self, node: ast.BinOp) -> ast.expr:
        self.generic_visit(node)
        node.left, node.right = undouble(node.left), undouble(node.right)
        function = _safe_power if isinstance(node.op, ast.Pow) else _BINARY.get(type(node.op))
        return (function and self._evaluate(function, node.left, node.right)) or _sign_taken_out(node)

    def visit_UnaryOp(self, node: ast.UnaryOp) -> ast.expr:
        self.generic_visit(node)
        if is_number_literal(node):
            return node
        return self._evaluate(_UNARY[type(node.op)], node.operand) or node

    def visit_Call(self, node: ast.Call) -> ast.expr:
        self.generic_visit(node)
        function = self.scope.foldable(node)
        if function is None or node.keywords or any(isinstance(arg, ast.Starred) for arg in node.args):
            return node
        return self._evaluate(function, *node.args) or node

    def visit_Compare(self, node: ast.Compare) -> ast.expr:
        self.generic_visit(node)
        if not all(type(op) in _COMPARE for op in node.ops):
            return node  # `is` and `in` may depend on identity, not value
        node.left, node.comparators = undouble(node.left), [undouble(c) for c in node.comparators]

        def chain(*values: object) -> bool:
            return all(_COMPARE[type(op)](a, b) for op, a, b in zip(node.ops, values, values[1:]))

        return self._evaluate(chain, node.left, *node.comparators) or node

    def visit_BoolOp(self, node: ast.BoolOp) -> ast.expr:
        self.generic_visit(node)
        values = list(node.values)
        # Only leading constants decide anything: `x and True` still returns x's value.
        while len(values) > 1 and isinstance(values[0], ast.Constant):
            if bool(values[0].value) == isinstance(node.op, ast.And):
                values.pop(0)  # a true `and` operand (false `or` operand) passes on to the next
            else:
                return values[0]  # it is the result; the rest never runs
        return values[0] if len(values) == 1 else ast.BoolOp(node.op, values)

    def visit_IfExp(self, node: ast.IfExp) -> ast.expr:
        self.generic_visit(node)
        if isinstance(node.test, ast.Constant):
            return node.body if node.test.value else node.orelse
        return node


def _sign_taken_out(node: ast.BinOp) -> ast.BinOp:
    """`a - -2.5 * x` -> `a + 2.5 * x`, `a + -2.5` -> `a - 2.5`: a negative float literal leading
    the right operand of a sum or difference is written as the opposite operation (tuned constants
    come out negative where the program subtracts). Exact: negation is, in every rounding."""
    if not isinstance(node.op, (ast.Add, ast.Sub)):
        return node
    holder, field = node, "right"  # where the leading factor stands: down the left side of a product
    while isinstance(factor := getattr(holder, field), ast.BinOp) and isinstance(factor.op, ast.Mult):
        holder, field = factor, "left"
    leading = getattr(holder, field)
    if not (is_number_literal(leading) and isinstance(leading, ast.UnaryOp) and isinstance(leading.operand.value, float)):  # type: ignore[attr-defined]
        return node
    setattr(holder, field, leading.operand)
    node.op = ast.Sub() if isinstance(node.op, ast.Add) else ast.Add()
    return node


_IDENTITIES = {ast.Add: 0, ast.Sub: 0, ast.Mult: 1}


def fold_accumulator_starts(tree: ast.Module) -> None:
    """`x = 0.0; x += e` -> `x = e` (module docstring), in every block of `tree`."""
    augmented = collections.Counter(
        node.target.id for node in ast.walk(tree) if isinstance(node, ast.AugAssign) and isinstance(node.target, ast.Name)
    )
    # Changed in place beyond the one update folded: `x` would then change `e` itself.
    changed_in_place = {name for name, count in augmented.items() if count > 1} | {
        target.value.id for node in ast.walk(tree) for target in getattr(node, "targets", [getattr(node, "target", None)])
        if isinstance(target, (ast.Subscript, ast.Attribute)) and isinstance(target.value, ast.Name)
    }
    for node in ast.walk(tree):
        for field in ("body", "orelse", "finalbody"):
            block = getattr(node, field, None)
            if isinstance(block, list):
                setattr(node, field, _folded_block(block, changed_in_place))


def _folded_block(block: list[ast.stmt], changed_in_place: set[str]) -> list[ast.stmt]:
    folded: list[ast.stmt] = []
    for statement in block:
        start = folded[-1] if folded else None
        if (
            isinstance(statement, ast.AugAssign) and isinstance(statement.target, ast.Name) and type(statement.op) in _IDENTITIES
            and isinstance(start, ast.Assign) and len(start.targets) == 1 and isinstance(start.targets[0], ast.Name)
            and start.targets[0].id == statement.target.id and statement.target.id not in changed_in_place
            and is_number_literal(start.value) and ast.literal_eval(start.value) == _IDENTITIES[type(statement.op)]
            and statement.target.id not in {n.id for n in ast.walk(statement.value) if isinstance(n, ast.Name)}
        ):
            value = ast.UnaryOp(ast.USub(), statement.value) if isinstance(statement.op, ast.Sub) else statement.value
            folded[-1] = ast.Assign([ast.Name(statement.target.id, ast.Store())], value)
            continue
        folded.append(statement)
    return folded
