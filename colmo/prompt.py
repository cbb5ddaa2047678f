"""Prompts: turning a selection of programs into the text a generator sees (paper Fig. 3).

The selected programs appear as `policy_v0`, `policy_v1`, ... in ascending score, each with
its tuned constants inlined, and the prompt ends with the header of the next version for the
model to complete. Scores are not shown, as in the paper and FunSearch: the order alone says
which program is better.

What the prompt says about constants is true of the run (`constants_tuned`): with GFO, both
forms say that the numeric constants are tuned automatically, so the structure is what to
change; without GFO (`gfo=none`, the programs run as written) nothing of the kind is said.
Both forms ask for a version that differs from every one shown: small models otherwise
copy the last version (most answers of a 1.5B model were copies, docs/llm-duplicates.md).
An answer that brings no new program is followed up in the chat form (`Prompt.followed_up`:
the model's answer and what was wrong with it, `colmo.answers`, in the words of
`copied_feedback` and `unusable_feedback`): every sentence the model is sent is in this module.
Each program is shown cleaned for reading (`readable`).

Helpers the programs define (module-level functions, classes, constants) are shown once,
above the versions. A helper that differs from one already shown under the same name, or
that uses such a helper, gets a version suffix (`wrap_v1`) so that every version still calls
its own helpers; so does a helper named like a version (`policy_v0` kept by a program that
calls it), which the version of that name would otherwise replace. Code is re-rendered with
`ast.unparse`, which drops comments.
"""

from __future__ import annotations

import ast
import copy
import dataclasses
import functools
import math
import re
from collections import deque
from dataclasses import dataclass
from typing import Optional, Sequence

from colmo import astutil
from colmo.astutil import bound_names, identifiers, is_docstring, rename
from colmo.coverage import Counts, prune
from colmo.database import Selection
from colmo.specs import DEFAULT_IMPORTS

NUMPY_IMPORT = "import numpy as np"
# Where a completion of the prompt text ends: the next top-level statement after the function.
# Four at most: OpenAI's completions endpoint takes no more.
COMPLETION_STOP = ("\ndef ", "\nclass ", "\nif __name__", "\n```")


@dataclass(frozen=True)
class Prompt:
    text: str  # completion form: ends with the header of the version to write
    messages: list[dict[str, str]]  # chat form: a system and a user message
    programs: list[str]  # the shown programs' code as stored, ascending score
    # The code shown (imports, helpers, versions policy_v0..) as rendered: what a chat answer may
    # call without copying it (`colmo.extract`); a completion continues `text`, which holds it.
    shown_code: str
    island: int
    parent_keys: list[str]
    # Which regeneration of a duplicate answer this prompt asks for (0: a first answer); language
    # models sample it hotter (`LanguageModelConfig.temperature_for`).
    retry: int = 0

    def followed_up(self, answer: str, feedback: str, retry: int) -> "Prompt":
        """This prompt's chat continued: its system and user messages, the model's `answer` to
        them and `feedback`, what was wrong with it; the same selection (programs, island,
        parents). Only the last answer is kept: a longer conversation would only be slower."""
        messages = [*self.messages[:2], {"role": "assistant", "content": answer}, {"role": "user", "content": feedback}]
        return dataclasses.replace(self, messages=messages, retry=retry)


def copied_feedback(version: Optional[int], constants_tuned: bool) -> str:
    """What a chat model is told of an answer whose program is known: the shown `policy_v<version>`
    it copied, or (None) a program evaluated before; with GFO, that its numbers are tuned anyway."""
    copied = f"`policy_v{version}`" if version is not None else "a program evaluated before"
    if constants_tuned:
        return (
            f"Your `policy` is {copied} with other numbers. The numbers are tuned automatically, so it would score the same. "
            "Write a `policy` with another structure: other terms, conditions or functions of the observation."
        )
    return f"Your `policy` is {copied} again. Write a different `policy`."


def unusable_feedback(reason: str) -> str:
    """What a chat model is told of an answer no program could be read from, and why."""
    return f"Your answer cannot be used: {reason}. Write `policy` again, corrected, in one ```python block."


def _system_message(function_name: str, args: str, constants_tuned: bool, allowed_imports: Sequence[str]) -> str:
    tuning = (
        " Its numeric constants are tuned automatically by an optimizer afterwards, so change the "
        "structure (which terms, conditions and functions of the observation it uses), not the values."
        if constants_tuned else ""
    )
    return (
        "You are an expert control engineer who writes control policies as short Python functions. "
        f"Answer with one Python function `{function_name}({args})` in a ```python code block. "
        f"numpy is available as np; use only {_listed(allowed_imports)}. Write a new policy, not a copy of one shown.{tuning}"
    )


def _listed(names: Sequence[str]) -> str:
    """`numpy`, `numpy and math`, `numpy, math and scipy`."""
    names = list(dict.fromkeys(names))
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} and {names[-1]}"


def _instructions(new: str, previous: str, function_name: str, constants_tuned: bool, blind: str) -> str:
    """What the completion form's docstring asks, after the task's description (`blind`: what
    `_blind_versions` says, or nothing)."""
    lines = [
        f"On every iteration, improve {previous} over the {function_name}_vX methods from previous iterations.",
        f"{new} must differ from every version above.",
    ]
    if constants_tuned:
        lines.append(f"The numeric constants of {new} are tuned automatically afterwards: change its structure, not its numbers.")
    if blind:
        lines.append(blind)
    return "\n".join(lines)


def _blind_versions(codes: Sequence[str], function_name: str, new: str) -> str:
    """A sentence naming the shown versions that never read their arguments (every task's starter
    returns a constant action), or "": a small model shown only such a version answers with
    another constant far more often than not (docs/llm-duplicates.md)."""
    blind = []
    for version, code in enumerate(codes):
        policy = astutil.function(astutil.parse(code), function_name)
        arguments = {a.arg for a in policy.args.posonlyargs + policy.args.args + policy.args.kwonlyargs}
        if not any(isinstance(n, ast.Name) and n.id in arguments for n in ast.walk(policy) if not isinstance(n, ast.arg)):
            blind.append(f"{function_name}_v{version}")
    if not blind:
        return ""
    verb = "ignores its observation" if len(blind) == 1 else "ignore their observation"
    return f"{_listed(blind)} {verb}: {new} should compute its action from the observation."


def build_prompt(
    description: str, selection: Selection, function_name: str = "policy", constants_tuned: bool = False,
    allowed_imports: Sequence[str] = DEFAULT_IMPORTS,
) -> Prompt:
    """The prompt showing `selection.programs` (ascending score) as `{function_name}_v0..`;
    `constants_tuned`: whether the run tunes the constants of what the model writes (GFO);
    `allowed_imports`: the modules the task's static check lets a policy import (`Spec.allowed_imports`)."""
    programs = selection.programs
    assert programs, "a prompt shows at least one program"
    assert all(math.isfinite(program.score) for program in programs), "failed programs are never shown"
    assert all(a.score <= b.score for a, b in zip(programs, programs[1:])), "programs must be in ascending score"

    codes = [readable(program.code, function_name, program.coverage) for program in programs]
    imports, definitions, versions, args = _render(codes, function_name)
    new, previous = f"{function_name}_v{len(programs)}", f"{function_name}_v{len(programs) - 1}"
    blind = _blind_versions(codes, function_name, new)
    docstring = f'"""{description.strip()}\n\n{_instructions(new, previous, function_name, constants_tuned, blind)}\n"""'
    shown_code = "\n\n\n".join(["\n".join(imports), *definitions, *versions])
    context = docstring + "\n\n" + shown_code
    header = f'def {new}({args}):\n    """Improved version of {previous}."""\n'
    # The chat form leaves out the header: the instruction asks for the function instead.
    request = (
        f"Write {new}, a new version that should score higher than {previous} and differs from every version above. "
        + (f"{blind} " if blind else "") + f"Name it `{function_name}` in your answer."
    )
    messages = [
        {"role": "system", "content": _system_message(function_name, args, constants_tuned, allowed_imports)},
        {"role": "user", "content": f"```python\n{context}\n```\n\n{request}"},
    ]
    return Prompt(
        text=context + "\n\n\n" + header,
        messages=messages,
        programs=[program.code for program in programs],
        shown_code=shown_code,
        island=selection.island,
        parent_keys=[program.key for program in programs],
    )


@functools.lru_cache(maxsize=64)  # the programs prompts show again and again: cleaned once
def readable(code: str, function_name: str = "policy", coverage: Optional[tuple[Counts, ...]] = None) -> str:
    """`code` as a prompt shows it: with `coverage` (what each branch did when it was scored),
    without the branches it never took (`colmo.coverage.prune`), so the model improves on what
    the program does; then without its dead code, literal arithmetic folded
    (`colmo.simplify.deadcode`, for reading: static, the same actions, the policy's docstring
    and named constants kept), so that what mutation left in a program (unused assignments,
    branches on constant conditions) does not stand between the model and its structure; `code`
    itself where the clean-up cannot read it."""
    # Imported here: the simplify package's own imports (its sandboxed stages) lead back to this module.
    from colmo.simplify.deadcode import remove_dead_code

    try:
        pruned = prune(code, coverage) if coverage else None
        return remove_dead_code(pruned.code if pruned else code, function_name, for_reading=True)
    except (SyntaxError, RecursionError, ValueError):
        return code


def _render(codes: list[str], function_name: str) -> tuple[list[str], list[str], list[str], str]:
    """Imports, shared definitions and versioned functions of `codes`, and the arguments of the
    last version (the next version keeps its signature)."""
    imports = {NUMPY_IMPORT: None}  # ordered sets
    definitions: dict[str, None] = {}
    shown: dict[str, str] = {}  # name bound by a shown definition -> that definition's text
    versions = []
    for version, code in enumerate(codes):
        statements = astutil.parse(code).body
        policies = [s for s in statements if isinstance(s, ast.FunctionDef) and s.name == function_name]
        if not policies:
            raise ValueError(f"program {version} of the prompt defines no {function_name}()")
        for statement in statements:
            if isinstance(statement, (ast.Import, ast.ImportFrom)):
                imports[ast.unparse(statement)] = None
        helpers = [s for s in statements if s not in policies and not is_docstring(s) and not isinstance(s, (ast.Import, ast.ImportFrom))]

        renames = {function_name: f"{function_name}_v{version}"}
        # A helper named like a version (a program that kept the versions it was shown and
        # calls them) would be replaced by that version: it is shown under a name of its own.
        for helper in helpers:
            renames.update({name: f"{name}_v{version}" for name in bound_names(helper) if re.fullmatch(rf"{function_name}_v\d+", name)})
        # A helper whose text differs from the shown one of its name is renamed; renaming it
        # changes the text of the helpers that name it, which are then looked at again (and only
        # they: looking at every helper until nothing changed was quadratic in a chain of helpers).
        naming: dict[str, list[int]] = {}
        for index, helper in enumerate(helpers):
            for name in identifiers(helper):
                naming.setdefault(name, []).append(index)
        pending = deque(range(len(helpers)))
        while pending:
            helper = helpers[pending.popleft()]
            text = ast.unparse(_renamed(helper, renames))
            for name in bound_names(helper):
                if name not in renames and shown.get(name, text) != text:
                    renames[name] = f"{name}_v{version}"
                    pending.extend(naming.get(name, ()))
        for helper in helpers:
            text = ast.unparse(_renamed(helper, renames))
            definitions[text] = None
            for name in bound_names(helper):
                shown.setdefault(renames.get(name, name), text)

        policy = _renamed(policies[-1], renames)  # the last definition is the one Python keeps
        if version > 0:
            if ast.get_docstring(policy, clean=False) is not None:
                policy.body.pop(0)
            policy.body.insert(0, ast.Expr(ast.Constant(f"Improved version of {function_name}_v{version - 1}.")))
        versions.append(ast.unparse(policy))
    return list(imports), list(definitions), versions, ast.unparse(policies[-1].args)


def _renamed(node: ast.AST, names: dict[str, str]) -> ast.AST:
    """A renamed copy of `node` (the selection's programs stay as stored)."""
    copied = copy.deepcopy(node)
    rename(copied, names)
    return copied
