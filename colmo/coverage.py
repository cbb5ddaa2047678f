"""Branch coverage: which branches of a policy ran, how often, over which episodes.

A program can read as "pump energy, then balance" and only pump: its balance branch tests a
value the observation never takes. Coverage measures what each branch did:
  * `if` and `while` statements and conditional expressions: how many times the condition was
    tested, and how many of those it was true;
  * `np.clip` (and an array's `.clip`): how many values it returned, and how many of them it
    raised or lowered (saturation: all of them, and the clip is a constant in disguise);
  * `np.where(condition, a, b)`: how many values it chose, and for how many the condition held;
  * a division (`/`, `//`, `%`) by something that is not a constant: how many values it gave,
    for how many the divisor was 0, and how many other results were not finite (a term that
    divides by a velocity that is 0 at every reset reads as physics and returns inf or nan).
    `x /= y` is not counted (rewriting it would change what it does to an array in place).

`instrument` rewrites a checked program's tree so that each such site reports to a `Probe`
(the names it calls start with `__`, which the static check refuses in a program, so the
program cannot reach them); the sandbox runs it in place of the program when an evaluation asks
for coverage (`EvalRequest.coverage`: on the fast path the worker's child, in referee mode the
policy's child, which sends its counts after the episodes), and the counts come back with the
evaluation. They come from the program's own process, so they describe the program; they
never take part in a score. `annotate` writes them into the program's text as a comment line
above each statement that holds a site, which is how `best_policy.py` carries them.
Sites are numbered in the order one walk of the tree meets them, the same for a program's
readable code and its parametrized skeleton, so the counts of one fit the text of the other
(`sites` of both must agree, which `annotate`'s callers check).
"""

from __future__ import annotations

import ast
import operator
from dataclasses import dataclass
from typing import Any, Callable, NamedTuple, Optional, Sequence

import numpy as np

from colmo import astutil
from colmo.program import PARAMS_NAME

BRANCH, CALL, DIVIDE = "__colmo_branch__", "__colmo_call__", "__colmo_divide__"
CONDITION_KINDS = ("if", "while", "conditional")
CALL_KINDS = ("clip", "where")
_DIVISIONS = {"Div": operator.truediv, "FloorDiv": operator.floordiv, "Mod": operator.mod}  # by the operator's AST name
MAX_SITES = 100_000  # far more than a program under the intake's node limit can hold
# Tests (or values); then true, raised by a clip, or a zero divisor; then lowered by a clip, or not finite.
Counts = tuple[int, int, int]


@dataclass(frozen=True)
class Site:
    """One branch of a program: its kind, the line of the statement that holds it, and its text."""

    kind: str
    line: int
    text: str


class _Sites(ast.NodeTransformer):
    """Finds the sites in walk order; with `rewrite`, routes each through the probe."""

    def __init__(self, rewrite: bool, tree: ast.Module):
        self.rewrite = rewrite
        self.found: list[Site] = []
        self.nodes: list[ast.AST] = []  # the node of each site: the If, While, IfExp, Call or BinOp
        self.statement_line = 0
        # A divisor made of constants, tuned parameters and module attributes (`2 * np.pi`) is no site.
        self.constant_names = {PARAMS_NAME} | {
            (alias.asname or alias.name).split(".")[0] for node in ast.walk(tree) if isinstance(node, (ast.Import, ast.ImportFrom)) for alias in node.names
        }

    def visit(self, node: ast.AST) -> Any:
        if not isinstance(node, ast.stmt):
            return super().visit(node)
        outer, self.statement_line = self.statement_line, node.lineno
        try:
            return super().visit(node)
        finally:
            self.statement_line = outer

    def _site(self, kind: str, node: ast.AST, text: ast.AST) -> int:
        self.found.append(Site(kind, self.statement_line, _short(ast.unparse(text))))
        self.nodes.append(node)
        return len(self.found) - 1

    def _condition(self, node: ast.If | ast.While | ast.IfExp, kind: str) -> ast.AST:
        index = self._site(kind, node, node.test)
        self.generic_visit(node)
        if self.rewrite:
            node.test = ast.Call(ast.Name(BRANCH, ast.Load()), [ast.Constant(index), node.test], [])
        return node

    def visit_If(self, node: ast.If) -> ast.AST:
        return self._condition(node, "if")

    def visit_While(self, node: ast.While) -> ast.AST:
        return self._condition(node, "while")

    def visit_IfExp(self, node: ast.IfExp) -> ast.AST:
        return self._condition(node, "conditional")

    def visit_Call(self, node: ast.Call) -> ast.AST:
        function = node.func
        name = function.attr if isinstance(function, ast.Attribute) else function.id if isinstance(function, ast.Name) else None
        if name not in CALL_KINDS:
            return self.generic_visit(node)
        index = self._site(name, node, node)
        self.generic_visit(node)
        if not self.rewrite:
            return node
        return ast.Call(ast.Name(CALL, ast.Load()), [ast.Constant(index), ast.Constant(name), node.func, *node.args], node.keywords)

    def visit_BinOp(self, node: ast.BinOp) -> ast.AST:
        if type(node.op).__name__ not in _DIVISIONS or self._constant(node.right):
            return self.generic_visit(node)
        index = self._site("division", node, node)
        self.generic_visit(node)
        if not self.rewrite:
            return node
        return ast.Call(ast.Name(DIVIDE, ast.Load()), [ast.Constant(index), ast.Constant(type(node.op).__name__), node.left, node.right], [])

    def _constant(self, node: ast.AST) -> bool:
        return not any(isinstance(n, ast.Call) or (isinstance(n, ast.Name) and n.id not in self.constant_names) for n in ast.walk(node))


def _short(text: str, limit: int = 60) -> str:
    return text if len(text) <= limit else text[: limit - 3] + "..."


def sites(code: str) -> list[Site]:
    """The sites of a program's text, in the order the probe numbers them."""
    tree = astutil.parse(code)
    visitor = _Sites(rewrite=False, tree=tree)
    visitor.visit(tree)
    return visitor.found


def same_sites(code: str, skeleton: str) -> bool:
    """Whether a program's readable code and its skeleton have the same sites in the same order,
    so that the counts of the skeleton's evaluation describe the code."""
    return [s.kind for s in sites(code)] == [s.kind for s in sites(skeleton)]


def instrument(tree: ast.Module) -> int:
    """Route every site of `tree` (checked, about to be compiled) through the probe, in place;
    the number of sites."""
    visitor = _Sites(rewrite=True, tree=tree)
    visitor.visit(tree)
    ast.fix_missing_locations(tree)
    return len(visitor.found)


class Probe:
    """The counts of an instrumented program's sites, over every episode its process runs; its
    two functions go into the program's namespace under `BRANCH` and `CALL`."""

    def __init__(self, size: int):
        self.counts = [[0, 0, 0] for _ in range(size)]

    def names(self) -> dict[str, Callable[..., Any]]:
        return {BRANCH: self.branch, CALL: self.call, DIVIDE: self.divide}

    def branch(self, index: int, condition: object) -> bool:
        value = bool(condition)  # exactly what `if` does with it, exceptions included
        counts = self.counts[index]
        counts[0] += 1
        counts[1] += value
        return value

    def call(self, index: int, kind: str, function: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Any:
        result = function(*args, **kwargs)
        try:
            self._count(self.counts[index], kind, function, args, kwargs, result)
        except Exception:  # a call the counts cannot read (a program's own `clip`): its result stands
            pass
        return result

    def divide(self, index: int, operation: str, left: Any, right: Any) -> Any:
        result = _DIVISIONS[operation](left, right)  # exactly the program's operation, errors included
        try:
            values = np.asarray(result, dtype=float)
            zero = np.broadcast_to(np.asarray(right, dtype=float) == 0, values.shape)
            counts = self.counts[index]
            counts[0] += values.size
            counts[1] += _true(zero)
            counts[2] += _true(~np.isfinite(values) & ~zero)
        except Exception:  # values the counts cannot read (not numbers): the result stands
            pass
        return result

    @staticmethod
    def _count(counts: list[int], kind: str, function: Callable[..., Any], args: tuple, kwargs: dict, result: Any) -> None:
        if kind == "where":
            if len(args) != 3:  # `np.where(condition)` finds indices: no choice made
                return
            counts[0] += np.size(result)
            counts[1] += _true(np.broadcast_to(np.asarray(args[0], dtype=bool), np.shape(result)))
            return
        # An array's own `.clip(lo, hi)` clips the array it is bound to; `np.clip(a, lo, hi)` its first argument.
        bound = getattr(function, "__self__", None)
        given = bound if isinstance(bound, np.ndarray) else args[0] if args else kwargs["a"]
        counts[0] += np.size(result)
        counts[1] += _true(result > given)
        counts[2] += _true(result < given)

    def result(self) -> tuple[Counts, ...]:
        return tuple((tests, first, second) for tests, first, second in self.counts)


def _true(comparison: Any) -> int:
    """How many entries of a comparison's outcome are true (one bool for scalars: the common case, cheap)."""
    return int(comparison) if isinstance(comparison, (bool, np.bool_)) else int(np.count_nonzero(comparison))


def checked_counts(value: object) -> tuple[Counts, ...]:
    """Counts from a sandbox reply, as data: a list of at most `MAX_SITES` triples of
    non-negative integers, each part at most the first; `ValueError` otherwise."""
    if not isinstance(value, list) or len(value) > MAX_SITES:
        raise ValueError("coverage is not a list of sites")
    counts = []
    for item in value:
        if not (isinstance(item, list) and len(item) == 3 and all(type(n) is int and 0 <= n < 2**62 for n in item)):
            raise ValueError("coverage holds a malformed site")
        if item[1] > item[0] or item[2] > item[0] or item[1] + item[2] > item[0]:
            raise ValueError("coverage counts more than a site's tests")
        counts.append((item[0], item[1], item[2]))
    return tuple(counts)


def added(parts: Sequence[Optional[Sequence[Counts]]]) -> Optional[tuple[Counts, ...]]:
    """The counts of one program over several requests, or None if any part has none."""
    if not parts or any(p is None for p in parts) or len({len(p) for p in parts}) != 1:
        return None
    return tuple(tuple(sum(c) for c in zip(*site)) for site in zip(*parts))  # type: ignore[misc]


class _Pruned(ast.NodeTransformer):
    """Each branch that was decided the same way at every test replaced by the side that ran."""

    def __init__(self, decided: dict[int, bool]):
        self.decided = decided  # id of an If, While or IfExp -> its condition's one value

    def _kept(self, node: ast.If | ast.While | ast.IfExp) -> Any:
        self.generic_visit(node)
        value = self.decided.get(id(node))
        if value is None:
            return node
        return node.body if value else node.orelse

    visit_If = visit_While = visit_IfExp = _kept


class Pruned(NamedTuple):
    """A program without the branches it never took: its code, what went in words, how many."""

    code: str
    description: str
    branches: int


def prune(code: str, counts: Sequence[Counts]) -> Optional[Pruned]:
    """`code` without the branches its counts show were never taken (an `if` or conditional
    expression whose condition was false at every test, or true at every test, keeps only the
    side that ran; a `while` never entered goes), and what was removed, in words; None where
    nothing was decided so, or the counts do not fit the code. What the episodes did not reach
    stays: the simplifier removes what it can by trial."""
    tree = astutil.parse(code)
    visitor = _Sites(rewrite=False, tree=tree)
    visitor.visit(tree)
    if len(visitor.found) != len(counts):
        return None
    decided: dict[int, bool] = {}
    removed = []
    for site, node, (tests, true, _) in zip(visitor.found, visitor.nodes, counts):
        if site.kind not in CONDITION_KINDS or not tests or 0 < true < tests or (site.kind == "while" and true):
            continue
        decided[id(node)] = bool(true)
        removed.append(f"`{site.text}` ({'always' if true else 'never'} true in {tests:,} tests)")
    if not decided:
        return None
    pruned = _Pruned(decided).visit(tree)
    for node in ast.walk(pruned):  # a block left empty holds `pass`
        if not isinstance(node, ast.Module) and getattr(node, "body", None) == []:
            node.body = [ast.Pass()]
    return Pruned(ast.unparse(ast.fix_missing_locations(pruned)), "removed the branches never taken: " + ", ".join(removed), len(removed))


def _percent(part: int, whole: int) -> str:
    share = 100 * part / whole
    return f"{share:.0f}%" if share in (0, 100) or share >= 1 else f"{share:.2g}%"


def describe(site: Site, counts: Counts) -> str:
    """One site's counts in words: `if cos_t > 0.95: true 37% of 1,000 tests`."""
    tests, first, second = counts
    if site.kind in CONDITION_KINDS:
        head = f"{site.kind} `{site.text}`"
        if not tests:
            return f"{head}: never reached"
        verdict = " (never true)" if first == 0 else " (always true)" if first == tests else ""
        return f"{head}: true {_percent(first, tests)} of {tests:,} tests{verdict}"
    head = f"`{site.text}`"
    if not tests:
        return f"{head}: never reached"
    if site.kind == "division":
        zero = f"divisor 0 for {_percent(first, tests)} of {tests:,} values" if first else f"divisor never 0 in {tests:,} values"
        return f"{head}: {zero}" + (f", {_percent(second, tests)} other results not finite" if second else "")
    if site.kind == "where":
        return f"{head}: condition true for {_percent(first, tests)} of {tests:,} values"
    verdict = ": always at a limit" if first + second == tests else ""
    changed = f"changed {_percent(first + second, tests)} of {tests:,} values"
    return f"{head}: {changed} ({_percent(first, tests)} raised, {_percent(second, tests)} lowered){verdict}"


def annotate(code: str, counts: Sequence[Counts], label: str = "coverage") -> Optional[str]:
    """`code` with each statement that holds a site preceded by a comment line per site saying
    what it did (`describe`); None where the counts do not fit the code's sites (another program's,
    or a different program version)."""
    found = sites(code)
    if len(found) != len(counts):
        return None
    lines = code.splitlines()
    comments: dict[int, list[str]] = {}
    for site, site_counts in zip(found, counts):
        comments.setdefault(site.line, []).append(f"# {label}: {describe(site, site_counts)}")
    out = []
    for number, line in enumerate(lines, start=1):
        indent = line[: len(line) - len(line.lstrip())]
        out.extend(indent + comment for comment in comments.get(number, ()))
        out.append(line)
    text = "\n".join(out) + ("\n" if code.endswith("\n") else "")
    # A comment line above a statement's first line cannot change the program; say so by checking.
    if ast.dump(astutil.parse(text)) != ast.dump(astutil.parse(code)):
        return None
    return text


def counts_of(summary: dict[str, Any]) -> list[Counts]:
    """The counts a `summary` holds, site by site ([] for an empty one)."""
    return [tuple(site["counts"]) for site in summary.get("sites", ())]  # type: ignore[misc]


def summary(code: str, counts: Sequence[Counts], episodes: int) -> dict[str, Any]:
    """What `summary.json` holds of a program's coverage: each site with its counts and words."""
    return {
        "episodes": episodes,
        "sites": [
            {"kind": s.kind, "line": s.line, "text": s.text, "counts": list(c), "says": describe(s, c)}
            for s, c in zip(sites(code), counts)
        ],
    }
