"""The simulated systems colmo ships, one module each, all on `colmo.environments.base.MujocoEnvironment`."""

from __future__ import annotations

import copy
import functools
import importlib.resources

import mujoco


def dm_control_model(name: str) -> mujoco.MjModel:
    """dm_control suite's `<name>.xml` compiled with the suite's shared assets, a model of its
    own (an environment may change its model: `colmo.environments.perturb`).

    The files are read from the installed dm_control package instead of through
    `dm_control.suite`, whose import loads every suite domain and probes for a renderer. Each
    name is compiled once per process and copied (`mj_copyModel`, the same model): a sandbox
    worker builds one environment per episode of a lockstep batch, and compiling costs many
    times what copying does.
    """
    return copy.copy(_compiled(name))


@functools.cache
def _compiled(name: str) -> mujoco.MjModel:
    suite = importlib.resources.files("dm_control") / "suite"
    assets = {
        entry.name: entry.read_bytes()
        for entry in (suite / "common").iterdir()
        if entry.name.endswith((".xml", ".png"))
    }
    return mujoco.MjModel.from_xml_string((suite / f"{name}.xml").read_text(), assets)
