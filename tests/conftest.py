"""Shared test set-up: the offline Menagerie tree, and helpers to run colmo's command lines."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
EXAMPLES = REPO / "examples"
_MENAGERIE = REPO.parent / "shared" / "menagerie"
if "MENAGERIE_ROOT" not in os.environ and _MENAGERIE.is_dir():
    os.environ["MENAGERIE_ROOT"] = str(_MENAGERIE)


def run_colmo(module: str, *overrides: str, cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess:
    """Run `python -m <module> <overrides>` as a user would, in `cwd`."""
    return subprocess.run(
        [sys.executable, "-m", module, *overrides], cwd=cwd, capture_output=True, text=True, timeout=timeout
    )


def last_json_line(stdout: str) -> dict:
    return json.loads(stdout.strip().splitlines()[-1])


@pytest.fixture
def examples() -> Path:
    return EXAMPLES


def compose(config_name: str, *overrides: str):
    """A config composed from colmo's bundled configs, as validated dataclasses."""
    from hydra import compose as hydra_compose
    from hydra import initialize_config_module

    from colmo.config import CONFIG_MODULE, register_schemas, to_objects

    register_schemas()
    with initialize_config_module(config_module=CONFIG_MODULE, version_base="1.3"):
        return to_objects(hydra_compose(config_name=config_name, overrides=list(overrides)))
