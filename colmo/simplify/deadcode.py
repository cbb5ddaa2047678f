"""Dead code: what a policy program can lose without computing different actions.

`remove_dead_code` is static and behaviour-preserving. It drops docstrings, `pass` and pure
expression statements, statements after `return`/`raise`/`break`/`continue` (or after an `if`
whose every branch ends so), `if`/`while`/conditional expressions on constant conditions,
assignments whose value is never read afterwards (backward liveness over the function's control
flow), locals that are only ever written (`a = np.zeros(3); a[0] = 1.0` with `a` never read),
and module-level imports, helpers and constants nothing reads; and it folds literal arithmetic
(`colmo.simplify.fold`). Only pure code goes (`colmo.simplify.scope`), so removing it can only
remove an exception it would have raised on inputs where it ran. Liveness is conservative:
statements it does not model (try, with, match, del, class...) are kept whole and keep every
name they mention alive. Branches never taken on the scored episodes are not static dead code:
the greedy stage removes them as measured deletions.
"""

from __future__ import annotations

import ast
import copy
from dataclasses import dataclass
from typing import Iterator, Optional

from colmo import astutil
from colmo.astutil import bindings, names_read, strip_docstrings
from colmo.simplify.fold import Fold, fold_accumulator_starts
from colmo.simplify.scope import Scope

BLOCKS = ("body", "orelse", "finalbody")
FUNCTIONS = (ast.FunctionDef, ast.AsyncFunctionDef)


def _reads(node: ast.AST) -> set[str]:
    return set(names_read(node))


def _target_reads(target: ast.expr) -> set[str]:
    """Names an assignment target reads: the owners and indices of subscript and attribute targets."""
    if isinstance(target, ast.Name):
        return set()
    if isinstance(target, (ast.Tuple, ast.List)):
        return set().union(*(_target_reads(t) for t in target.elts))
    if isinstance(target, ast.Starred):
        return _target_reads(target.value)
    return _reads(target)


def _target_names(target: ast.expr) -> Optional[set[str]]:
    """The names a target binds if it binds only names (`a`, `a, b`, `a, *b`), else None."""
    if isinstance(target, ast.Name):
        return {target.id}
    if isinstance(target, ast.Starred):
        return _target_names(target.value)
    if isinstance(target, (ast.Tuple, ast.List)):
        parts = [_target_names(t) for t in target.elts]
        return None if any(p is None for p in parts) else set().union(*parts)
    return None


def _ends_block(statement: ast.stmt) -> bool:
    """Control never reaches the statement after this one."""
    if isinstance(statement, (ast.Return, ast.Raise, ast.Break, ast.Continue)):
        return True
    if isinstance(statement, ast.If):
        return bool(statement.orelse) and _block_ends(statement.body) and _block_ends(statement.orelse)
    if isinstance(statement, ast.While):
        return isinstance(statement.test, ast.Constant) and bool(statement.test.value) and not _breaks(statement.body)
    return False


def _block_ends(block: list[ast.stmt]) -> bool:
    return any(_ends_block(s) for s in block)


def _breaks(block: list[ast.stmt]) -> bool:
    """A `break` in `block` that leaves the loop owning the block (not one of an inner loop)."""
    for statement in block:
        if isinstance(statement, ast.Break):
            return True
        if isinstance(statement, (*FUNCTIONS, ast.ClassDef)):
            continue
        if isinstance(statement, (ast.For, ast.AsyncFor, ast.While)):
            inner = [statement.orelse]  # an inner loop's `else` clause runs in the outer loop
        else:
            inner = _child_blocks(statement)
        if any(_breaks(b) for b in inner):
            return True
    return False


def _child_blocks(statement: ast.stmt) -> list[list[ast.stmt]]:
    """The statement lists directly inside a statement (bodies, else, finally, handlers, cases)."""
    blocks = [getattr(statement, name) for name in BLOCKS if isinstance(getattr(statement, name, None), list)]
    blocks += [item.body for item in (getattr(statement, "handlers", None) or []) + (getattr(statement, "cases", None) or [])]
    return blocks


class _Statements:
    """Block-level clean-up: constant conditions, unreachable code, `pass`, pure expressions."""

    def __init__(self, scope: Scope):
        self.scope = scope

    def block(self, statements: list[ast.stmt], keep_empty: bool = False) -> list[ast.stmt]:
        kept: list[ast.stmt] = []
        for statement in statements:
            for replacement in self.statement(statement):
                kept.append(replacement)
                if _ends_block(replacement):
                    break
            else:
                continue
            break
        without_pass = [s for s in kept if not isinstance(s, ast.Pass)]
        if without_pass or keep_empty:
            return without_pass
        return [ast.Pass()]

    def statement(self, statement: ast.stmt) -> list[ast.stmt]:
        if isinstance(statement, ast.If) and isinstance(statement.test, ast.Constant):
            return self.block(statement.body if statement.test.value else statement.orelse, keep_empty=True)
        if isinstance(statement, ast.While) and isinstance(statement.test, ast.Constant) and not statement.test.value:
            return self.block(statement.orelse, keep_empty=True)
        if isinstance(statement, ast.Expr) and self.scope.is_pure(statement.value):
            return []
        if isinstance(statement, ast.ClassDef):
            return [statement]  # class bodies are namespaces: left as written
        for name in BLOCKS:
            block = getattr(statement, name, None)
            if isinstance(block, list) and block:
                optional = name != "body" and not isinstance(statement, ast.Try)
                setattr(statement, name, self.block(block, keep_empty=optional))
        for handler in getattr(statement, "handlers", None) or []:
            handler.body = self.block(handler.body)
        for case in getattr(statement, "cases", None) or []:
            case.body = self.block(case.body)
        if isinstance(statement, ast.If) and _is_pass(statement.body) and not statement.orelse and self.scope.is_pure(statement.test):
            return []
        return [statement]


def _is_pass(block: list[ast.stmt]) -> bool:
    return all(isinstance(s, ast.Pass) for s in block)


@dataclass
class _Flow:
    """Where `break` and `continue` jump, as the names live there."""

    after_loop: Optional[set[str]] = None
    loop_head: Optional[set[str]] = None


class _Liveness:
    """Backward liveness over structured control flow; drops assignments nothing reads afterwards.

    Conservative: statements it does not model (try, with, match, del, class...) kill nothing and
    keep everything they read live, as well as where their `break`/`continue` would jump."""

    def __init__(self, scope: Scope, pinned: set[str]):
        self.scope = scope
        self.pinned = pinned  # never removed: globals, nonlocals, names nested scopes read

    def block(self, statements: list[ast.stmt], live: set[str], flow: _Flow) -> tuple[list[ast.stmt], set[str]]:
        kept: list[ast.stmt] = []
        for statement in reversed(statements):
            result, live = self.statement(statement, live, flow)
            if result is not None:
                kept.append(result)
        return kept[::-1], live

    def removable(self, names: set[str], live: set[str]) -> bool:
        return not (names & live) and not (names & self.pinned)

    def statement(self, s: ast.stmt, live: set[str], flow: _Flow) -> tuple[Optional[ast.stmt], set[str]]:
        if isinstance(s, ast.Return):
            return s, _reads(s.value) if s.value else set()
        if isinstance(s, ast.Raise):
            return s, _reads(s)
        if isinstance(s, ast.Break):
            return s, set(flow.after_loop or ())
        if isinstance(s, ast.Continue):
            return s, set(flow.loop_head or ())
        if isinstance(s, (ast.Assign, ast.AnnAssign)):
            targets = s.targets if isinstance(s, ast.Assign) else [s.target]
            if s.value is None:
                return s, live
            names = [_target_names(t) for t in targets]
            if all(n is not None for n in names):
                bound = set().union(*names)
                if self.removable(bound, live) and self.scope.is_pure(s.value):
                    return None, live
                return s, (live - bound) | _reads(s.value)
            return s, live | _reads(s.value) | set().union(*(_target_reads(t) for t in targets))
        if isinstance(s, ast.AugAssign):  # `a += v` reads `a` (and may write into its object)
            return s, live | _reads(s.value) | {n.id for n in ast.walk(s.target) if isinstance(n, ast.Name)}
        if isinstance(s, (ast.Import, ast.ImportFrom)):
            if any(alias.name == "*" for alias in s.names):
                return s, live
            aliases = [a for a in s.names if not self.removable(set(bindings(a)), live)]
            if not aliases:
                return None, live
            s.names = aliases
            return s, live - {name for a in aliases for name in bindings(a)}
        if isinstance(s, FUNCTIONS):  # a definition runs its decorators and defaults only
            evaluated = [*s.decorator_list, *s.args.defaults, *(d for d in s.args.kw_defaults if d)]
            if self.removable({s.name}, live) and all(self.scope.is_pure(e) for e in evaluated):
                return None, live
            return s, (live - {s.name}) | set().union(*(_reads(e) for e in evaluated))
        if isinstance(s, ast.If):
            s.body, live_body = self.block(s.body, live, flow)
            s.orelse, live_else = self.block(s.orelse, live, flow)
            if not s.body:
                s.body = [ast.Pass()]
            return s, _reads(s.test) | live_body | live_else
        if isinstance(s, (ast.For, ast.While)):
            return self.loop(s, live, flow)
        if isinstance(s, (ast.Expr, ast.Pass, ast.Global, ast.Nonlocal, ast.Assert)):
            return s, live | _reads(s)
        # Anything else (try, with, match, del...): keep it whole, kill nothing, and count every
        # name it mentions as read (`del x` needs x bound), as well as where it may jump to.
        jumps = (flow.after_loop or set()) | (flow.loop_head or set())
        return s, live | {n.id for n in ast.walk(s) if isinstance(n, ast.Name)} | jumps

    def loop(self, s: ast.For | ast.While, live: set[str], flow: _Flow) -> tuple[ast.stmt, set[str]]:
        _, live_else = self.block(copy.deepcopy(s.orelse), live, flow)
        head = set(live_else)
        while True:  # the names live at the loop head grow to a fixpoint
            body = copy.deepcopy(s.body)
            _, live_body = self.block(body, head, _Flow(after_loop=live, loop_head=head))
            if isinstance(s, ast.For):
                new_head = live_else | (live_body - (_target_names(s.target) or set())) | _target_reads(s.target)
            else:
                new_head = live_else | live_body | _reads(s.test)
            if new_head <= head:
                break
            head |= new_head
        s.body, _ = self.block(s.body, head, _Flow(after_loop=live, loop_head=head))
        s.body = s.body or [ast.Pass()]
        s.orelse, _ = self.block(s.orelse, live, flow)
        return s, (head | _reads(s.iter)) if isinstance(s, ast.For) else head


def _nested_scope_reads(function: ast.AST) -> set[str]:
    """Names read inside functions, lambdas and classes nested in `function` (read at call time)."""
    reads: set[str] = set()
    for node in ast.walk(function):
        if node is not function and isinstance(node, (*FUNCTIONS, ast.Lambda, ast.ClassDef)):
            reads |= _reads(node)
    return reads


def _declared(function: ast.AST) -> set[str]:
    return {name for node in ast.walk(function) if isinstance(node, (ast.Global, ast.Nonlocal)) for name in node.names}


def _pinned(function: ast.FunctionDef | ast.AsyncFunctionDef) -> set[str]:
    """Locals no removal may touch: declared global or nonlocal, or read by nested scopes."""
    return _declared(function) | _nested_scope_reads(function)


def _function_liveness(function: ast.FunctionDef | ast.AsyncFunctionDef, scope: Scope, pinned: set[str]) -> None:
    function.body, _ = _Liveness(scope, pinned).block(function.body, set(), _Flow())
    function.body = function.body or [ast.Pass()]


def _write_only_locals(function: ast.FunctionDef | ast.AsyncFunctionDef, scope: Scope, pinned: set[str]) -> None:
    """Drop every statement about a local that is bound to fresh values and never read, only written
    into (`a = np.zeros(3)`, `a[0] = x`, `a += 1`): liveness keeps these, since writes read the owner."""
    arguments = {a.arg for a in ast.walk(function.args) if isinstance(a, ast.arg)}
    writes: dict[str, list[ast.stmt]] = {}
    disqualified: set[str] = arguments | pinned
    write_positions: set[int] = set()
    for statement in own_statements(function.body):
        owner = _written_owner(statement, scope)
        if owner is not None:
            writes.setdefault(owner, []).append(statement)
            write_positions.add(id(_owner_name(statement.targets[0] if isinstance(statement, ast.Assign) else statement.target)))
    for node in ast.walk(function):
        if node is function:
            continue
        if isinstance(node, ast.Name) and id(node) not in write_positions:
            disqualified.add(node.id)  # read, or bound some other way (for, with, except, walrus...)
        elif not isinstance(node, ast.Name):
            disqualified.update(bindings(node))
    # Only locals: a name with no binding here is a global, and writing into it is an effect.
    local = {name for name, statements in writes.items() if any(isinstance(s, ast.Assign) and isinstance(s.targets[0], ast.Name) for s in statements)}
    dead = {id(s) for name in local - disqualified for s in writes[name]}
    if dead:
        _remove_statements(function, dead)


def _written_owner(statement: ast.stmt, scope: Scope) -> Optional[str]:
    """The local a statement only writes (`a = fresh`, `a[...] = v`, `a += v`, `a[...] += v`), if pure."""
    if isinstance(statement, ast.Assign) and len(statement.targets) == 1:
        target, value = statement.targets[0], statement.value
        if isinstance(target, ast.Name):
            return target.id if scope.is_fresh(value) and scope.is_pure(value) else None
    elif isinstance(statement, ast.AugAssign):
        target, value = statement.target, statement.value
    else:
        return None
    while isinstance(target, ast.Subscript):
        if not scope.is_pure(target.slice):
            return None
        target = target.value
    return target.id if isinstance(target, ast.Name) and scope.is_pure(value) else None


def _owner_name(target: ast.expr) -> ast.expr:
    while isinstance(target, ast.Subscript):
        target = target.value
    return target


def own_statements(block: list[ast.stmt]) -> Iterator[ast.stmt]:
    """Statements of a function body, nested blocks included, nested functions and classes excluded."""
    for statement in block:
        yield statement
        if not isinstance(statement, (*FUNCTIONS, ast.ClassDef)):
            for inner in _child_blocks(statement):
                yield from own_statements(inner)


def _remove_statements(root: ast.AST, dead: set[int]) -> None:
    for node in ast.walk(root):
        for name in BLOCKS:
            block = getattr(node, name, None)
            if isinstance(block, list) and any(id(s) in dead for s in block):
                kept = [s for s in block if id(s) not in dead]
                setattr(node, name, kept or ([ast.Pass()] if name == "body" or isinstance(node, ast.Try) else []))


def _module_liveness(tree: ast.Module, scope: Scope, function_name: str) -> None:
    """Module-level code runs once; functions read globals when called, after all of it ran."""
    read_by_functions: set[str] = {function_name}
    for node in ast.walk(tree):
        if isinstance(node, (*FUNCTIONS, ast.Lambda)):
            body = node.body if isinstance(node.body, list) else [node.body]
            read_by_functions |= set().union(*(_reads(s) for s in body))
    pinned = _declared(tree) | {function_name}
    tree.body, _ = _Liveness(scope, pinned).block(tree.body, read_by_functions, _Flow())


def remove_dead_code(code: str, function_name: str = "policy", for_reading: bool = False) -> str:
    """`code` without dead code and with literal arithmetic folded, as `ast.unparse` writes it
    (see the module docstring for what goes); the program computes the same actions.
    `for_reading`: as a prompt shows a program, the docstring of `function_name` kept (a task's
    starter says there what the observation and the action are) and named constants left
    unfolded (`2 * math.pi`, not `6.283185307179586`)."""
    tree = astutil.parse(code)
    docstring = _docstring_of(tree, function_name) if for_reading else None
    strip_docstrings(tree)
    before = ast.dump(tree)
    for _ in range(100):  # each pass only removes; the bound is a guard
        fold_accumulator_starts(tree)
        scope = Scope(tree)
        tree = Fold(scope, named=not for_reading).visit(tree)
        tree.body = _Statements(scope).block(tree.body, keep_empty=True)
        for node in ast.walk(tree):
            if isinstance(node, FUNCTIONS):
                # Computed before either removal; if stale for the second, the next pass redoes it.
                pinned = _pinned(node)
                _function_liveness(node, scope, pinned)
                _write_only_locals(node, scope, pinned)
        _module_liveness(tree, scope, function_name)
        dump = ast.dump(tree)
        if dump == before:
            break
        before = dump
    function = astutil.function(tree, function_name) if docstring is not None else None
    if function is not None:
        function.body = [ast.Expr(ast.Constant(docstring)), *(s for s in function.body if not isinstance(s, ast.Pass))]
    return ast.unparse(ast.fix_missing_locations(tree))


def _docstring_of(tree: ast.Module, function_name: str) -> Optional[str]:
    function = astutil.function(tree, function_name)
    return None if function is None else ast.get_docstring(function, clean=False)

