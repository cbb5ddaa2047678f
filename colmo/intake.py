"""Intake: from a generator's raw output to a checked parametric program, or why there is none.

The output is untrusted text, read in the coordinator, so it is bounded before anything parses
it: at most `MAX_ANSWER_CHARS` characters and `MAX_NESTING` levels of brackets (a linear scan),
so a hostile answer costs milliseconds, not minutes and gigabytes. Then the policy is extracted
(`colmo.extract`), parametrized (`colmo.program`), bounded to `MAX_PROGRAM_NODES` AST nodes,
statically checked (`colmo.sandbox.check`), and refused if it reads a name that nothing defines.

`read_program` raises `Unusable` when no program can be read (the sample is `unusable`) and
`ForbiddenProgram` when the program is refused (the sample `failed`), and nothing else for any
text: a character that is not text (U+FFFD, which a generator's lone surrogate or a file's
undecodable byte became) is `Unusable` too, before anything parses it.
"""

from __future__ import annotations

import ast
import re
import textwrap
from pathlib import Path
from typing import Optional, Sequence

from colmo.astutil import node_count, parse, unbound_names
from colmo.errors import ConfigError
from colmo.extract import ExtractionError, extract_policy, first_syntax_error
from colmo.program import ParametricProgram, ProgramError, instantiate, measure, parametrize
from colmo.sandbox.check import ForbiddenProgram, check_tree, parse_program
from colmo.sandbox.namespace import PREDEFINED_NAMES

_NOT_TEXT = re.compile("[\ufffd\ud800-\udfff]")  # U+FFFD: what a generator's lone surrogate became
MAX_ANSWER_CHARS = 100_000  # a 1024-token answer is about 4,000 characters
MAX_NESTING = 100  # brackets; Python's own parser stops at 200
MAX_PROGRAM_NODES = 20_000  # the paper's policies have a few hundred
# What a raw completion body in a policy file continues: the signature every spec's policy has.
COMPLETION_SIGNATURE = "def policy(obs):\n"


class Unusable(ValueError):
    """No usable program in the output; the message is the reason."""


def nesting(text: str) -> int:
    """The deepest bracket nesting in `text`, strings included (a bound, not a parse)."""
    depth = deepest = 0
    for char in text:
        if char in "([{":
            depth += 1
            deepest = max(deepest, depth)
        elif char in ")]}":
            depth = max(depth - 1, 0)
    return deepest


def read_program(
    text: str, allowed_imports: Sequence[str], prefix: str = "", max_nodes: Optional[int] = None, shown: str = "",
    max_constants: Optional[int] = None,
) -> ParametricProgram:
    """The checked parametric program in a generator's output (module docstring); for a
    completion, `prefix` is the prompt text it continues, for a chat answer `shown` the code
    its prompt showed (both colmo's own, so not bounded). A program bigger than `max_nodes`
    AST nodes (`database.max_nodes`), or with more than `max_constants` tunable constants
    (`database.max_constants`), is refused: readability."""
    if len(text) > MAX_ANSWER_CHARS:
        raise Unusable(f"the output has {len(text)} characters, more than the {MAX_ANSWER_CHARS} allowed")
    not_text = _NOT_TEXT.search(text)
    if not_text:
        line = text.count("\n", 0, not_text.start()) + 1
        raise Unusable(f"the output holds a character that is not text at line {line} (an undecodable byte or a lone surrogate)")
    if nesting(text) > MAX_NESTING:
        raise Unusable(f"the output nests brackets more than {MAX_NESTING} deep")
    try:
        program = parametrize(extract_policy(text, prefix=prefix, shown=shown))
    except (ExtractionError, ProgramError) as error:
        raise Unusable(str(error)) from None
    tree = parse_program(program.skeleton)
    if node_count(tree) > MAX_PROGRAM_NODES:
        raise Unusable(f"the program has more than {MAX_PROGRAM_NODES} AST nodes")
    check_tree(tree, allowed_imports)
    # A name nothing defines fails the first step it is reached on (small models use the
    # variables of a shown version they did not copy): said here, where a chat model can be told.
    undefined = unbound_names(tree, PREDEFINED_NAMES)
    if undefined:
        raise Unusable(f"{_named(undefined)} used but never defined")
    if max_nodes is not None:
        nodes = measure(instantiate(program.skeleton, program.values)).nodes
        if nodes > max_nodes:
            raise ForbiddenProgram(f"too large: {nodes} AST nodes (database.max_nodes={max_nodes})")
    if max_constants is not None and program.n_params > max_constants:
        raise ForbiddenProgram(f"too many constants: {program.n_params} tunable constants (database.max_constants={max_constants})")
    return program


def _named(names: Sequence[str]) -> str:
    """`theta` is, `theta` and `omega` are."""
    quoted = [f"`{name}`" for name in names]
    return f"{quoted[0]} is" if len(quoted) == 1 else f"{', '.join(quoted[:-1])} and {quoted[-1]} are"


def read_policy_file(path: str, allowed_imports: Sequence[str]) -> ParametricProgram:
    """The checked program in a policy file given on a command line (a `.py` file or a raw
    language-model answer); `ConfigError` naming the file if there is none."""
    file = Path(path).expanduser()
    if file.is_dir():
        raise ConfigError(f"policy_file is a directory, not a file: {path}")
    if not file.is_file():
        raise ConfigError(f"policy_file not found: {path}")
    try:
        text = file.read_text(errors="replace")
    except OSError as error:
        raise ConfigError(f"cannot read policy_file {path}: {error.strerror}") from None
    if text.lstrip("\n")[:1].isspace():
        # A raw completion body, indented from its first line: what a completion model wrote after
        # the prompt's `def policy(obs):` line, read exactly as the search reads it (a trailing,
        # unfinished next version included).
        return _read(path, text, allowed_imports, prefix=COMPLETION_SIGNATURE, reading=" (read as a raw completion body)")
    syntax = _syntax_error(text)
    lines = text.splitlines()
    typo = ConfigError(f"no usable policy in {path}: syntax error at line {syntax[0]}: {syntax[1]}") if syntax else None
    # A typo inside a block of a `.py` file is the user's to fix: extraction would cut the
    # definition before it (the rule for a truncated answer) and run a broken policy. Prose,
    # the other thing that fails to parse in a saved answer, is not indented.
    if syntax and lines[syntax[0] - 1 : syntax[0]] and lines[syntax[0] - 1][:1].isspace():
        raise typo
    try:
        return _read(path, text, allowed_imports)
    except ConfigError as error:
        if typo and "no complete top-level definition" in str(error):  # a typo in the signature
            raise typo from None
        if "no function named" not in str(error):
            raise
        functions = _top_level_functions(text)
        if functions:
            raise ConfigError(f"{error} (it defines {', '.join(functions)}; a policy file's function is `def policy(obs)`)") from None
    # Statements without a `def` line: a completion body saved without its indentation.
    return _read(path, textwrap.indent(text, "    "), allowed_imports, prefix=COMPLETION_SIGNATURE, reading=" (read as a raw completion body)")


def _read(path: str, text: str, allowed_imports: Sequence[str], prefix: str = "", reading: str = "") -> ParametricProgram:
    """`read_program`, its refusal one `ConfigError` naming the file."""
    try:
        return read_program(text, allowed_imports, prefix=prefix)
    except (Unusable, ForbiddenProgram) as error:
        raise ConfigError(f"no usable policy in {path}{reading}: {error}") from None


def _top_level_functions(text: str) -> list[str]:
    """The functions the top level of `text` defines, if it is Python."""
    try:
        return [statement.name for statement in parse(text).body if isinstance(statement, ast.FunctionDef)]
    except SyntaxError:
        return []


def _syntax_error(text: str) -> tuple[int, str] | None:
    """The line and message of the first syntax error in `text`, if it has one (not looked for
    in a text `read_program` refuses unparsed: its reason stands)."""
    if len(text) > MAX_ANSWER_CHARS or nesting(text) > MAX_NESTING:
        return None
    return first_syntax_error(text)
