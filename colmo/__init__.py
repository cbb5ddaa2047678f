"""colmo: interpretable control policies from program search with in-the-loop gradient-free optimization.

Data flows one way: generator (`generate`) → intake (`intake`, `extract`) → parametrize
(`program`) → sandboxed evaluate + optimize (`sandbox`, `executor`, `optimize`, `rollout`) →
store and database (`store`, `database`) → prompt (`prompt`) → generator. `search` runs the
loop; `python -m colmo` is the search app.

The public API is what this package exports (`colmo.__all__`, documented in docs/api.md): what a
spec file builds a task from, the evaluation entry points, and the registries a new generator,
GFO method, executor or tracker is added to. Those names stay put across releases; the modules
behind them may move. They are imported when first used, so `import colmo` stays cheap.
"""

from __future__ import annotations

import importlib
from importlib.metadata import PackageNotFoundError, version
from typing import Any

try:
    __version__ = version("colmo")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0"

_EXPORTS = {
    # what a spec file builds a task from
    "Environment": "colmo.environments.base",
    "MujocoEnvironment": "colmo.environments.base",
    "PolicyFailure": "colmo.environments.base",
    "dm_control_model": "colmo.environments",
    # specs, programs and their evaluation
    "Spec": "colmo.specs",
    "load_spec": "colmo.specs",
    "ParametricProgram": "colmo.program",
    "parametrize": "colmo.program",
    "instantiate": "colmo.program",
    "Evaluation": "colmo.evaluation",
    "evaluate_policy": "colmo.rollout",
    "episode_seeds": "colmo.rollout",
    "heldout_seeds": "colmo.rollout",
    # the registries a component is added to
    "Registry": "colmo.registry",
    "GENERATORS": "colmo.generate",
    "Generator": "colmo.generate",
    "METHODS": "colmo.optimize.methods",
    "Method": "colmo.optimize.methods",
    "GFOConfig": "colmo.config",
    "option": "colmo.config.fields",
    "EXECUTORS": "colmo.executor",
    "TRACKERS": "colmo.trackers",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'colmo' has no attribute {name!r}")
    return getattr(importlib.import_module(module), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
