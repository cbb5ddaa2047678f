"""Small AST helpers shared by every module that reads or rewrites program code: parsing,
finding a program's function, docstrings, the names a statement or a node binds, renaming identifiers, replacing nodes, and
counting nodes.

They work on `ast` trees only and never run code. Every parse in colmo goes through `parse`:
CPython (3.11, 3.12) keeps the recursion depth of its AST constructor in state shared by all
threads, so two threads parsing at once (the generation thread and the program threads of a
search) can fail one of them with `SystemError: AST constructor recursion depth mismatch`,
which ended a whole sweep; `parse` holds one lock while it builds a tree.
"""

from __future__ import annotations

import ast
import math
import threading
from typing import Collection, Iterator, Mapping, Sequence

_DEFINITIONS = (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)
_PARSING = threading.Lock()


def parse(source: str, filename: str = "<unknown>", mode: str = "exec") -> ast.AST:
    """`ast.parse`, one thread at a time (see the module docstring)."""
    with _PARSING:
        return ast.parse(source, filename=filename, mode=mode)


def expression(source: str) -> ast.expr:
    """The expression `source` parsed (`parse` in "eval" mode)."""
    return parse(source, mode="eval").body  # type: ignore[attr-defined,no-any-return]  # an ast.Expression


def function(tree: ast.Module, name: str) -> ast.FunctionDef | ast.AsyncFunctionDef | None:
    """The module-level function `name` of `tree` (its first definition), or None."""
    return next((s for s in tree.body if isinstance(s, (ast.FunctionDef, ast.AsyncFunctionDef)) and s.name == name), None)


def is_docstring(statement: ast.AST) -> bool:
    """A bare string statement: a docstring, or a comment written as a string."""
    return isinstance(statement, ast.Expr) and isinstance(statement.value, ast.Constant) and isinstance(statement.value.value, str)


def strip_docstrings(tree: ast.AST) -> None:
    """Drop docstrings and other bare string statements, in place; a block left empty gets `pass`."""
    for node in ast.walk(tree):
        for field in ("body", "orelse", "finalbody"):
            statements = getattr(node, field, None)
            if not isinstance(statements, list):
                continue
            kept = [s for s in statements if not is_docstring(s)]
            # A block that held only strings must still hold a statement (`finally: pass`);
            # an emptied `else` simply goes.
            if statements and not kept and field != "orelse" and not isinstance(node, ast.Module):
                kept = [ast.Pass()]
            setattr(node, field, kept)


def stored_names(targets: Sequence[ast.AST]) -> set[str]:
    """The plain names that assignment targets bind (`a, b[i] = ...` binds `a`)."""
    return {n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}


def bound_names(statement: ast.stmt) -> list[str]:
    """Names a module-level statement binds: imports, definitions, assignment targets."""
    if isinstance(statement, (ast.Import, ast.ImportFrom)):
        return [alias.asname or alias.name.split(".")[0] for alias in statement.names]
    if isinstance(statement, _DEFINITIONS):
        return [statement.name]
    if isinstance(statement, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
        targets = statement.targets if isinstance(statement, ast.Assign) else [statement.target]
        return sorted(stored_names(targets))
    return []  # statements that only run code


def bindings(node: ast.AST) -> Iterator[str]:
    """The names one node binds, wherever it is: stored names, parameters, definitions,
    imports, exception handlers, match captures, and the names `global`/`nonlocal` declare."""
    if isinstance(node, ast.Name) and not isinstance(node.ctx, ast.Load):
        yield node.id
    elif isinstance(node, ast.arg):
        yield node.arg
    elif isinstance(node, _DEFINITIONS):
        yield node.name
    elif isinstance(node, ast.alias):
        yield node.asname or node.name.split(".")[0]
    elif isinstance(node, (ast.ExceptHandler, ast.MatchAs, ast.MatchStar)) and node.name:
        yield node.name
    elif isinstance(node, ast.MatchMapping) and node.rest:
        yield node.rest
    elif isinstance(node, (ast.Global, ast.Nonlocal)):
        yield from node.names


def unbound_names(tree: ast.AST, predefined: Collection[str]) -> list[str]:
    """The names `tree` reads that nothing in it binds and `predefined` does not hold, in source
    order: each raises NameError where it is reached. Scopes are not told apart, so a name
    bound anywhere counts as bound everywhere (this never flags a name the program defines)."""
    bound = {name for node in ast.walk(tree) for name in bindings(node)}
    read = sorted(
        (node.lineno, node.col_offset, node.id) for node in ast.walk(tree)
        if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Load) and node.id not in bound and node.id not in predefined
    )
    return list(dict.fromkeys(name for _, _, name in read))


# Fields whose subtree is no value a rewrite may replace or drop on its own: an index and what it
# indexes (`obs[2]`), a callee (`np.tanh`), an attribute's object (`np` in `np.pi`).
OPAQUE_FIELDS = {(ast.Subscript, "slice"), (ast.Subscript, "value"), (ast.Call, "func"), (ast.Attribute, "value")}


# Fields of AST nodes that bind or name an identifier, besides Name, Attribute and imports.
IDENTIFIER_FIELDS = {
    ast.FunctionDef: "name", ast.AsyncFunctionDef: "name", ast.ClassDef: "name", ast.arg: "arg",
    ast.keyword: "arg", ast.ExceptHandler: "name", ast.MatchAs: "name", ast.MatchStar: "name",
    ast.MatchMapping: "rest",
}


def identifiers(tree: ast.AST) -> set[str]:
    """Every identifier the code binds or uses (attribute names excluded)."""
    names = set()
    for node in ast.walk(tree):
        for field in ("id", "arg", "name", "asname", "rest"):
            value = getattr(node, field, None)
            if isinstance(value, str):
                names.add(value)
        if isinstance(node, (ast.Global, ast.Nonlocal)):
            names.update(node.names)
    return names


def rename(tree: ast.AST, names: Mapping[str, str]) -> None:
    """Rename identifiers everywhere they are bound or used, in place: names, parameters,
    definitions, import aliases, global statements, and the keyword arguments of calls to the
    code's own functions (a renamed parameter). Attribute names are not identifiers."""
    local_functions = {n.name for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))}
    for node in ast.walk(tree):  # breadth-first: a call is seen before its callee's name changes
        if isinstance(node, ast.Name):
            node.id = names.get(node.id, node.id)
        elif isinstance(node, ast.arg):
            node.arg = names.get(node.arg, node.arg)
        elif isinstance(node, (*_DEFINITIONS, ast.ExceptHandler)) and node.name is not None:
            node.name = names.get(node.name, node.name)
        elif isinstance(node, ast.alias) and (node.asname or node.name) in names:
            node.asname = names[node.asname or node.name]
        elif isinstance(node, (ast.Global, ast.Nonlocal)):
            node.names = [names.get(name, name) for name in node.names]
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in local_functions:
            for keyword in node.keywords:
                if keyword.arg is not None:
                    keyword.arg = names.get(keyword.arg, keyword.arg)


class _Replace(ast.NodeTransformer):
    def __init__(self, replacements: Mapping[int, ast.AST]):
        self.replacements = replacements

    def visit(self, node: ast.AST) -> ast.AST:
        replacement = self.replacements.get(id(node))
        return replacement if replacement is not None else self.generic_visit(node)


def replace_nodes(tree: ast.AST, replacements: Mapping[int, ast.AST]) -> ast.AST:
    """Swap nodes, identified by `id()`, for their replacements; returns the (new) root."""
    return _Replace(replacements).visit(tree)


def names_read(node: ast.AST) -> list[str]:
    """The names `node` reads (loads), each once, in walk order."""
    return list(dict.fromkeys(n.id for n in ast.walk(node) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)))


def negated(node: ast.expr) -> ast.expr:
    """`-node`, with the sign on a leading literal factor: `-(0.3 * x)` is `-0.3 * x`, exactly."""
    if is_number_literal(node):
        return number_literal(-ast.literal_eval(node))
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Mult, ast.Div)) and is_number_literal(node.left):
        return ast.BinOp(negated(node.left), node.op, node.right)
    return ast.UnaryOp(ast.USub(), node)


def is_number_literal(node: ast.AST) -> bool:
    """An int or float literal, possibly signed: `-3.2` is one literal (one tunable constant),
    not an operator applied to one. Booleans are not numbers here."""
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        node = node.operand
    return isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool)


def number_literal(value: int | float | bool) -> ast.expr:
    """The literal for a number; a negative one (-0.0 too) is written `-x`, a unary minus, so
    that `ast.unparse` parenthesizes it where needed: `(-2.0) ** 2`."""
    if isinstance(value, bool) or not math.copysign(1.0, value) < 0:
        return ast.Constant(value)
    return ast.UnaryOp(ast.USub(), ast.Constant(-value))


def node_count(tree: ast.AST) -> int:
    """AST nodes, without the context and operator markers (`Load`, `Add`, ...), which are
    part of the node that holds them: `a + b` is 3 nodes. A signed number literal (`-3.2`) is one
    node, as it is one constant, so a constant tuned across zero leaves the count unchanged."""
    labels = (ast.expr_context, ast.operator, ast.boolop, ast.unaryop, ast.cmpop)
    # A signed literal's sign is a label too: its number, the operand, is the one node counted.
    return sum(1 for node in ast.walk(tree) if not isinstance(node, labels) and not (isinstance(node, ast.UnaryOp) and is_number_literal(node)))
