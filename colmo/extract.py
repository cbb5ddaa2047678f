"""Getting the policy program out of raw language-model output.

Rules, in the order they apply:
  * Code comes from the markdown fences (```python, ```py, plain ```; an unclosed last fence runs
    to the end of the answer). If no fence holds the function, the whole answer is searched, so
    bare code with prose around it works too.
  * Within a chunk, code starts at a line that opens a definition, an import or an assignment;
    the region keeps the indentation of that line (a uniform indent, as inside a class, is
    removed) and is cut to its longest parseable prefix. That drops prose after the code and the
    broken tail of a truncated answer; a definition left with an empty body by the cut was cut
    off and is dropped with it.
  * Candidates are top-level functions named `policy` or `policy_vN`. The newest is the one
    defined last in the answer (models write improved versions after older ones; the plain name
    wins only if it comes last); if its body is only a docstring, `pass` or `...`, the answer is
    rejected ("empty policy body"). Methods inside a class are not lifted out.
  * The result keeps the chosen function, renamed to `policy` (references to its old name
    too), plus the module-level imports, helper functions, classes and constant assignments it
    needs, followed transitively by name. Unused ones are dropped, so a stray import cannot fail
    the sandbox's import check. When a name is defined twice, the last definition wins. Other
    versions are dropped unless the chosen one calls them; top-level statements that run code
    (prints, tests, `if __name__ == ...`) are always dropped.
  * `import numpy as np` / `import math` are added when the code uses `np` / `math` unbound, and
    `from math import sqrt, pi` when it uses names of the math module (`sqrt`, `pi`, ...) that
    nothing in it binds.
  * A completion (a model continuing the prompt text, `prompt_format=completion`) is extracted
    with `prefix=` the prompt text it continues: prefix and completion are read as one answer
    without fences, and only a version whose definition ends in the completion can be chosen,
    so a continuation whose body does not parse is rejected instead of falling back to a
    version the prompt showed. The prompt's helpers can be used by the new version.
  * A chat answer is extracted with `shown=` the code its prompt showed (`Prompt.shown_code`):
    the answer may call what it saw there (`policy_v1(obs)`, a shown helper) without copying
    it, as a completion may; the answer's own definitions come after the shown ones, so they
    win, and the version chosen is always one the answer wrote.
  * Type annotations are dropped (`x: T = v` becomes `x = v`): they do not change what the
    policy computes, and the static check would read them as code.
The result is formatted by ast.unparse, which drops comments; the caller keeps the raw text.
"""

from __future__ import annotations

import ast
import bisect
import builtins
import math
import re
from typing import Iterator

from colmo import astutil
from colmo.astutil import bound_names, rename, unbound_names
from colmo.sandbox.namespace import PREDEFINED_NAMES

_FENCE = re.compile(r"\s*```")
# Lines that can open a stretch of code (definition, import, assignment); prose rarely does.
_CODE_START = re.compile(r"\s*(?:(?:async\s+)?def\s|class\s|import\s|from\s+[\w.]+\s+import\s|@\w|[A-Za-z_]\w*\s*(?::[^=]+)?=(?!=))")
_MISSING_IMPORTS = {"np": "import numpy as np", "numpy": "import numpy", "math": "import math"}
_MATH_NAMES = frozenset(name for name in dir(math) if not name.startswith("_"))
# Lines that continue the statement before them rather than start one.
_CLAUSE = re.compile(r"(?:else|elif|except|finally)\b")
# Parse errors of a piece that a later line may complete: an open string or bracket.
_OPEN = re.compile(r"never closed|unterminated triple-quoted|unexpected EOF")
# Characters ast.parse may read per character of the answer, plus a fixed allowance: every line
# is read about twice (fences, then the whole answer), so this is ample for any real answer.
_PARSE_BUDGET_FACTOR = 10
_PARSE_BUDGET_BASE = 50_000
# Shorter cuts tried on a broken statement before the run ends before it (each reads it again).
_MAX_CUTS = 3


# Names a shown function may never take: every builtin and every name a program finds predefined.
_RESERVED_NAMES = frozenset(dir(builtins)) | PREDEFINED_NAMES


class ExtractionError(ValueError):
    """No usable policy in the answer; the message is a one-line reason."""


def extract_policy(text: str, function_name: str = "policy", prefix: str = "", shown: str = "") -> str:
    """The policy module (imports, helpers, `def policy`) in a language model's answer `text`;
    for a completion, `prefix` is the prompt text that `text` continues; for a chat answer,
    `shown` is the code its prompt showed (colmo's own rendering), which the answer may use."""
    try:
        return _extract(text, function_name, prefix, shown)
    except (RecursionError, MemoryError):  # the parser and AST visitors recurse per nesting level
        raise ExtractionError("the answer is nested too deeply to parse") from None


def _extract(text: str, function_name: str, prefix: str, shown: str) -> str:
    version = re.compile(rf"{re.escape(function_name)}(?:_v\d+)?")
    budget = _ParseBudget(prefix + text)
    if prefix:
        statements = [s for module in _code_regions(prefix + text, budget) for s in module.body]
        # Lines up to here are the prompt's alone; the version the completion wrote ends after them.
        prompt_lines = prefix.count("\n")
        versions = [f for f in _versions(statements, version) if f.end_lineno > prompt_lines]
        if not versions:
            raise ExtractionError(f"the completion holds no complete body of '{function_name}'")
    else:
        statements = [s for block in _fenced_blocks(text) for module in _code_regions(block, budget) for s in module.body]
        if not _versions(statements, version):
            statements = [s for module in _code_regions(text, budget) for s in module.body]
        versions = _versions(statements, version)
        if shown:  # before the answer's statements, what the shown code may supply (`_supplied`)
            statements = _supplied(shown, statements) + statements
    if not versions:
        signature = re.search(rf"^[ \t]*def\s+{version.pattern}\s*\(", text, re.MULTILINE)
        if signature:
            where = _syntax_error_from(text, text.count("\n", 0, signature.start()))
            raise ExtractionError(f"found 'def {function_name}' but no complete top-level definition of it{where}")
        raise ExtractionError(f"no function named '{function_name}'")
    chosen = versions[-1]
    if _is_empty(chosen):
        raise ExtractionError("empty policy body")
    module = ast.Module(body=_needed(chosen, statements), type_ignores=[])
    rename(module, {chosen.name: function_name})
    _strip_annotations(module)
    _add_missing_imports(module)
    return ast.unparse(module)


def first_syntax_error(source: str) -> tuple[int, str] | None:
    """The line and message of the first syntax error in `source`, if it has one (None too for
    what the parser refuses for other reasons: null bytes, absurd nesting)."""
    try:
        astutil.parse(source)
    except SyntaxError as error:
        return error.lineno or 1, error.msg
    except (ValueError, RecursionError, MemoryError):
        pass
    return None


def _syntax_error_from(text: str, first: int) -> str:
    """`: syntax error at line N: message` for the first syntax error in the lines of `text` from
    line `first` (0-based: the policy's `def`) to the end of its fenced block; N counts lines of
    `text`. Empty if those lines parse (a method of a class, say)."""
    lines = text.splitlines()[first:]
    end = next((i for i, line in enumerate(lines) if i and line.lstrip().startswith("```")), len(lines))
    indent = len(lines[0]) - len(lines[0].lstrip())
    error = first_syntax_error("\n".join(line[indent:] if line[:indent].isspace() else line for line in lines[:end]))
    if error is None:
        return ""
    message = re.sub(r"detected at line (\d+)", lambda found: f"detected at line {first + int(found[1])}", error[1])
    return f": syntax error at line {first + error[0]}: {message}"


def _strip_annotations(module: ast.Module) -> None:
    """Drop type annotations, in place: common in model answers (`obs: np.ndarray`), they never
    change what the policy computes, and they would meet the static check (`.ndarray`)."""
    for node in ast.walk(module):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            node.returns = None
        elif isinstance(node, ast.arg):
            node.annotation = None
        for field in ("body", "orelse", "finalbody"):
            statements = getattr(node, field, None)
            if isinstance(statements, list) and any(isinstance(s, ast.AnnAssign) for s in statements):
                kept = [_unannotated(s) if isinstance(s, ast.AnnAssign) else s for s in statements]
                kept = [s for s in kept if s is not None]
                setattr(node, field, kept or ([] if field == "orelse" else [ast.Pass()]))


def _unannotated(statement: ast.AnnAssign) -> ast.stmt | None:
    """`x: T = v` as `x = v`; a bare declaration `x: T` binds nothing and goes."""
    if statement.value is None:
        return None
    return ast.copy_location(ast.Assign(targets=[statement.target], value=statement.value), statement)


def _fenced_blocks(text: str) -> list[str]:
    blocks, current = [], None
    for line in text.splitlines():
        if _FENCE.match(line):
            if current is None:
                current = []
            else:
                blocks.append("\n".join(current))
                current = None
        elif current is not None:
            current.append(line)
    if current is not None:  # the answer stopped inside a fence
        blocks.append("\n".join(current))
    return blocks


def _code_regions(chunk: str, budget: _ParseBudget) -> list[ast.Module]:
    """Every parseable stretch of code in `chunk`, skipping the prose between them; line
    numbers are the chunk's."""
    lines = chunk.splitlines()
    modules, start = [], 0
    while start < len(lines):
        found = _parse_prefix(lines, start, budget) if _CODE_START.match(lines[start]) else None
        if found is not None:
            module, end = found
            modules.append(ast.increment_lineno(module, start))
            start = end
        elif lines[start].lstrip().startswith("@"):
            # A start further down the same run of decorators meets the same statement after it,
            # so it fails the same way: skip the run (a model repeating `@x` costs one try).
            indent = lines[start][: len(lines[start]) - len(lines[start].lstrip())]
            start += 1
            while start < len(lines) and lines[start].startswith(indent + "@"):
                start += 1
        else:
            start += 1
    return modules


class _ParseBudget:
    """Characters `ast.parse` may still read for one answer. A parse costs time in proportion to
    its text, failing ones too, so a bound on the total keeps any answer linear in its length."""

    def __init__(self, text: str):
        self.left = _PARSE_BUDGET_FACTOR * len(text) + _PARSE_BUDGET_BASE

    def parse(self, lines: list[str]) -> ast.Module:
        source = "\n".join(lines)
        self.left -= len(source) + 1
        if self.left < 0:
            raise ExtractionError("the answer is too irregular to read (parse budget spent)")
        return astutil.parse(source)


def _statement_starts(lines: list[str], begin: int, indent: str) -> Iterator[int]:
    """The lines after `begin` that likely start a statement at `indent`, then the end of the run
    at that indentation; read lazily, so a run that fails early costs only its first lines.
    A start is a line at `indent`, not a clause of the statement before (`else:`) and not after a
    decorator or a backslash. It is a guess (a bracket or string can hold such a line):
    `_parse_prefix` joins pieces that fail alone."""
    previous = lines[begin][len(indent) :].rstrip()
    i = begin + 1
    while i < len(lines):
        if lines[i].strip():
            if not lines[i].startswith(indent):
                break
            line = lines[i][len(indent) :]
            if line[0] not in " \t#" and not _CLAUSE.match(line) and not previous.startswith("@") and not previous.endswith("\\"):
                yield i
            previous = line.rstrip()
        i += 1
    yield i


def _parse_prefix(lines: list[str], start: int, budget: _ParseBudget) -> tuple[ast.Module, int] | None:
    """The longest parseable run of lines from `start` at its indentation, and where it ends.

    Read statement by statement, so each line is parsed about once: a piece that fails alone
    because it opens a string or bracket is joined with the following ones (doubling), else the
    run ends there, cut before the line that failed (the broken tail of a truncated answer;
    at most `_MAX_CUTS` cuts)."""
    indent = lines[start][: len(lines[start]) - len(lines[start].lstrip())]
    pending = _statement_starts(lines, start, indent)
    starts: list[int] = []  # read so far; once `pending` is spent, the last is the end of the run
    spent = False

    def start_after(done: int, n: int) -> tuple[int, bool]:
        """The n-th start after line `done` (0: the next), or the end; and whether it is the end."""
        nonlocal spent
        index = bisect.bisect_right(starts, done) + n
        while len(starts) <= index and not spent:
            extra = next(pending, None)
            if extra is None:
                spent = True
            else:
                starts.append(extra)
        return starts[min(index, len(starts) - 1)], spent and index >= len(starts) - 1

    def parse(begin: int, stop: int) -> ast.Module:
        return ast.increment_lineno(budget.parse([line[len(indent) :] for line in lines[begin:stop]]), begin - start)

    body: list[ast.stmt] = []
    done = start  # lines[start:done] are parsed
    while True:
        stop, last = start_after(done, 0)
        if stop <= done:
            break
        step, first_stop, piece = 1, stop, None
        while True:
            try:
                piece = parse(done, stop)
                break
            except SyntaxError as error:
                if step == 1:
                    first_error = error
                if last or not _OPEN.search(error.msg or ""):
                    break
                step *= 2
                stop, last = start_after(done, step - 1)
        if piece is None:
            # No longer prefix holds the offending line: keep what parses before it.
            size = min((first_error.lineno or 1) - 1, first_stop - done - 1)
            for _ in range(_MAX_CUTS):
                if size <= 0:
                    break
                try:
                    piece = parse(done, done + size)
                    break
                except SyntaxError as error:
                    size = min(size - 1, (error.lineno or size) - 1)
            if piece is not None and piece.body and isinstance(piece.body[-1], ast.FunctionDef) and _is_empty(piece.body[-1]):
                piece.body.pop()  # truncated right after its signature or docstring
            if piece is not None:
                body += piece.body
                done += size
            break
        body += piece.body
        done = stop
    if done == start:
        return None
    return ast.Module(body=body, type_ignores=[]), done


def _versions(statements: list[ast.stmt], version: re.Pattern) -> list[ast.FunctionDef]:
    return [s for s in statements if isinstance(s, ast.FunctionDef) and version.fullmatch(s.name)]


def _is_empty(function: ast.FunctionDef) -> bool:
    return all(isinstance(s, ast.Pass) or (isinstance(s, ast.Expr) and isinstance(s.value, ast.Constant)) for s in function.body)


def _free_names(statement: ast.stmt) -> set[str]:
    names = [n for n in ast.walk(statement) if isinstance(n, ast.Name)]
    loaded = {n.id for n in names if isinstance(n.ctx, ast.Load)}
    if not isinstance(statement, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
        return loaded
    local = {n.id for n in names if not isinstance(n.ctx, ast.Load)} | {a.arg for a in ast.walk(statement) if isinstance(a, ast.arg)}
    declared_global = {name for n in ast.walk(statement) if isinstance(n, ast.Global) for name in n.names}
    return loaded - (local - declared_global)


def _supplied(shown: str, answer: list[ast.stmt]) -> list[ast.stmt]:
    """What the code a chat answer's prompt showed may add to the answer: its function
    definitions, and nothing else (`_needed` then keeps those the answer calls, and the ones they
    call). One program must not change another, and a shown program is another program: so no
    module-level statement of any other kind (a shown `np = math` or `import math as np` would
    rebind the answer's `np`; the imports a shown function needs are the answer's own, or those
    added for names like `np`), no function under a name the answer binds itself (its own
    definition, import or assignment wins), and none under a builtin's or another predefined
    name (a shown `def float(x)` would clip every `float(...)` of the answer)."""
    taken = {name for statement in answer for name in bound_names(statement)} | _RESERVED_NAMES
    return [s for s in astutil.parse(shown).body if isinstance(s, ast.FunctionDef) and s.name not in taken]


def _needed(chosen: ast.FunctionDef, statements: list[ast.stmt]) -> list[ast.stmt]:
    """`chosen` and the module-level statements it depends on: imports first, then answer order."""
    definitions: dict[str, list[ast.stmt]] = {}
    for statement in statements:
        for name in bound_names(statement):
            if isinstance(statement, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                definitions[name] = [statement]  # a redefinition replaces the earlier one
            else:
                definitions.setdefault(name, []).append(statement)
    kept, pending, visited = {id(chosen)}, list(_free_names(chosen)), set()
    while pending:
        name = pending.pop()
        if name in visited:
            continue
        visited.add(name)
        for statement in definitions.get(name, []):
            if statement is not chosen and id(statement) not in kept:
                kept.add(id(statement))
                pending.extend(_free_names(statement))
    ordered = [s for s in statements if id(s) in kept]
    imports = {ast.dump(s): s for s in ordered if isinstance(s, (ast.Import, ast.ImportFrom))}
    return list(imports.values()) + [s for s in ordered if not isinstance(s, (ast.Import, ast.ImportFrom))]


def _add_missing_imports(module: ast.Module) -> None:
    bound = {name for statement in module.body for name in bound_names(statement)}
    bound |= {name for n in ast.walk(module) if isinstance(n, (ast.Import, ast.ImportFrom)) for name in bound_names(n)}
    used = {n.id for n in ast.walk(module) if isinstance(n, ast.Name)}
    missing = [astutil.parse(line).body[0] for name, line in _MISSING_IMPORTS.items() if name in used - bound]
    # Names bound anywhere (a local `pi = 3.14`, an argument) are not the math module's.
    from_math = sorted(set(unbound_names(module, ())) & _MATH_NAMES)
    if from_math:
        missing.append(ast.ImportFrom(module="math", names=[ast.alias(name) for name in from_math], level=0))
    module.body[:0] = missing
