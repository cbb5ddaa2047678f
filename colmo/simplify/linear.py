"""Collecting a sum's like terms: the simplifier's candidate for sums that mutation grew term by term.

Mutation writes sums such as `a + 1.663 * (0.3931 - b + 1.142 * b)`: the same subexpression
twice with different constants, and a constant factor over a sum. `collected_sum` reads a sum of
terms, each a subexpression times a number (`c * e`, `e * c`, `e / c`, `-e`, or a number alone),
and writes it with each subexpression once, its coefficients added, the numbers added into one:
`a + 0.6537 + 0.2361 * b`; a constant factor over an inner sum is distributed over that sum's
terms or kept in front of it, whichever writes the whole smaller. Exact but for the
constants' rounding to what a person reads; a subexpression that is not a number (a list's `+`
concatenates) or that differs from call to call would make it wrong, so, like every candidate,
it is scored before it is kept.
"""

from __future__ import annotations

import ast
import math
from typing import Optional

from colmo.astutil import is_number_literal, negated, node_count, number_literal
from colmo.program import round_significant

_Terms = dict[str, tuple[float, Optional[ast.expr]]]  # by `ast.dump` of the subexpression ("" for the number)


def _number(node: ast.expr) -> Optional[float]:
    if not is_number_literal(node):
        return None
    value = ast.literal_eval(node)
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else None


def _is_sum(node: ast.expr) -> bool:
    return isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub))


def _add_terms(node: ast.expr, scale: float, terms: _Terms, distribute: bool, top: bool = True) -> None:
    """Add `scale * node`'s terms to `terms`; a constant factor over a sum inside it is
    distributed over that sum's terms, or (not `distribute`) kept as the coefficient of the sum."""
    if _is_sum(node) and (top or distribute):
        _add_terms(node.left, scale, terms, distribute, top)
        _add_terms(node.right, -scale if isinstance(node.op, ast.Sub) else scale, terms, distribute, top)
        return
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        _add_terms(node.operand, -scale if isinstance(node.op, ast.USub) else scale, terms, distribute, top)
        return
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Mult, ast.Div)):
        right = _number(node.right)
        left = _number(node.left) if isinstance(node.op, ast.Mult) else None
        if right is not None and (right != 0 or isinstance(node.op, ast.Mult)):
            _add_terms(node.left, scale * right if isinstance(node.op, ast.Mult) else scale / right, terms, distribute, top=False)
            return
        if left is not None:
            _add_terms(node.right, scale * left, terms, distribute, top=False)
            return
    value = _number(node)
    key = "" if value is not None else ast.dump(node)
    coefficient, expression = terms.get(key, (0.0, None if value is not None else node))
    terms[key] = (coefficient + (scale * value if value is not None else scale), expression)


def _term(coefficient: float, expression: Optional[ast.expr]) -> ast.expr:
    """`|coefficient| * expression` (the sign goes to the sum), or the number alone."""
    magnitude = number_literal(round_significant((abs(coefficient),))[0])
    if expression is None:
        return magnitude
    return expression if math.isclose(abs(coefficient), 1.0) else ast.BinOp(magnitude, ast.Mult(), expression)


def collected_sum(node: ast.expr) -> Optional[ast.expr]:
    """`node`, a sum or a constant times one, with its like terms collected and its constants
    added (see the module docstring), the constant factors over its inner sums distributed or
    kept, whichever is smaller; None unless that is smaller than `node` (`node_count`)."""
    if not isinstance(node, ast.BinOp) or not isinstance(node.op, (ast.Add, ast.Sub, ast.Mult, ast.Div)):
        return None
    written = [_sum_of(terms) for terms in (_terms(node, distribute) for distribute in (True, False)) if terms is not None]
    smallest = min(written, key=node_count, default=None)
    return smallest if smallest is not None and node_count(smallest) < node_count(node) else None


def _terms(node: ast.expr, distribute: bool) -> Optional[list[tuple[float, Optional[ast.expr]]]]:
    """The sum's terms (coefficient, subexpression; None for the number), those that round to 0
    left out; None if a coefficient is not finite."""
    terms: _Terms = {}
    _add_terms(node, 1.0, terms, distribute)
    if not all(math.isfinite(coefficient) for coefficient, _ in terms.values()):
        return None
    return [(coefficient, expression) for coefficient, expression in terms.values() if round_significant((coefficient,))[0] != 0.0]


def _sum_of(terms: list[tuple[float, Optional[ast.expr]]]) -> ast.expr:
    """The sum of `terms` as a person writes it: signs between the terms, the first on its number."""
    if not terms:
        return number_literal(0.0)
    (coefficient, expression), *rest = terms
    total = _term(coefficient, expression)
    if coefficient < 0:
        total = negated(total)
    for coefficient, expression in rest:
        total = ast.BinOp(total, ast.Add() if coefficient > 0 else ast.Sub(), _term(coefficient, expression))
    return total


def top_of_sum(node: ast.AST, parent: ast.AST) -> bool:
    """Whether `node` is a sum or a constant times one that is no term of a larger such sum, the
    place `collected_sum` is offered (inner parts of a sum would offer what the whole collects)."""
    if not isinstance(node, ast.BinOp) or not isinstance(node.op, (ast.Add, ast.Sub, ast.Mult, ast.Div)):
        return False
    if isinstance(parent, ast.BinOp) and isinstance(parent.op, (ast.Add, ast.Sub)):
        return False
    if isinstance(parent, ast.UnaryOp) and isinstance(parent.op, (ast.USub, ast.UAdd)):
        return False
    scaled = isinstance(parent, ast.BinOp) and isinstance(parent.op, (ast.Mult, ast.Div))
    return not (scaled and _number(parent.right if parent.left is node else parent.left) is not None)
