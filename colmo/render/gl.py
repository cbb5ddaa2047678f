"""OpenGL for rendering without a display: which backend `mujoco.Renderer` uses here.

`select_gl_backend` finds one (EGL, else OSMesa; only the user's if MUJOCO_GL is set), each
tried in a short-lived subprocess, since a failed GL initialisation can break the process that
tried, and points this process's `mujoco.Renderer` at it. With none it returns None and
`gl_unavailable_reason` says why in one line, naming the package to install.
"""

from __future__ import annotations

import functools
import importlib
import logging
import os
import subprocess
import sys
from typing import Optional

import mujoco

from colmo.errors import failure_reason

_CANDIDATES = ("egl", "osmesa")
_DISABLED = ("disable", "disabled", "off", "false", "0")
_PROBE_TIMEOUT_S = 120.0  # generous: the probe imports mujoco on a possibly loaded machine
OSMESA_HINT = "install OSMesa for software rendering: apt-get install libosmesa6"

_PROBE = """
import mujoco
model = mujoco.MjModel.from_xml_string("<mujoco><worldbody><geom size='.1'/></worldbody></mujoco>")
data = mujoco.MjData(model)
mujoco.mj_forward(model, data)
with mujoco.Renderer(model, 8, 8) as renderer:
    renderer.update_scene(data)
    assert renderer.render().shape == (8, 8, 3)
"""


class NoGLError(RuntimeError):
    """No OpenGL backend works in this process, so no video can be rendered."""


def probe(backend: str) -> Optional[str]:
    """None if a fresh interpreter renders with `MUJOCO_GL=backend`, else why not (one line)."""
    environment = dict(os.environ, MUJOCO_GL=backend)
    try:
        result = subprocess.run(
            [sys.executable, "-c", _PROBE], env=environment, capture_output=True, text=True, timeout=_PROBE_TIMEOUT_S
        )
    except subprocess.TimeoutExpired:
        return f"timed out after {_PROBE_TIMEOUT_S:.0f} s"
    if result.returncode == 0:
        return None
    lines = [line.strip() for line in result.stderr.splitlines() if line.strip()]
    return (lines[-1] if lines else f"exit status {result.returncode}")[:120]


def _selection() -> tuple[Optional[str], str]:
    backend, reason = _selection_for(os.environ.get("MUJOCO_GL", "").strip().lower())
    if backend:
        # The backend stays this process's though something unset MUJOCO_GL since it was chosen:
        # say so again, for the subprocesses started from here.
        os.environ["MUJOCO_GL"] = backend
    return backend, reason


@functools.cache
def _selection_for(requested: str) -> tuple[Optional[str], str]:
    """The working backend for a MUJOCO_GL value, made this process's; else None and the
    one-line reason. Cached per value: a backend is probed once per process."""
    if requested in _DISABLED:
        return None, f"rendering is disabled (MUJOCO_GL={requested})"
    failures = []
    for backend in (requested,) if requested else _CANDIDATES:
        reason = probe(backend)
        if reason is None:
            try:
                _use(backend)
            except Exception as error:  # e.g. PyOpenGL already loaded here for another platform
                reason = failure_reason(f"{type(error).__name__}: {error}")
            else:
                return backend, ""
        failures.append(f"MUJOCO_GL={backend}: {reason}")
    return None, f"no OpenGL for rendering videos ({'; '.join(failures)}); {OSMESA_HINT}"


def _use(backend: str) -> None:
    """Make `mujoco.Renderer` use `backend` in this process, though mujoco was imported before.

    `import mujoco` imports `mujoco.rendering.classic.gl_context`, which reads MUJOCO_GL once and
    binds its `GLContext` (GLFW when unset); `Renderer` looks up `gl_context.GLContext` each time
    it is created. Reloading that module with MUJOCO_GL set rebinds it. The EGL and OSMesa
    modules set PYOPENGL_PLATFORM themselves, which PyOpenGL reads on its first import, here.
    """
    os.environ["MUJOCO_GL"] = backend
    # PyOpenGL says at INFO level, on its first import, that its optional accelerator is missing.
    logging.getLogger("OpenGL.acceleratesupport").setLevel(logging.WARNING)
    from mujoco.rendering.classic import gl_context

    importlib.reload(gl_context)
    mujoco.GLContext = gl_context.GLContext  # the public alias `import mujoco` bound to the old one


def select_gl_backend() -> Optional[str]:
    """The MUJOCO_GL value rendering uses in this process, or None if no backend works.

    A MUJOCO_GL the user set is the only one tried; otherwise EGL, then OSMesa. The first that
    renders in a subprocess is made this process's. The answer is cached for the process (per
    MUJOCO_GL value).
    """
    return _selection()[0]


def gl_unavailable_reason() -> str:
    """Why `select_gl_backend` found none (one line); empty if it found one."""
    return _selection()[1]
