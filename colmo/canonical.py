"""The canonical form of a skeleton that its structure key hashes: constants that add no freedom merged.

Where GFO tunes every constant, two skeletons are one structure when they describe the same
family of functions. `c1 * c2 * x` and `c * x` do; so do `c0 * (c1 * x + c2 * y)` and
`c1 * x + c2 * y` (the shared factor distributes into the terms' own constants), `x - c` and
`x + c`, and `-(c * x)` and `c * x`. The canonical form replaces every tunable constant
(`params[i]`) with one marker and then, bottom-up:

  * an expression of constants alone (`+ - * /` and signs over markers, `np.pi`, `np.e`) is one
    marker;
  * a product (`*`, `/`) keeps one constant factor, written first, and its other factors in order;
    it loses that factor too when another factor is *scalable*;
  * a sum (`+`, `-`) keeps one constant term, written first, and the signs of its scalable terms
    are dropped (a constant factor absorbs them);
  * a minus in front of a scalable expression is dropped.

An expression is scalable when every value of `c * e` is again a value of `e` with other
constants: a marker, a product with a constant factor or a scalable factor, a sum of scalable
terms, `np.clip(e, c1, c2)` of a scalable `e` with constant limits, `np.where(cond, a, b)` and
`a if cond else b` of scalable `a` and `b`, and a list, tuple or `np.array` of scalable items.

Each rule maps a family of functions onto itself (up to a constant of 0, which a search does
not reach by tuning), so programs that share a canonical form reach the same functions by
tuning, and a search evaluates only one of them. Nothing else is rewritten: names, indices,
calls, comparisons and the order of the non-constant terms stay as the program wrote them.
"""

from __future__ import annotations

import ast
from typing import Callable

_MARKER_VALUE = ...  # never a tunable constant, so it cannot collide with what a program writes
_SCALABLE = "colmo_scalable"  # an attribute on nodes of the canonical tree; ast.dump ignores it
_FIXED_NUMBERS = frozenset({"pi", "e"})


def canonical_form(tree: ast.AST, is_constant: Callable[[ast.AST], bool]) -> ast.AST:
    """`tree` rewritten (in place where it can be) to its canonical form; `is_constant` tells a
    tunable constant (a `params[i]` slot of the skeleton)."""
    return _Canonical(is_constant).visit(tree)


def _marker() -> ast.Constant:
    marker = ast.Constant(_MARKER_VALUE)
    setattr(marker, _SCALABLE, True)
    return marker


def _is_marker(node: ast.AST) -> bool:
    return isinstance(node, ast.Constant) and node.value is _MARKER_VALUE


def _scalable(node: ast.AST) -> bool:
    return getattr(node, _SCALABLE, False)


def _scaled(node: ast.AST) -> ast.AST:
    setattr(node, _SCALABLE, True)
    return node


def _is_numpy(node: ast.AST, names: frozenset[str]) -> bool:
    return (
        isinstance(node, ast.Attribute) and node.attr in names
        and isinstance(node.value, ast.Name) and node.value.id in ("np", "numpy")
    )


def _factors(node: ast.AST, inverted: bool = False) -> list[tuple[ast.AST, bool]]:
    """The factors of a product chain, each with whether it divides."""
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Mult, ast.Div)):
        return _factors(node.left, inverted) + _factors(node.right, inverted != isinstance(node.op, ast.Div))
    return [(node, inverted)]


def _terms(node: ast.AST, negative: bool = False) -> list[tuple[ast.AST, bool]]:
    """The terms of a sum, each with whether it is subtracted."""
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub)):
        return _terms(node.left, negative) + _terms(node.right, negative != isinstance(node.op, ast.Sub))
    return [(node, negative)]


class _Canonical(ast.NodeTransformer):
    def __init__(self, is_constant: Callable[[ast.AST], bool]):
        self.is_constant = is_constant

    def visit(self, node: ast.AST) -> ast.AST:
        if self.is_constant(node):
            return _marker()
        return super().visit(node)

    def visit_UnaryOp(self, node: ast.UnaryOp) -> ast.AST:
        self.generic_visit(node)
        if isinstance(node.op, (ast.USub, ast.UAdd)) and _scalable(node.operand):
            return node.operand
        return node

    def visit_BinOp(self, node: ast.BinOp) -> ast.AST:
        self.generic_visit(node)
        if isinstance(node.op, (ast.Mult, ast.Div)):
            return self._product(node)
        if isinstance(node.op, (ast.Add, ast.Sub)):
            return self._sum(node)
        return node

    def _product(self, node: ast.BinOp) -> ast.AST:
        factors = _factors(node)
        constant = any(_is_marker(factor) for factor, _ in factors)
        others = [(f, divides) for f, divides in factors if not _is_marker(f) and not _is_numpy(f, _FIXED_NUMBERS)]
        if constant and not others:
            return _marker()
        if not constant:
            return _scaled(node) if any(_scalable(f) for f, _ in factors) else node
        if any(_scalable(f) for f, _ in others):
            constant = False  # the scalable factor takes the constant factor's place
        if not constant and all(divides for _, divides in others):
            return _scaled(node)  # `c / s` of a scalable `s`: as written, there is no `1 / s` to write
        product = _marker() if constant else None
        for factor, divides in others:
            if product is None:
                product = factor
            else:
                product = ast.BinOp(product, ast.Div() if divides else ast.Mult(), factor)
        return _scaled(product)

    def _sum(self, node: ast.BinOp) -> ast.AST:
        terms = _terms(node)
        constant = any(_is_marker(term) for term, _ in terms)
        others = [(t, negative and not _scalable(t)) for t, negative in terms if not _is_marker(t)]
        if constant and not others:
            return _marker()
        total: ast.AST | None = _marker() if constant else None
        for term, negative in others:
            if total is None:
                total = ast.UnaryOp(ast.USub(), term) if negative else term
            else:
                total = ast.BinOp(total, ast.Sub() if negative else ast.Add(), term)
        assert total is not None
        if all(_scalable(term) for term, _ in terms):
            _scaled(total)
        return total

    def visit_Call(self, node: ast.Call) -> ast.AST:
        self.generic_visit(node)
        args = node.args
        if node.keywords:
            return node
        if _is_numpy(node.func, frozenset({"clip"})) and len(args) == 3:
            if _scalable(args[0]) and _is_marker(args[1]) and _is_marker(args[2]):
                return _scaled(node)
        elif _is_numpy(node.func, frozenset({"where"})) and len(args) == 3:
            if _scalable(args[1]) and _scalable(args[2]):
                return _scaled(node)
        elif _is_numpy(node.func, frozenset({"array", "asarray"})) and len(args) == 1 and _scalable(args[0]):
            return _scaled(node)
        return node

    def visit_IfExp(self, node: ast.IfExp) -> ast.AST:
        self.generic_visit(node)
        return _scaled(node) if _scalable(node.body) and _scalable(node.orelse) else node

    def _sequence(self, node: ast.List | ast.Tuple) -> ast.AST:
        self.generic_visit(node)
        return _scaled(node) if node.elts and all(_scalable(e) for e in node.elts) else node

    visit_List = _sequence
    visit_Tuple = _sequence
