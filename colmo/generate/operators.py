"""The genetic operators of the embedded `mutate` generator, on the AST of a policy function.

`Pieces` draws random code fragments for the children of one prompt, written with the names
and observation entries its programs use: terms (`c * feature`, PD feedback), conditions,
wrappers. `MUTATIONS` (with their weights; `ACTUATOR_MUTATIONS` too where the action is a
vector, and `JOINT_MUTATIONS` where `llm.joint_terms` asks) and `CROSSOVERS` each edit a policy
function in place and say whether they found something to edit; `colmo.generate.mutate`
documents what each does and chooses among them.
"""

from __future__ import annotations

import ast
import copy
from typing import Any, Callable, Optional, Sequence

import numpy as np

from colmo import astutil
from colmo.astutil import OPAQUE_FIELDS, is_docstring, replace_nodes

_FUNCTIONS = ("sin", "cos", "tanh", "sign", "abs")
_ARITHMETIC = (ast.Add, ast.Sub, ast.Mult, ast.Div)
_FLIPPED = {ast.Lt: ast.Gt, ast.Gt: ast.Lt, ast.LtE: ast.GtE, ast.GtE: ast.LtE, ast.Eq: ast.NotEq, ast.NotEq: ast.Eq}
_VALUE_KINDS = (ast.BinOp, ast.Call, ast.Name, ast.Attribute, ast.Subscript, ast.IfExp)


def _is_number(node: ast.AST) -> bool:
    return isinstance(node, ast.Constant) and type(node.value) in (int, float)


def _is_value(node: ast.AST, parent: ast.AST) -> bool:
    if isinstance(node, ast.Constant):
        # Integers handed to calls are sizes, counts and axes, not values.
        return _is_number(node) and not (type(node.value) is int and isinstance(parent, (ast.Call, ast.keyword)))
    if isinstance(node, ast.UnaryOp):
        return not isinstance(node.op, ast.Not)
    return isinstance(node, _VALUE_KINDS) and isinstance(getattr(node, "ctx", ast.Load()), ast.Load)


def value_nodes(root: ast.AST) -> list[ast.expr]:
    """Expressions a mutation may rewrite, in source order: numeric values, but no indices,
    called functions, attribute owners, assignment targets or sizes."""
    found = []

    def visit(node: ast.AST) -> None:
        for field, value in ast.iter_fields(node):
            if (type(node), field) in OPAQUE_FIELDS:
                continue
            for child in value if isinstance(value, list) else [value]:
                if isinstance(child, ast.AST):
                    if _is_value(child, node):
                        found.append(child)
                    visit(child)

    visit(root)
    return found


def policy_function(tree: ast.Module) -> ast.FunctionDef:
    function = astutil.function(tree, "policy")
    if not isinstance(function, ast.FunctionDef):  # intake refuses such a program before it is stored
        raise ValueError("the program defines no policy() to mutate")
    return function


def _replace(root: ast.AST, old: ast.AST, new: ast.AST) -> None:
    replace_nodes(root, {id(old): new})


def _statement_lists(fn: ast.FunctionDef) -> list[list[ast.stmt]]:
    """Every block of statements in the function: its body and those of its ifs and loops."""
    return [
        block
        for node in ast.walk(fn)
        for block in (getattr(node, "body", None), getattr(node, "orelse", None))
        if isinstance(block, list) and block and isinstance(block[0], ast.stmt)
    ]


class Pieces:
    """Random code fragments for the children of one prompt, written with the names and
    observation entries its programs use."""

    def __init__(self, rng: np.random.Generator, parents: Sequence[Any], stated_obs_size: Optional[int], action_size: int = 1):
        self.rng = rng
        self.action_size = action_size  # entries of the action vector (1: a scalar action)
        self.obs = parents[0].fn.args.args[0].arg if parents[0].fn.args.args else "obs"
        imports = [a for n in parents[0].tree.body if isinstance(n, ast.Import) for a in n.names]
        self.np = next(a.asname or a.name for a in imports if a.name == "numpy")
        seen = sorted({
            n.slice.value
            for p in parents
            for n in ast.walk(p.fn)
            if isinstance(n, ast.Subscript) and isinstance(n.value, ast.Name) and n.value.id == self.obs
            and _is_number(n.slice) and type(n.slice.value) is int  # obs[-1] is a UnaryOp: left out
        })
        self.obs_size = stated_obs_size or 1 + max(seen, default=0)
        self.indices = range(self.obs_size) if stated_obs_size else seen or [0]
        self.names = sorted({
            n.id for p in parents for n in ast.walk(p.fn) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)
        })

    def pick(self, items: Sequence[Any]) -> Any:
        return items[self.rng.integers(len(items))] if len(items) else None

    def magnitude(self, high: float = 1.0) -> str:
        """A positive constant from 0.1 to 10**high, log-uniform, to 3 significant digits."""
        return repr(float(f"{10 ** self.rng.uniform(-1.0, high):.3g}"))

    def entries(self, k: int) -> list[str]:
        """`k` observation entries, distinct where there are enough."""
        indices = self.rng.choice(self.indices, size=k, replace=len(self.indices) < k)
        return [f"{self.obs}[{i}]" for i in indices]

    def feature(self) -> str:
        # Weighted toward plain entries: linear feedback is the backbone of most controllers.
        kind = self.pick(["entry"] * 3 + ["function"] * 2 + ["product", "square", "angle"] + ["name"] * bool(self.names))
        first, second = self.entries(2)
        if kind == "function":
            return f"{self.np}.{self.pick(_FUNCTIONS)}({first})"
        if kind == "product":
            return f"{first} * {second}"
        if kind == "square":
            return f"{first} ** 2"
        if kind == "angle":
            return f"{self.np}.arctan2({first}, {second})"
        return self.pick(self.names) if kind == "name" else first

    def sign(self) -> str:
        return self.pick(("", "-"))

    def term(self) -> ast.expr:
        """`c * feature`, or linear feedback on two entries `c1 * obs[i] + c2 * obs[j]` (PD)."""
        if self.rng.random() < 0.4:
            first, second = self.entries(2)
            return astutil.expression(f"{self.sign()}{self.magnitude()} * {first} {self.pick('+-')} {self.magnitude()} * {second}")
        return astutil.expression(f"{self.sign()}{self.magnitude()} * {self.feature()}")

    def gains(self) -> str:
        """A gain per actuator, `np.array([c1, ..., cK])`: random signs and magnitudes from 0.1 to 1."""
        values = ", ".join(f"{self.sign()}{self.magnitude(high=0.0)}" for _ in range(self.action_size))
        return f"{self.np}.array([{values}])"

    def extended(self, node: ast.expr) -> ast.expr:
        """`node + c * feature` or `node - c * feature`."""
        return ast.BinOp(node, self.pick((ast.Add, ast.Sub))(), astutil.expression(f"{self.magnitude()} * {self.feature()}"))

    def condition(self) -> ast.expr:
        """A threshold on an observation entry (half the time) or another feature, or on its
        absolute value; thresholds from 0.1 to 2, the scale of angles, cosines, velocities."""
        [entry] = self.entries(1)
        x = entry if self.rng.random() < 0.5 else self.feature()
        if self.rng.random() < 0.3:
            return astutil.expression(f"{self.np}.abs({x}) {self.pick('<>')} {self.magnitude(high=0.3)}")
        return astutil.expression(f"{x} {self.pick('<>')} {self.sign()}{self.magnitude(high=0.3)}")

    def wrapped(self, node: ast.expr) -> ast.expr:
        function = self.pick(_FUNCTIONS + ("clip",))
        bounds = f", -{self.magnitude()}, {self.magnitude()}" if function == "clip" else ""
        return astutil.expression(f"{self.np}.{function}({ast.unparse(node)}{bounds})")


# Each mutation edits the policy function in place and says whether it found something to edit.

def _insert_term(fn: ast.FunctionDef, pieces: Pieces) -> bool:
    target = pieces.pick(value_nodes(fn))
    if target is None:
        return False
    _replace(fn, target, pieces.extended(target))
    return True


def _replace_subtree(fn: ast.FunctionDef, pieces: Pieces) -> bool:
    target = pieces.pick(value_nodes(fn))
    if target is None:
        return False
    _replace(fn, target, pieces.term())
    return True


def _wrap(fn: ast.FunctionDef, pieces: Pieces) -> bool:
    target = pieces.pick([node for node in value_nodes(fn) if not isinstance(node, ast.Constant)])
    if target is None:
        return False
    _replace(fn, target, pieces.wrapped(target))
    return True


def _hoist(fn: ast.FunctionDef, pieces: Pieces) -> bool:
    """Replace an expression with one of its own subexpressions: the counterweight to growth."""
    nodes = [(node, inner) for node in value_nodes(fn) if (inner := value_nodes(node))]
    if not nodes:
        return False
    node, inner = pieces.pick(nodes)
    _replace(fn, node, pieces.pick(inner))
    return True


def _add_branch(fn: ast.FunctionDef, pieces: Pieces) -> bool:
    blocks = [
        (block, i) for block in _statement_lists(fn)
        for i, s in enumerate(block) if isinstance(s, (ast.Assign, ast.AugAssign, ast.Return)) and s.value
    ]
    if not blocks:
        return False
    block, i = pieces.pick(blocks)
    other = copy.deepcopy(block[i])
    other.value = pieces.term() if pieces.rng.random() < 0.5 else pieces.extended(other.value)
    block[i] = ast.If(pieces.condition(), [block[i]], [other])
    return True


def _remove_branch(fn: ast.FunctionDef, pieces: Pieces) -> bool:
    branches = [(block, i) for block in _statement_lists(fn) for i, s in enumerate(block) if isinstance(s, ast.If)]
    if not branches:
        return False
    block, i = pieces.pick(branches)
    sides = [side for side in (block[i].body, block[i].orelse) if side]
    block[i:i + 1] = pieces.pick(sides)
    return True


def _delete_statement(fn: ast.FunctionDef, pieces: Pieces) -> bool:
    candidates = [
        (block, i) for block in _statement_lists(fn) if len(block) > 1
        for i, s in enumerate(block) if not isinstance(s, ast.Return) and not is_docstring(s)
    ]
    if not candidates:
        return False
    block, i = pieces.pick(candidates)
    del block[i]
    return True


def _swap_statements(fn: ast.FunctionDef, pieces: Pieces) -> bool:
    pairs = [
        (block, i) for block in _statement_lists(fn) for i in range(len(block) - 1)
        if not any(isinstance(s, ast.Return) or is_docstring(s) for s in block[i:i + 2])
    ]
    if not pairs:
        return False
    block, i = pieces.pick(pairs)
    block[i], block[i + 1] = block[i + 1], block[i]
    return True


def _change_operator(fn: ast.FunctionDef, pieces: Pieces) -> bool:
    nodes = [n for n in ast.walk(fn) if isinstance(n, (ast.BinOp, ast.AugAssign)) and isinstance(n.op, _ARITHMETIC)]
    if not nodes:
        return False
    node = pieces.pick(nodes)
    node.op = pieces.pick([op for op in _ARITHMETIC if not isinstance(node.op, op)])()
    return True


def _flip_comparison(fn: ast.FunctionDef, pieces: Pieces) -> bool:
    nodes = [n for n in ast.walk(fn) if isinstance(n, ast.Compare) and type(n.ops[0]) in _FLIPPED]
    if not nodes:
        return False
    node = pieces.pick(nodes)
    node.ops[0] = _FLIPPED[type(node.ops[0])]()
    return True


def _insert_actuator_term(fn: ast.FunctionDef, pieces: Pieces) -> bool:
    """`e` -> `e + np.array([c1, ..., cK]) * f` where `e` is what the policy returns (a returned
    expression, or the value of a variable it returns): each actuator its own gain on a feature.
    The other terms give every actuator the same value; a gait needs joints that differ."""
    return _add_to_action(fn, pieces, lambda: astutil.expression(f"{pieces.gains()} * {pieces.feature()}"))


def _insert_joint_term(fn: ast.FunctionDef, pieces: Pieces) -> bool:
    """`e` -> `e + c * np.eye(K)[j] * f`: one actuator's own gain on a feature, one constant
    where an actuator term has K (a search capped by `database.max_constants` can afford it)."""
    def term() -> ast.expr:
        selector = f"{pieces.np}.eye({pieces.action_size})[{pieces.rng.integers(pieces.action_size)}]"
        return astutil.expression(f"{pieces.sign()}{pieces.magnitude()} * {selector} * {pieces.feature()}")

    return _add_to_action(fn, pieces, term)


def _add_to_action(fn: ast.FunctionDef, pieces: Pieces, term: Callable[[], ast.expr]) -> bool:
    """`e` -> `e + term()` where `e` is what the policy returns (a returned expression, or the value
    of a variable it returns); the term is drawn after the statement."""
    returned = {n.id for r in ast.walk(fn) if isinstance(r, ast.Return) and r.value for n in ast.walk(r.value) if isinstance(n, ast.Name)}
    targets = [
        s for s in ast.walk(fn)
        if (isinstance(s, ast.Return) and s.value is not None)
        or (isinstance(s, ast.Assign) and len(s.targets) == 1 and isinstance(s.targets[0], ast.Name) and s.targets[0].id in returned)
    ]
    statement = pieces.pick(targets)
    if statement is None:
        return False
    statement.value = ast.BinOp(statement.value, ast.Add(), term())
    return True


def _redraw_constant(fn: ast.FunctionDef, pieces: Pieces) -> bool:
    constant = pieces.pick([node for node in value_nodes(fn) if _is_number(node)])
    if constant is None:
        return False
    constant.value = float(pieces.magnitude())
    return True


# (operator, weight): terms and branches build controllers; hoisting and deleting keep them short.
MUTATIONS = (
    (_insert_term, 3.0),
    (_replace_subtree, 2.0),
    (_add_branch, 2.0),
    (_wrap, 1.0),
    (_hoist, 1.5),
    (_remove_branch, 1.0),
    (_delete_statement, 1.0),
    (_swap_statements, 0.5),
    (_change_operator, 1.0),
    (_flip_comparison, 1.0),
    (_redraw_constant, 0.5),
)
# Added to `MUTATIONS` where the action is a vector.
ACTUATOR_MUTATIONS = ((_insert_actuator_term, 2.0),)
# Added too where `llm.joint_terms` asks for them.
JOINT_MUTATIONS = ((_insert_joint_term, 1.0),)


# Each crossover edits a copy of the first program's policy, taking material from the second's.

def _merge(fn: ast.FunctionDef, other: ast.FunctionDef, pieces: Pieces) -> bool:
    """Run both bodies (the second's variables renamed where they clash), then blend or switch
    between the two results."""
    def single_return(f: ast.FunctionDef) -> bool:
        returns = [n for n in ast.walk(f) if isinstance(n, ast.Return)]
        return len(returns) == 1 and f.body[-1] is returns[0] and returns[0].value is not None

    if not (single_return(fn) and single_return(other)):
        return False
    used = {n.id for n in ast.walk(fn) if isinstance(n, ast.Name)}
    clashes = used & {n.id for n in ast.walk(other) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}
    body = copy.deepcopy(other.body)
    for node in ast.walk(ast.Module(body, [])):
        if isinstance(node, ast.Name) and node.id in clashes:
            node.id += "_b"
    first, second = fn.body[-1].value, body[-1].value
    if pieces.rng.random() < 0.5:
        result = astutil.expression(f"0.5 * ({ast.unparse(first)}) + 0.5 * ({ast.unparse(second)})")
    else:
        result = ast.IfExp(pieces.condition(), first, second)
    fn.body[-1:] = [s for s in body[:-1] if not is_docstring(s)] + [ast.Return(result)]
    return True


def _splice_statement(fn: ast.FunctionDef, other: ast.FunctionDef, pieces: Pieces) -> bool:
    statements = [s for s in other.body if not isinstance(s, ast.Return) and not is_docstring(s)]
    if not statements:
        return False
    block = pieces.pick(_statement_lists(fn))
    first, end = int(is_docstring(block[0])), len(block) - isinstance(block[-1], ast.Return)
    block.insert(int(pieces.rng.integers(first, end + 1)), copy.deepcopy(pieces.pick(statements)))
    return True


def _splice_expression(fn: ast.FunctionDef, other: ast.FunctionDef, pieces: Pieces) -> bool:
    target, donor = pieces.pick(value_nodes(fn)), pieces.pick(value_nodes(other))
    if target is None or donor is None:
        return False
    _replace(fn, target, copy.deepcopy(donor))
    return True


CROSSOVERS = (_merge, _splice_statement, _splice_expression)


