"""Specification files: one Python file per task that says what to solve and how it is scored.

A spec file (see `colmo/specs/pendulum.py`) holds
- its module docstring: the task description that heads every prompt;
- `make_environment(**options) -> colmo.environments.base.Environment`: the simulator, with the task YAML's
  `env:` mapping as keyword arguments;
- `policy(obs)`: the starter program the search evolves;
- optionally `ALLOWED_IMPORTS`: modules a policy may import besides numpy and math;
- optionally `OBSERVATION_NAMES`: a name per observation entry, which the prompt shows as the
  line of code that unpacks `obs` and against which a policy's variable names are checked
  (`colmo.names`).
"""

from __future__ import annotations

import ast
import hashlib
import importlib.resources
import importlib.util
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Mapping, Optional

from colmo import astutil
from colmo.names import observation_in_code

if TYPE_CHECKING:  # the simulator (MuJoCo) is imported when a spec is loaded, not with the prompt's imports
    from colmo.environments.base import Environment

DEFAULT_IMPORTS = ("numpy", "math")


class SpecError(ValueError):
    """A spec file that cannot be used; the message is one line naming the problem."""


@dataclass(frozen=True)
class Spec:
    name: str
    path: Path
    description: str
    starter_code: str
    make_environment: Callable[..., Environment]
    allowed_imports: tuple[str, ...]
    observation_names: tuple[str, ...] = ()  # `OBSERVATION_NAMES`: a name per observation entry, if the spec gives them
    # `OBSERVATION_BOUNDS`: per entry, (low, high) that it never leaves, or None (`colmo.bounds`)
    observation_bounds: tuple[Optional[tuple[float, float]], ...] = ()

    @property
    def prompt_text(self) -> str:
        """The task as a prompt states it: the description, and the observation's names as code."""
        if not self.observation_names:
            return self.description
        return f"{self.description}\n\nThe observation, in code: `{observation_in_code(self.observation_names)}`."

    def prompt_text_for(self, env_options: Mapping[str, Any]) -> str:
        """`prompt_text` for the task as configured: where `env_options` (the task's `env:`) set
        the episodes' length (`horizon`) to another than the default, the length a description
        states, a line says this search's, so that a model is not told the wrong one."""
        if "horizon" not in env_options:
            return self.prompt_text
        configured = self.make_environment(**env_options)
        others = {name: value for name, value in env_options.items() if name != "horizon"}
        try:
            default = self.make_environment(**others).horizon
        except TypeError:  # an environment that takes no default length
            default = None
        if configured.horizon == default:
            return self.prompt_text
        period = getattr(configured, "control_timestep", None)
        seconds = f" ({configured.horizon * period:g} s)" if period else ""
        told = "" if default is None else f"; the task's default is {default}"
        return f"{self.prompt_text}\n\nEpisodes in this search last {configured.horizon} control steps{seconds}{told}."


def resolve_spec_path(name_or_path: str) -> Path:
    """A spec given as a path (absolute or relative to the working directory) or as a file
    name in colmo's bundled `specs/`."""
    candidate = Path(name_or_path).expanduser()
    if candidate.is_file():
        return candidate.resolve()
    bundled = Path(str(importlib.resources.files("colmo.specs"))) / name_or_path
    if bundled.is_file():
        return bundled
    raise SpecError(f"spec file not found: {name_or_path!r} (not a file, nor one of colmo's bundled specs)")


def _starter_code(source: str, tree: ast.Module, path: Path) -> str:
    policy = next((n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name == "policy"), None)
    if policy is None:
        raise SpecError(f"{path}: no starter `def policy(obs)` in the spec file")
    imports = [ast.get_source_segment(source, n) for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom))]
    kept = [line for line in imports if line and "colmo" not in line]
    return "\n".join(kept) + "\n\n\n" + ast.get_source_segment(source, policy, padded=True) + "\n"


def load_spec(name_or_path: str) -> Spec:
    """Load and check a spec file; raises `SpecError` with a one-line reason."""
    from colmo.environments.perturb import perturbable

    path = resolve_spec_path(name_or_path)
    source = path.read_text()
    try:
        tree = astutil.parse(source, filename=str(path))
    except SyntaxError as error:
        raise SpecError(f"{path}:{error.lineno}: syntax error in spec file: {error.msg}") from None
    description = ast.get_docstring(tree)
    if not description:
        raise SpecError(f"{path}: the spec file needs a module docstring describing the task")
    starter = _starter_code(source, tree, path)

    module_name = f"colmo_spec_{path.stem}_{hashlib.sha1(str(path).encode()).hexdigest()[:8]}"
    module_spec = importlib.util.spec_from_file_location(module_name, path)
    module = importlib.util.module_from_spec(module_spec)
    try:
        module_spec.loader.exec_module(module)
    except Exception as error:
        raise SpecError(f"{path}: importing the spec file failed: {type(error).__name__}: {error}") from None
    sys.modules[module_name] = module
    make_environment = getattr(module, "make_environment", None)
    if not callable(make_environment):
        raise SpecError(f"{path}: the spec file needs a `make_environment(**options)` function")
    allowed = tuple(dict.fromkeys(DEFAULT_IMPORTS + tuple(getattr(module, "ALLOWED_IMPORTS", ()))))
    names = getattr(module, "OBSERVATION_NAMES", ())
    if not isinstance(names, (tuple, list)) or not all(isinstance(n, str) and n.isidentifier() for n in names):
        raise SpecError(f"{path}: OBSERVATION_NAMES must be a tuple of Python identifiers, one per observation entry")
    bounds = _observation_bounds(getattr(module, "OBSERVATION_BOUNDS", ()), path)
    # Any MuJoCo spec takes `task.perturb` through the reserved option, unknown to its make_environment.
    return Spec(path.stem, path, description, starter, perturbable(make_environment), allowed, tuple(names), bounds)


def _observation_bounds(bounds: object, path: Path) -> tuple[Optional[tuple[float, float]], ...]:
    """A spec's `OBSERVATION_BOUNDS`, checked: per entry, None or a pair of numbers low <= high."""
    def pair(bound: object) -> Optional[tuple[float, float]]:
        if bound is None:
            return None
        if isinstance(bound, (tuple, list)) and len(bound) == 2 and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in bound):
            if bound[0] <= bound[1]:
                return (float(bound[0]), float(bound[1]))
        raise SpecError(f"{path}: OBSERVATION_BOUNDS must hold, per observation entry, None or (low, high) with low <= high; got {bound!r}")

    if not isinstance(bounds, (tuple, list)):
        raise SpecError(f"{path}: OBSERVATION_BOUNDS must be a tuple with one entry per observation entry")
    return tuple(pair(bound) for bound in bounds)


def load_task_spec(name_or_path: str) -> Spec:
    """`load_spec` for a configured task: a bad spec is the user's configuration error."""
    from colmo.errors import ConfigError

    try:
        return load_spec(name_or_path)
    except SpecError as error:
        raise ConfigError(str(error)) from None
