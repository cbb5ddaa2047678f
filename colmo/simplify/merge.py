"""Merging two terms of a sum that are alike: the simplifier's candidate for mutation's blends.

Mutation's merge crossover writes `0.5 * (r1) + 0.5 * (r2)` of two programs of one island,
often a program and its mutated relative, each result assigned to its own name (`action`,
`action_b`). `merged_terms` writes such a sum as one term when the two are alike but for their
float constants and at most one subexpression: each constant the pair's weighted mean, the
subexpression that differs the weighted sum of the two, the weights' sum in front. It is exact
where the expression is linear in its constants, and otherwise close when the pair is; either
way `colmo.simplify.candidates` offers it as a candidate, and scores decide.
"""

from __future__ import annotations

import ast
import copy
import math
from collections import Counter
from dataclasses import dataclass
from typing import Any, Optional

from colmo.astutil import bindings, is_number_literal, number_literal
from colmo.program import round_significant


def _displayed(value: float) -> float:
    """A constant as a person reads it, and as it is then scored."""
    return round_significant((value,))[0]


def single_definitions(function: ast.FunctionDef | ast.AsyncFunctionDef) -> dict[str, ast.expr]:
    """The names `function`'s body binds once, by a plain assignment among its top-level
    statements, from names the body never binds: each such name's value wherever it is read."""
    bound = Counter(name for statement in function.body for n in ast.walk(statement) for name in bindings(n))
    single: dict[str, ast.expr] = {}
    for statement in function.body:
        if isinstance(statement, ast.Assign) and len(statement.targets) == 1 and isinstance(statement.targets[0], ast.Name):
            reads = {n.id for n in ast.walk(statement.value) if isinstance(n, ast.Name)}
            if bound[statement.targets[0].id] == 1 and not any(bound[name] for name in reads):
                single[statement.targets[0].id] = statement.value
    return single


def _float_value(node: ast.AST) -> Optional[float]:
    """The value of a float literal (a signed one is one literal), else None."""
    value = ast.literal_eval(node) if is_number_literal(node) else None
    return value if isinstance(value, float) else None


def _weighable(node: Any) -> bool:
    """An expression whose value a weight may scale: not a container (its elements are merged
    one by one), nor a constant other than a float (an index, an exponent or a flag)."""
    if not isinstance(node, ast.expr) or isinstance(node, (ast.List, ast.Tuple, ast.Set, ast.Dict, ast.Starred, ast.Slice)):
        return False
    if isinstance(node, ast.Constant) or is_number_literal(node):
        return _float_value(node) is not None
    return True


@dataclass(frozen=True)
class _Blend:
    """Merges two expressions weighted w1 and w2 (w1 + w2 not 0) into one, node by node."""

    w1: float
    w2: float

    def literal(self, a: float, b: float) -> ast.expr:
        return number_literal(_displayed((self.w1 * a + self.w2 * b) / (self.w1 + self.w2)))

    def both(self, x: ast.expr, y: ast.expr) -> ast.expr:
        """`(w1 * x + w2 * y) / (w1 + w2)`, each weight folded into a float literal side."""
        def share(weight: float, node: ast.expr) -> ast.expr:
            fraction = weight / (self.w1 + self.w2)
            value = _float_value(node)
            if value is not None:
                return number_literal(_displayed(fraction * value))
            return ast.BinOp(number_literal(_displayed(fraction)), ast.Mult(), copy.deepcopy(node))
        left, right = share(self.w1, x), share(self.w2, y)
        if isinstance(right, ast.UnaryOp):  # a negative literal: `a - 0.15`, not `a + -0.15`
            return ast.BinOp(left, ast.Sub(), right.operand)
        return ast.BinOp(left, ast.Add(), right)

    def merged(self, x: Any, y: Any) -> Optional[tuple[Any, int]]:
        """x and y merged, and how many subexpressions that differ other than by their float
        constants it had to write as `both` (each counted once, as high in the tree as it
        takes to make them one); None where they differ at a node that is not an expression."""
        first, second = _float_value(x), _float_value(y)
        if first is not None and second is not None:
            return self.literal(first, second), 0
        together = self.field_by_field(x, y)
        if together is not None and together[1] <= 1:
            return together
        if _weighable(x) and _weighable(y):
            return self.both(x, y), 1
        return together

    def field_by_field(self, x: Any, y: Any) -> Optional[tuple[Any, int]]:
        """`merged`, where x and y are nodes of one type (or lists, or plain values) merged field
        by field, never written as `both` at their root."""
        if isinstance(x, list) and isinstance(y, list):
            if len(x) != len(y):
                return None
            items = [self.merged(a, b) for a, b in zip(x, y)]
            if any(item is None for item in items):
                return None
            return [item[0] for item in items], sum(item[1] for item in items)
        if not isinstance(x, ast.AST):
            return (x, 0) if type(x) is type(y) and x == y else None
        if type(x) is not type(y):
            return None
        fields: dict[str, Any] = {}
        differences = 0
        for name in x._fields:
            if isinstance(x, ast.Subscript) and name == "slice" and ast.dump(x.slice) != ast.dump(y.slice):
                return None  # another element read, not another value
            item = self.merged(getattr(x, name, None), getattr(y, name, None))
            if item is None:
                return None
            fields[name], differences = item[0], differences + item[1]
        return type(x)(**fields), differences


def _weighted(term: ast.expr) -> tuple[float, ast.expr]:
    """`c * x` or `x * c`, c a number literal, as (c, x); any other term as (1, term)."""
    if isinstance(term, ast.BinOp) and isinstance(term.op, ast.Mult):
        for weight, rest in ((term.left, term.right), (term.right, term.left)):
            if is_number_literal(weight) and not is_number_literal(rest):
                return float(ast.literal_eval(weight)), rest
    return 1.0, term


def merged_terms(node: ast.BinOp, definitions: dict[str, ast.expr]) -> Optional[ast.expr]:
    """`w1 * x + w2 * y` (or `-`; a term without a literal factor has weight 1) as one term,
    when x and y are alike but for their float constants and at most one subexpression: the
    same expression, or names of `definitions` assigned such expressions. The term is
    `(w1 + w2) * m`, m being x's expression with each float constant the weighted mean
    (w1 * a + w2 * b) / (w1 + w2) of the pair and the subexpression that differs the weighted sum
    of the two; exact where the expression is linear in its constants. None where the terms
    differ more, or at their root, or the weights cancel."""
    if not isinstance(node.op, (ast.Add, ast.Sub)):
        return None
    (w1, x), (w2, y) = _weighted(node.left), _weighted(node.right)
    w2 = -w2 if isinstance(node.op, ast.Sub) else w2
    total = _displayed(w1 + w2)
    if total == 0 or not math.isfinite(total):
        return None
    if isinstance(x, ast.Name) and isinstance(y, ast.Name) and x.id == y.id:
        merged: ast.expr = copy.deepcopy(x)
    else:
        x, y = (definitions.get(t.id, t) if isinstance(t, ast.Name) else t for t in (x, y))
        together = _Blend(w1, w2).field_by_field(x, y)  # the root alike: a merge, not a rewritten sum
        if together is None or together[1] > 1:
            return None
        merged = together[0]
    return merged if total == 1.0 else ast.BinOp(number_literal(total), ast.Mult(), merged)
