"""One-step simplifications of a policy program: the deletions the greedy stage tries.

`deletion_candidates` lists every one-step simplification: delete a statement, keep one branch
of an `if` statement or of a conditional expression, drop a term of a sum or difference, a
factor of a product, a divisor or an exponent, merge a product's constant factors wherever they
stand (`2.0 * (3.0 * x)` -> `6.0 * x`, `2.0 * y * (3.0 * x)` -> `6.0 * y * x`,
`2.0 * (np.array([1.0, 3.0]) * x)` -> `np.array([2.0, 6.0]) * x`), unwrap a call
to one of its arguments (`np.tanh(e)` -> `e`, `np.clip(e, a, b)` -> `e`; never `np.array([...])`
to its list), cut an array literal
to one entry or to one value shared by all (`np.array([a, b, c])` -> `b * np.eye(3)[1]` or
`np.full(3, mean)`: the gain vector's constants less one, where a deletion of the whole vector
loses what its strongest entry carries), keep one operand of
`and`/`or`, merge two terms alike but for their constants and at most one subexpression
(`0.5 * a + 0.5 * a_b`, where `a` and `a_b` are assigned such expressions, as mutation's blend
of a program and its relative writes: one expression, each constant the weighted mean of the
pair, the subexpression that differs the weighted sum of the two), collect a sum's like terms
(`a + 1.663 * (0.3931 - b + 1.142 * b)` -> `a + 0.6537 + 0.2361 * b`, `colmo.simplify.linear`), the
same with the names assigned once and read only in that sum written in (`a = 0.17` then
`return a - 2.0 * x + 0.33` -> `return 0.5 - 2.0 * x`; a number read more than once there too), and replace a subexpression
that no drop covers (a call argument, a compared value, an assigned or returned value, a branch)
by 0.0 or 1.0. The last `return` of the policy is never deleted (a policy returning None always
fails). Each candidate is cleaned by `remove_dead_code`, so what a deletion leaves dead goes
with it, and must be strictly smaller (`colmo.astutil.node_count`); duplicates (same code) are
dropped. Nothing here judges a candidate: scores do.
"""

from __future__ import annotations

import ast
import copy
import math
from collections import Counter
from dataclasses import dataclass
from typing import Any, Callable, Iterator, Optional

from colmo import astutil
from colmo.astutil import OPAQUE_FIELDS, is_number_literal, negated, node_count, number_literal, replace_nodes, strip_docstrings
from colmo.program import round_significant
from colmo.simplify.deadcode import FUNCTIONS, own_statements, remove_dead_code
from colmo.simplify.linear import collected_sum, top_of_sum
from colmo.simplify.merge import merged_terms, single_definitions


@dataclass(frozen=True)
class Candidate:
    description: str  # what was deleted, with its line in the code it was deleted from
    code: str  # the program after the deletion and `remove_dead_code`
    nodes: int  # its AST nodes, `colmo.astutil.node_count`


# Where an expression is not a value to simplify, besides `OPAQUE_FIELDS`: assignment targets,
# and what only the interpreter reads.
_NOT_VALUES = ("targets", "target", "decorator_list", "annotation", "returns", "args")  # `args` of a def, not of a call
_DROP_SIDES = {
    ast.Add: ("left", "right"), ast.Sub: ("left", "right"), ast.Mult: ("left", "right"),
    ast.Div: ("left",), ast.Pow: ("left",), ast.Mod: ("left",), ast.FloorDiv: ("left",),
}
_TERM_WORDS = {ast.Add: "term", ast.Sub: "term", ast.Mult: "factor", ast.Div: "divisor", ast.Pow: "exponent", ast.Mod: "modulus", ast.FloorDiv: "divisor"}


def _short(node: ast.AST, limit: int = 60) -> str:
    text = ast.unparse(node)
    first = text.splitlines()[0] if text else text
    return first if len(first) <= limit and first == text else first[: limit - 3] + "..."


def _parents(tree: ast.AST) -> dict[int, tuple[ast.AST, str, Optional[int]]]:
    """Each node's parent, the field holding it and its index in that field (None: not a list)."""
    parents: dict[int, tuple[ast.AST, str, Optional[int]]] = {}
    for node in ast.walk(tree):
        for name, value in ast.iter_fields(node):
            if isinstance(value, list):
                for i, child in enumerate(value):
                    if isinstance(child, ast.AST):
                        parents[id(child)] = (node, name, i)
            elif isinstance(value, ast.AST):
                parents[id(value)] = (node, name, None)
    return parents


def _value_positions(tree: ast.Module) -> Iterator[ast.expr]:
    """Expressions inside functions that are values a deletion may rewrite, in `ast.walk` order."""
    opaque: set[int] = set()
    for node in ast.walk(tree):
        for name, value in ast.iter_fields(node):
            children = value if isinstance(value, list) else [value]
            if (type(node), name) in OPAQUE_FIELDS or (name in _NOT_VALUES and not isinstance(node, ast.Call)):
                opaque.update(id(n) for child in children if isinstance(child, ast.AST) for n in ast.walk(child))
    inside_functions = {id(n) for f in ast.walk(tree) if isinstance(f, FUNCTIONS) for s in f.body for n in ast.walk(s)}
    for node in ast.walk(tree):
        stored = isinstance(getattr(node, "ctx", None), (ast.Store, ast.Del))
        if isinstance(node, ast.expr) and id(node) in inside_functions and id(node) not in opaque and not stored:
            yield node


# An edit applies a deletion to (a copy of) a node, given the node's parent, field and index.
Edit = Callable[[ast.AST, ast.AST, str, Optional[int]], None]


def _edits(tree: ast.Module, function_name: str, parents: dict[int, tuple[ast.AST, str, Optional[int]]]) -> Iterator[tuple[ast.AST, str, Edit]]:
    """(node, description, edit) for every deletion, in source-walk order."""

    def replace_with(make: Callable[[ast.AST], ast.AST]) -> Edit:
        def edit(node: ast.AST, parent: ast.AST, name: str, index: Optional[int]) -> None:
            replacement = make(node)
            if index is None:
                setattr(parent, name, replacement)
            else:
                getattr(parent, name)[index] = replacement
        return edit

    def splice(make: Callable[[ast.AST], list[ast.stmt]]) -> Edit:
        def edit(node: ast.AST, parent: ast.AST, name: str, index: Optional[int]) -> None:
            block = getattr(parent, name)
            block[index : index + 1] = make(node)
            if not block and name == "body":
                block.append(ast.Pass())
        return edit

    functions = [n for n in ast.walk(tree) if isinstance(n, FUNCTIONS)]
    definitions: dict[int, dict[str, ast.expr]] = {}  # each node's function's `single_definitions`
    reads: dict[int, Counter[str]] = {}  # each node's function's reads of each name (its nested functions' included)
    for function in functions:  # in walk order: a nested function's nodes end with its own
        single = single_definitions(function)
        read = _loads(function)
        definitions.update((id(n), single) for n in ast.walk(function))
        reads.update((id(n), read) for n in ast.walk(function))
    for function in functions:
        # Without its last statement, a `return`, the policy returns None: always a failure.
        final_return = function.body[-1] if function.name == function_name and isinstance(function.body[-1], ast.Return) else None
        for statement in own_statements(function.body):
            where = f"line {statement.lineno}"
            if not isinstance(statement, ast.Pass) and statement is not final_return:
                yield statement, f"deleted `{_short(statement)}` at {where}", splice(lambda s: [])
            if isinstance(statement, ast.If):
                test = _short(statement.test, 40)
                yield statement, f"kept only the body of `if {test}` at {where}", splice(lambda s: s.body)
                if statement.orelse:
                    yield statement, f"kept only the else branch of `if {test}` at {where}", splice(lambda s: s.orelse)
    for node in _value_positions(tree):
        where = f"line {node.lineno}"
        single = definitions.get(id(node), {})
        if isinstance(node, ast.IfExp):
            test = _short(node.test, 40)
            yield node, f"kept only the if-side of `... if {test} else ...` at {where}", replace_with(lambda n: n.body)
            yield node, f"kept only the else-side of `... if {test} else ...` at {where}", replace_with(lambda n: n.orelse)
        elif isinstance(node, ast.BinOp) and type(node.op) in _DROP_SIDES:
            word = _TERM_WORDS[type(node.op)]
            for side in _DROP_SIDES[type(node.op)]:
                kept, dropped = (node.left, node.right) if side == "left" else (node.right, node.left)
                if side == "right" and isinstance(node.op, ast.Sub):
                    yield node, f"dropped the term `{_short(dropped)}` at {where}", replace_with(lambda n: negated(n.right))
                else:
                    yield node, f"dropped the {word} `{_short(dropped)}` at {where}", replace_with(lambda n, side=side: getattr(n, side))
            if (factors := _merged_factors(node)) is not None:
                yield node, f"merged the constant factors of `{_short(node)}` at {where}", replace_with(
                    lambda n, factors=factors: copy.deepcopy(factors)
                )
            merged = merged_terms(node, single)
            if merged is not None:
                yield node, f"merged the alike terms of `{_short(node)}` into one at {where}", replace_with(
                    lambda n, merged=merged: copy.deepcopy(merged)
                )
            if top_of_sum(node, parents[id(node)][0]):
                if (collected := collected_sum(node)) is not None:
                    yield node, f"collected the like terms of `{_short(node)}` at {where}", replace_with(
                        lambda n, collected=collected: copy.deepcopy(collected)
                    )
                # Names assigned once and read only in this sum, written in, may have terms to collect:
                # read once, or a number read more than once (an expression is not written twice).
                here = _loads(node)
                read_here = {
                    name: single[name] for name in here
                    if name in single and reads[id(node)][name] == here[name] and (here[name] == 1 or is_number_literal(single[name]))
                }
                if read_here and (collected := collected_sum(_written_in(node, read_here))) is not None:
                    names = ", ".join(f"`{name}`" for name in read_here)
                    yield node, f"collected the like terms of `{_short(node)}` with {names} written in at {where}", replace_with(
                        lambda n, collected=collected: copy.deepcopy(collected)
                    )
        elif isinstance(node, ast.BoolOp):
            for i, value in enumerate(node.values):
                yield node, f"kept only `{_short(value)}` of `{_short(node, 40)}` at {where}", replace_with(lambda n, i=i: n.values[i])
        elif isinstance(node, ast.Call):
            inverted = _inverted_clip(node)
            if inverted is not None:
                low, high = inverted
                yield node, f"replaced `{_short(node)}` at {where}, whose lower limit {low:g} exceeds its upper one, by {high:g}, all it returns", replace_with(
                    lambda n: n.args[2]
                )
            for i, argument in enumerate(node.args):
                # A list is not an array: `[0.5, 2.0] * x` works only while x is a numpy number.
                if not is_number_literal(argument) and not isinstance(argument, (ast.Starred, ast.List, ast.Tuple)):
                    yield node, f"unwrapped `{_short(node)}` to `{_short(argument)}` at {where}", replace_with(lambda n, i=i: n.args[i])
            for description, make in _array_edits(node):
                yield node, f"{description} at {where}", replace_with(make)
        parent, name, _ = parents[id(node)]
        covered = isinstance(parent, ast.BinOp) and type(parent.op) in _DROP_SIDES and (name == "left" or type(parent.op) in (ast.Add, ast.Sub, ast.Mult))
        if not covered and not is_number_literal(node) and not isinstance(node, ast.Constant):
            for value in (0.0, 1.0):
                yield node, f"replaced `{_short(node)}` by {value} at {where}", replace_with(lambda n, value=value: ast.Constant(value))


def _loads(node: ast.AST) -> Counter[str]:
    """How many times `node` reads each name."""
    return Counter(n.id for n in ast.walk(node) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load))


def _written_in(node: ast.expr, values: dict[str, ast.expr]) -> ast.expr:
    """A copy of `node` with each name of `values` read in it replaced by (a copy of) its value."""
    copied = copy.deepcopy(node)
    reads = [n for n in ast.walk(copied) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load) and n.id in values]
    return replace_nodes(copied, {id(n): copy.deepcopy(values[n.id]) for n in reads})


def _inverted_clip(node: ast.Call) -> Optional[tuple[float, float]]:
    """`(low, high)` of `np.clip(x, low, high)` (or `clip`) with literal limits and `low > high`:
    numpy then returns `high` whatever `x` is."""
    name = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", None)
    if name != "clip" or len(node.args) != 3 or node.keywords or not all(is_number_literal(a) for a in node.args[1:]):
        return None
    low, high = (ast.literal_eval(a) for a in node.args[1:])
    return (low, high) if low > high else None


def _merged_literal(value: float, node: ast.AST) -> Optional[ast.expr]:
    """`value * node` as one literal when `node` is a number literal, or as one array literal
    when it is `np.array([...])` of number literals; each product written as a person reads constants
    (`colmo.program.DISPLAY_DIGITS` significant digits: 6.285, not 6.284600000000001), so it is scored as read."""
    if is_number_literal(node):
        product = value * ast.literal_eval(node)
        if not math.isfinite(product):
            return None
        return number_literal(round_significant((product,))[0] if isinstance(product, float) else product)
    numbers = _array_numbers(node)
    if numbers is None:
        return None
    elements = [_merged_literal(value, number) for number in numbers]
    if any(element is None for element in elements):
        return None
    return ast.Call(node.func, [ast.List(elements, ast.Load())], [])


def _array_elements(node: ast.AST) -> Optional[list[ast.expr]]:
    """The elements of `np.array([e0, e1, ...])` (`numpy.array` too, no keywords, at least one);
    None for anything else."""
    if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "array"):
        return None
    module = node.func.value
    if not (isinstance(module, ast.Name) and module.id in ("np", "numpy")) or node.keywords or len(node.args) != 1:
        return None
    listed = node.args[0]
    return listed.elts if isinstance(listed, ast.List) and listed.elts else None


def _array_edits(node: ast.Call) -> Iterator[tuple[str, Callable[[ast.AST], ast.expr]]]:
    """(description, replacement) for each way to leave fewer constants in an array literal
    `np.array([e0, ..., en])`: keep only element i, `ei * np.eye(n)[i]` (the other entries 0; a
    gain vector of which one joint matters), or, when every element is a number, one value, their
    mean, shared by every entry: `np.full(n, mean)`. The size and index are structural integers,
    not constants (`colmo.program`)."""
    elements = _array_elements(node)
    if elements is None or len(elements) < 2:
        return
    module, size = node.func.value.id, len(elements)  # type: ignore[attr-defined]  # `np` or `numpy`: an array literal

    def one_entry(i: int) -> Callable[[ast.AST], ast.expr]:
        return lambda copied: ast.BinOp(_array_elements(copied)[i], ast.Mult(), astutil.expression(f"{module}.eye({size})[{i}]"))  # type: ignore[index]  # a copy of `node`

    for i, element in enumerate(elements):
        if not (is_number_literal(element) and ast.literal_eval(element) == 0):
            yield f"kept only entry {i}, `{_short(element)}`, of `{_short(node)}`", one_entry(i)
    if _array_numbers(node) is not None:
        mean = round_significant((sum(ast.literal_eval(element) for element in elements) / size,))[0]
        shared = f"{module}.full({size}, {float(mean)!r})"
        yield f"shared one value, their mean {mean:g}, across the entries of `{_short(node)}`", lambda copied: astutil.expression(shared)


def _merged_factors(node: ast.AST) -> Optional[ast.expr]:
    """A product's number literals as one, wherever they stand among its factors (`c1 * (c2 * x)`,
    `c1 * np.eye(6)[3] * (c2 * x)`) -> `c * ...` with c = c1 * c2: constants fewer; likewise taken
    into an array literal among the factors, `c * (np.array([a, b]) * x)` or `c * np.array([a, b])`
    as `np.array([c*a, c*b]) * x`. The factors stay in their order. Not a static fold, since the
    product rounds differently, so it is scored like a deletion."""
    if not (isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult)):
        return None
    factors = _product_factors(node)
    numbers = [factor for factor in factors if is_number_literal(factor)]
    arrays = [factor for factor in factors if _array_numbers(factor) is not None]
    if not numbers or len(numbers) + len(arrays[:1]) < 2:
        return None
    value = math.prod(ast.literal_eval(number) for number in (numbers if arrays else numbers[1:]))
    target = arrays[0] if arrays else numbers[0]
    merged = _merged_literal(value, target)
    if merged is None:
        return None
    dropped = {id(number) for number in numbers if number is not target}

    def rebuilt(factor: ast.expr) -> Optional[ast.expr]:
        if factor is target:
            return merged
        if id(factor) in dropped:
            return None
        if not (isinstance(factor, ast.BinOp) and isinstance(factor.op, ast.Mult)):
            return factor
        left, right = rebuilt(factor.left), rebuilt(factor.right)
        return right if left is None else left if right is None else ast.BinOp(left, ast.Mult(), right)

    return rebuilt(node)


def _array_numbers(node: ast.AST) -> Optional[list[ast.expr]]:
    """The elements of `np.array([...])` when every one is a number literal (an array
    `_merged_literal` can scale); None otherwise."""
    elements = _array_elements(node)
    return elements if elements is not None and all(is_number_literal(element) for element in elements) else None


def _product_factors(node: ast.expr) -> list[ast.expr]:
    """The factors of a product, through nested products, in source order."""
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult):
        return _product_factors(node.left) + _product_factors(node.right)
    return [node]


def deletion_candidates(code: str, function_name: str = "policy", stop: Callable[[], bool] = lambda: False) -> list[Candidate]:
    """Every one-step simplification of `code` (see the module docstring), each cleaned by
    `remove_dead_code`, strictly smaller than `code`, without duplicates, in source-walk order;
    those made before `stop()` says so, which is asked before each (each costs a parse of the
    whole program: a program of a few hundred statements has thousands, minutes of work)."""
    tree = astutil.parse(code)
    strip_docstrings(tree)
    nodes = node_count(tree)
    seen = {ast.dump(astutil.parse(remove_dead_code(code, function_name)))}
    candidates: list[Candidate] = []
    parents = _parents(tree)
    walk_order = {id(node): i for i, node in enumerate(ast.walk(tree))}
    source = ast.unparse(tree)
    # Each deletion edits a fresh copy: parsing the source again is much faster than deepcopy,
    # and gives the same tree, walked in the same order, whenever unparsing loses nothing.
    reparses = ast.dump(astutil.parse(source)) == ast.dump(tree)
    for node, description, edit in _edits(tree, function_name, parents):
        if stop():
            break
        parent, name, index = parents[id(node)]
        if reparses:
            copied = astutil.parse(source)
            walked = list(ast.walk(copied))
            edit(walked[walk_order[id(node)]], walked[walk_order[id(parent)]], name, index)
        else:
            copies: dict[int, Any] = {}  # deepcopy's memo: each original node's copy, by id
            copied = copy.deepcopy(tree, copies)
            edit(copies[id(node)], copies[id(parent)], name, index)
        try:
            new_code = remove_dead_code(ast.unparse(ast.fix_missing_locations(copied)), function_name)
            new_tree = astutil.parse(new_code)
        except (SyntaxError, ValueError, RecursionError):
            continue
        dump, new_nodes = ast.dump(new_tree), node_count(new_tree)
        if dump in seen or new_nodes >= nodes or astutil.function(new_tree, function_name) is None:
            continue
        seen.add(dump)
        candidates.append(Candidate(description, new_code, new_nodes))
    return candidates
