"""Deprecated: `colmo.task` held the environment interface and the rollout until they were
split (into `colmo.environments.base` and `colmo.rollout`). Spec files that import from it keep
working, with a `DeprecationWarning` naming the public import (`from colmo import ...`)."""

from __future__ import annotations

import importlib
import warnings
from typing import Any

_MOVED = {
    "Environment": "colmo.environments.base",
    "MujocoEnvironment": "colmo.environments.base",
    "PolicyFailure": "colmo.environments.base",
    "episode_seeds": "colmo.rollout",
    "heldout_seeds": "colmo.rollout",
    "as_action": "colmo.rollout",
    "act": "colmo.rollout",
    "rollout": "colmo.rollout",
    "evaluate_policy": "colmo.rollout",
    "evaluate_program": "colmo.rollout",
}


def __getattr__(name: str) -> Any:
    module = _MOVED.get(name)
    if module is None:
        raise AttributeError(f"module 'colmo.task' has no attribute {name!r}")
    public = f"from colmo import {name}" if name in importlib.import_module("colmo").__all__ else f"from {module} import {name}"
    warnings.warn(f"colmo.task is deprecated: use `{public}`", DeprecationWarning, stacklevel=2)
    return getattr(importlib.import_module(module), name)
