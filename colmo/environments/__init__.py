"""The simulated systems colmo ships, one module each, all on `colmo.environments.base.MujocoEnvironment`."""

from __future__ import annotations

import importlib.resources

import mujoco


def dm_control_model(name: str) -> mujoco.MjModel:
    """Compile dm_control suite's `<name>.xml` with the suite's shared assets.

    The files are read from the installed dm_control package instead of through
    `dm_control.suite`, whose import loads every suite domain and probes for a renderer.
    """
    suite = importlib.resources.files("dm_control") / "suite"
    assets = {
        entry.name: entry.read_bytes()
        for entry in (suite / "common").iterdir()
        if entry.name.endswith((".xml", ".png"))
    }
    return mujoco.MjModel.from_xml_string((suite / f"{name}.xml").read_text(), assets)
