"""The public API (docs/api.md): every name it documents imports from `colmo`, nothing else is
exported, the old `colmo.task` path keeps working with a deprecation warning, and a spec file
written against the public names runs a search."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

import colmo

ROOT = Path(__file__).resolve().parent.parent
DOCUMENTED = re.findall(r"^### `colmo\.(\w+)`$", (ROOT / "docs" / "api.md").read_text(), re.MULTILINE)

SPEC = '''"""Pendulum swing-up, written against colmo's public API.

A pole hangs from a hinge. Observation (size 3): [cos(theta), sin(theta), angular velocity].
Action: one torque in [-1, 1]. Reward 1 for every step the pole is within 0.5 rad of upright.
"""

import numpy as np

from colmo import MujocoEnvironment, dm_control_model


class Swingup(MujocoEnvironment):
    observation_size = 3

    def __init__(self):
        super().__init__(dm_control_model("pendulum"), n_sub_steps=1)

    def initialize_episode(self, random):
        self.data.qpos[0] = random.uniform(-np.pi, np.pi)

    def observation(self):
        pole = self.data.xmat[self.model.body("pole").id]
        return np.array((pole[8], pole[2], self.data.qvel[0]))

    def reward(self):
        return float(self.data.xmat[self.model.body("pole").id][8] >= np.cos(0.5))


def make_environment(**options):
    return Swingup(**options)


def policy(obs):
    """obs size is 3. return shape is ()."""
    return 0.0
'''


def test_the_documented_names_are_the_exports():
    assert len(DOCUMENTED) >= 15
    assert sorted(DOCUMENTED) == colmo.__all__


@pytest.mark.parametrize("name", DOCUMENTED)
def test_every_documented_name_imports_from_colmo(name):
    namespace: dict = {}
    exec(f"from colmo import {name}", namespace)
    assert namespace[name] is getattr(colmo, name)


def test_an_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'Nothing'"):
        colmo.Nothing  # noqa: B018


def test_the_old_colmo_task_path_works_and_warns():
    with pytest.warns(DeprecationWarning, match="use `from colmo import MujocoEnvironment`"):
        from colmo.task import MujocoEnvironment
    assert MujocoEnvironment is colmo.MujocoEnvironment


def test_a_spec_file_on_the_public_api_runs_a_search(tmp_path):
    (tmp_path / "swingup.py").write_text(SPEC)
    run = subprocess.run(
        [sys.executable, "-m", "colmo", f"task.spec={tmp_path / 'swingup.py'}", "search.max_samples=3", "gfo.budget=3", "task.episodes=2",
         "heldout.episodes=2", "finish.render=false", "finish.simplify=false", "executor.workers=1", "search.progress=false",
         "tracker=none", "hydra.run.dir=run"],
        cwd=tmp_path, capture_output=True, text=True, timeout=600,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["programs_evaluated"] >= 1 and summary["best_score"] is not None
