"""Comparisons a policy's code decides before it runs: interval arithmetic over the program.

A model writes `if abs(angle) < -0.73:` or `if cos_theta > 1.5:`, a balance branch that can
never run, and the code reads as if it balanced. `decided_comparisons` finds such tests without
running anything: each expression gets the range of values it can take (a `(low, high)` pair), from number
literals, from the observation's entries (a spec's `OBSERVATION_BOUNDS`: a `(low, high)` pair
or None per entry, e.g. `cos θ` in [-1, 1]; an entry without bounds can be any number), from
names assigned once in the policy, and through arithmetic and the functions whose range is known
(`abs`, `cos`, `tanh`, `clip`, `sqrt`, ...). A comparison whose two sides' ranges cannot overlap
the other way is decided: always true or never true, whatever the episode. It assumes the
observation holds finite numbers and scalars where it is compared; anything it cannot bound is
any number, so it flags only what is certain. `colmo.coverage` measures what ran; this says why
a branch cannot run at all.
"""

from __future__ import annotations

import ast
import math
from dataclasses import dataclass
from typing import Optional, Sequence

from colmo import astutil
from colmo.astutil import bindings, is_number_literal
from colmo.simplify.scope import Scope

Bounds = Sequence[Optional[tuple[float, float]]]  # a spec's OBSERVATION_BOUNDS: per entry, (low, high) or None
_ANY = (-math.inf, math.inf)
_FUNCTIONS = {  # what a call computes, by the dotted name it resolves to (`colmo.simplify.scope`)
    **dict.fromkeys(("builtins.abs", "numpy.abs", "numpy.absolute", "numpy.fabs", "math.fabs"), "abs"),
    **dict.fromkeys(("numpy.cos", "numpy.sin", "math.cos", "math.sin"), "unit"),
    **dict.fromkeys(("numpy.tanh", "math.tanh"), "tanh"),
    **dict.fromkeys(("numpy.arctan", "math.atan"), "arctan"),
    **dict.fromkeys(("numpy.arctan2", "math.atan2"), "arctan2"),
    **dict.fromkeys(("numpy.sqrt", "math.sqrt"), "sqrt"),
    **dict.fromkeys(("numpy.exp", "math.exp"), "exp"),
    "numpy.sign": "sign", "numpy.clip": "clip",
    **dict.fromkeys(("builtins.max", "numpy.maximum"), "max"),
    **dict.fromkeys(("builtins.min", "numpy.minimum"), "min"),
}
_MONOTONE = {"tanh": math.tanh, "arctan": math.atan, "sign": lambda x: float((x > 0) - (x < 0))}  # they keep the order
_OPERATORS = (ast.Lt, ast.LtE, ast.Gt, ast.GtE)  # orderings; `==` and `is` are left alone


@dataclass(frozen=True)
class Decided:
    """A comparison whose outcome the code fixes."""

    line: int
    text: str  # the comparison as written
    outcome: bool  # what it always evaluates to
    why: str  # the ranges that decide it

    def __str__(self) -> str:
        return f"`{self.text}` is {'always' if self.outcome else 'never'} true ({self.why})"


def _shown(value: float) -> str:
    return f"{value:.4g}" if math.isfinite(value) else ("inf" if value > 0 else "-inf")


def _range_text(bound: tuple[float, float]) -> str:
    low, high = bound
    return f"always {_shown(low)}" if low == high else f"in [{_shown(low)}, {_shown(high)}]"


def _checked(low: float, high: float) -> tuple[float, float]:
    return _ANY if math.isnan(low) or math.isnan(high) else (low, high)


def _product(a: tuple[float, float], b: tuple[float, float]) -> tuple[float, float]:
    ends = [x * y for x in a for y in b]
    return _ANY if any(math.isnan(e) for e in ends) else (min(ends), max(ends))


class _Ranges:
    """The range of each expression of one policy function."""

    def __init__(self, function: ast.FunctionDef, bounds: Bounds, scope: Scope):
        self.bounds, self.scope = list(bounds), scope
        self.observation = function.args.args[0].arg if function.args.args else None
        counts: dict[str, int] = {}
        self.values: dict[str, ast.expr] = {}
        for node in ast.walk(function):
            for name in bindings(node):  # `global x` counts too: x can change between calls
                counts[name] = counts.get(name, 0) + 1
            if isinstance(node, ast.Assign) and len(node.targets) == 1:
                target = node.targets[0]
                if isinstance(target, ast.Name):
                    self.values[target.id] = node.value
                elif isinstance(target, ast.Tuple) and isinstance(node.value, ast.Name) and node.value.id == self.observation:
                    for index, element in enumerate(target.elts):  # `a, b, c = obs`
                        if isinstance(element, ast.Name):
                            self.values[element.id] = ast.Subscript(node.value, ast.Constant(index), ast.Load())
        # Only a name bound exactly once has one value. Entries keep their bounds only while nothing
        # can change them: the observation's name never rebound, nothing written into a subscript.
        self.values = {name: value for name, value in self.values.items() if counts.get(name) == 1 and name != self.observation}
        written = any(isinstance(node, ast.Subscript) and isinstance(node.ctx, ast.Store) for node in ast.walk(function))
        if written or counts.get(self.observation or "", 0) != 1:
            self.bounds = []
        self.visiting: set[str] = set()

    def of(self, node: ast.AST) -> tuple[float, float]:
        if is_number_literal(node):
            value = float(ast.literal_eval(node))
            return (value, value)
        if isinstance(node, ast.Name) and node.id in self.values and node.id not in self.visiting:
            self.visiting.add(node.id)
            try:
                return self.of(self.values[node.id])
            finally:
                self.visiting.discard(node.id)
        if isinstance(node, ast.Subscript):
            return self._entry(node)
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            low, high = self.of(node.operand)
            return (-high, -low) if isinstance(node.op, ast.USub) else (low, high)
        if isinstance(node, ast.BinOp):
            return self._binary(node)
        if isinstance(node, ast.IfExp):
            (a, b), (c, d) = self.of(node.body), self.of(node.orelse)
            return (min(a, c), max(b, d))
        if isinstance(node, ast.Call) and not node.keywords and not any(isinstance(a, ast.Starred) for a in node.args):
            return self._call(node)
        return _ANY

    def _entry(self, node: ast.Subscript) -> tuple[float, float]:
        if not (isinstance(node.value, ast.Name) and node.value.id == self.observation and is_number_literal(node.slice)):
            return _ANY
        index = ast.literal_eval(node.slice)
        if not isinstance(index, int) or not -len(self.bounds) <= index < len(self.bounds):
            return _ANY
        bound = self.bounds[index]
        return (float(bound[0]), float(bound[1])) if bound is not None else _ANY

    def _binary(self, node: ast.BinOp) -> tuple[float, float]:
        (a, b), (c, d) = self.of(node.left), self.of(node.right)
        if isinstance(node.op, ast.Add):
            return _checked(a + c, b + d)
        if isinstance(node.op, ast.Sub):
            return _checked(a - d, b - c)
        if isinstance(node.op, ast.Mult):
            return _product((a, b), (c, d))
        if isinstance(node.op, ast.Div) and (c > 0 or d < 0):  # a divisor that cannot be 0
            return _product((a, b), (1 / d, 1 / c))
        if isinstance(node.op, ast.Pow) and c == d and float(c).is_integer() and 0 < c <= 64:
            n = int(c)
            try:
                if n % 2:  # an odd power keeps the order
                    return (a**n, b**n)
                return (0.0 if a <= 0 <= b else min(abs(a), abs(b)) ** n, max(abs(a), abs(b)) ** n)
            except OverflowError:
                return _ANY
        return _ANY

    def _call(self, node: ast.Call) -> tuple[float, float]:
        name = _FUNCTIONS.get(self.scope.resolve(node.func) or "")
        args = [self.of(arg) for arg in node.args]
        if name == "abs" and len(args) == 1:
            low, high = args[0]
            return (0.0 if low <= 0 <= high else min(abs(low), abs(high)), max(abs(low), abs(high)))
        if name == "unit" and len(args) == 1:  # a cosine or a sine
            return (-1.0, 1.0)
        if name in _MONOTONE and len(args) == 1:
            return (_MONOTONE[name](args[0][0]), _MONOTONE[name](args[0][1]))
        if name == "arctan2" and len(args) == 2:
            return (-math.pi, math.pi)
        if name == "sqrt" and len(args) == 1 and args[0][0] >= 0:
            return (math.sqrt(args[0][0]), math.sqrt(args[0][1]))
        if name == "exp" and len(args) == 1:
            return (math.exp(min(args[0][0], 700.0)), math.exp(min(args[0][1], 700.0)))
        if name == "clip" and len(args) == 3:  # numpy's is min(max(x, low), high), rising in each: inverted limits too
            (x_low, x_high), (low_low, low_high), (high_low, high_high) = args
            return (min(max(x_low, low_low), high_low), min(max(x_high, low_high), high_high))
        if name == "max" and len(args) == 2:
            return (max(args[0][0], args[1][0]), max(args[0][1], args[1][1]))
        if name == "min" and len(args) == 2:
            return (min(args[0][0], args[1][0]), min(args[0][1], args[1][1]))
        return _ANY


def decided_comparisons(code: str, bounds: Bounds = (), function_name: str = "policy") -> list[Decided]:
    """Every ordering comparison (`<`, `<=`, `>`, `>=`) in the policy of `code` that the code
    decides, in source order; `bounds` are the spec's per-entry observation bounds. Code that
    does not parse, or has no such function, decides nothing."""
    try:
        tree = astutil.parse(code)
    except (SyntaxError, ValueError):
        return []
    function = astutil.function(tree, function_name)
    if function is None:
        return []
    ranges = _Ranges(function, bounds, Scope(tree))
    found = []
    for node in ast.walk(function):
        if not isinstance(node, ast.Compare) or not all(type(op) in _OPERATORS for op in node.ops):
            continue
        operands = [node.left, *node.comparators]
        if all(is_number_literal(operand) for operand in operands):
            continue  # a literal comparison is constant folding's, and says nothing of the program
        # A chain `a < b < c` is never true if one link never is, always true only if every link always is.
        links = [(_decide(type(op), ranges.of(left), ranges.of(right)), left, right) for op, left, right in zip(node.ops, operands, operands[1:])]
        deciding = [link for link in links if link[0] is False] or (links if all(link[0] for link in links) else [])
        if deciding:
            outcome, left, right = deciding[0]
            why = ", ".join(f"`{_short(side)}` is {_range_text(ranges.of(side))}" for side in (left, right) if not is_number_literal(side))
            found.append(Decided(node.lineno, ast.unparse(node), outcome, why))
    return sorted(found, key=lambda decided: decided.line)


def _short(node: ast.AST, limit: int = 40) -> str:
    text = ast.unparse(node)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _decide(op: type, left: tuple[float, float], right: tuple[float, float]) -> Optional[bool]:
    """True or False if `left op right` is so for every pair of values in the ranges, else None."""
    (a, b), (c, d) = left, right
    if op in (ast.Gt, ast.GtE):  # `x > y` is `y < x`
        (a, b), (c, d) = (c, d), (a, b)
    strict = op in (ast.Lt, ast.Gt)
    if (b < c) if strict else (b <= c):
        return True
    if (a >= d) if strict else (a > d):
        return False
    return None
