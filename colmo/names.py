"""Names that do not lie: a policy's variables checked against what the task says its observation holds.

A reader believes a program's names. When a model calls `obs[0]` "theta" where the task's
observation is `[cos θ, sin θ, ω]`, the program reads as if it tested an angle, and it does not.
A spec may name each entry of its observation (`OBSERVATION_NAMES`, e.g. `("cos_theta",
"sin_theta", "angular_velocity")`); the prompt then shows the observation as code
(`observation_in_code`), and `misnamed` lists each variable bound straight to an observation
entry (`x = obs[i]`, or unpacked: `a, b, c = obs`) whose name contradicts the spec's name for it:
  * it names a quantity the entry's name does not (`sin_theta = obs[0]`, `velocity = obs[0]`), or
  * it leaves out what tells the entry from the others (`theta = obs[0]`: every pendulum entry
    is about θ; only "cos" says which one).
Words are compared after a few synonyms are folded (`angle` and `theta`, `vel`, `omega`,
`dot` and `velocity`, `pos` and `position`); a name made of words no spec name uses (`x`, `u`,
`error`) says nothing and is never flagged. It reads code only; nothing runs. `renamed` gives
such variables the spec's names where that cannot change what the program does (the
simplifier's last step).
"""

from __future__ import annotations

import ast
import builtins
import keyword
import re
from collections import Counter
from typing import Sequence

from colmo import astutil

# Words a name may use for the same quantity, folded to one (`omega` is an angular velocity).
_SYNONYMS: dict[str, tuple[str, ...]] = {
    "angle": ("theta",), "ang": ("angular",), "th": ("theta",), "pos": ("position",), "vel": ("velocity",),
    "speed": ("velocity",), "dot": ("velocity",), "omega": ("angular", "velocity"), "cosine": ("cos",), "sine": ("sin",),
}


def _words(name: str) -> set[str]:
    """The words of an identifier (`cosTheta`, `cos_theta` and `cos_theta2` give cos, theta), synonyms folded."""
    pieces = re.findall(r"[A-Z]?[a-z]+|[A-Z]+(?![a-z])", name)
    folded: set[str] = set()
    for piece in (p.lower() for p in pieces):
        folded.update(_SYNONYMS.get(piece, (piece,)))
    if {"theta", "velocity"} <= folded:  # `theta_dot`, `angle_vel`: the rate of an angle
        folded = (folded - {"theta"}) | {"angular"}
    return folded


def observation_in_code(names: Sequence[str], argument: str = "obs") -> str:
    """The spec's observation names as the line of code that would unpack them."""
    return f"{', '.join(names)} = {argument}"


def bound_entries(code: str, argument: str = "obs", function_name: str = "policy") -> list[tuple[str, int]]:
    """Each (variable, index) that the policy binds straight to an entry of its observation."""
    function = astutil.function(astutil.parse(code), function_name)
    if function is None or not function.args.args or function.args.args[0].arg != argument:
        return []
    bound = []
    for node in ast.walk(function):
        if not isinstance(node, ast.Assign) or len(node.targets) != 1:
            continue
        target, value = node.targets[0], node.value
        if isinstance(target, ast.Name) and (index := _is_entry(value, argument)) is not None:
            bound.append((target.id, index))
        elif isinstance(target, ast.Tuple) and isinstance(value, ast.Name) and value.id == argument:
            bound += [(element.id, index) for index, element in enumerate(target.elts) if isinstance(element, ast.Name)]
    return bound


def _is_entry(node: ast.AST, argument: str) -> int | None:
    """`i` if `node` is `obs[i]` with a literal non-negative `i`."""
    if isinstance(node, ast.Subscript) and isinstance(node.value, ast.Name) and node.value.id == argument:
        index = node.slice
        if isinstance(index, ast.Constant) and type(index.value) is int and index.value >= 0:
            return index.value
    return None


def _contradicting(code: str, names: Sequence[str], argument: str) -> list[tuple[str, int]]:
    """Each (variable, index) of `code` whose name contradicts the spec's `names` for the entry it holds."""
    if not names:
        return []
    vocabulary = [_words(name) for name in names]
    known = set().union(*vocabulary)
    found = []
    for variable, index in bound_entries(code, argument):
        if index >= len(names):
            continue
        words = _words(variable) & known
        own = vocabulary[index]
        telling = own - set().union(*(v for i, v in enumerate(vocabulary) if i != index and v != own))
        if words and (words - own or (telling and not words & telling)):
            found.append((variable, index))
    return found


def misnamed(code: str, names: Sequence[str], argument: str = "obs") -> list[str]:
    """One line per variable of `code` whose name contradicts the spec's `names` for the
    observation entry it holds (module docstring); [] where the spec names nothing."""
    return [f"`{variable}` holds {argument}[{index}], which the task calls {names[index]}" for variable, index in _contradicting(code, names, argument)]


def renamed(code: str, names: Sequence[str], argument: str = "obs", function_name: str = "policy") -> tuple[str, list[str]]:
    """`code` with each misnamed variable (`misnamed`) given the spec's name for the entry it
    holds, and a line per renaming; only where that cannot change what the program does: the
    variable is bound once, in the policy function, and used nowhere else (no argument, helper or
    comprehension of that name), and the spec's name appears nowhere in the program."""
    tree = astutil.parse(code)
    function = astutil.function(tree, function_name)
    if function is None:
        return code, []
    everywhere = _identifiers(tree)
    done: list[str] = []
    for variable, index in _contradicting(code, names, argument):
        new = names[index]
        stores = [n for n in ast.walk(function) if isinstance(n, ast.Name) and n.id == variable and not isinstance(n.ctx, ast.Load)]
        if new in everywhere or keyword.iskeyword(new) or hasattr(builtins, new) or len(stores) != 1:
            continue
        inside = sum(1 for n in ast.walk(function) if isinstance(n, ast.Name) and n.id == variable)
        if everywhere[variable] != inside:  # an argument, a helper's, a global's: not only this variable
            continue
        for node in ast.walk(function):
            if isinstance(node, ast.Name) and node.id == variable:
                node.id = new
        everywhere[new] = everywhere.pop(variable)
        done.append(f"renamed `{variable}` to `{new}`: it holds {argument}[{index}], which the task calls {new}")
    return (ast.unparse(tree), done) if done else (code, [])


def _identifiers(tree: ast.AST) -> Counter[str]:
    """How often each identifier occurs in `tree`: names, arguments, definitions, imports, globals."""
    counts: Counter[str] = Counter()
    for node in ast.walk(tree):
        if isinstance(node, ast.Name):
            counts[node.id] += 1
        elif isinstance(node, ast.arg):
            counts[node.arg] += 1
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            counts[node.name] += 1
        elif isinstance(node, ast.alias):
            counts[(node.asname or node.name).split(".")[0]] += 1
        elif isinstance(node, (ast.Global, ast.Nonlocal)):
            counts.update(node.names)
    return counts
