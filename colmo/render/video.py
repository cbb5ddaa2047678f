"""Videos of an episode: its recorded physics states replayed through `mujoco.Renderer`.

Only numbers are replayed (`colmo.trace.EpisodeTrace.states`), never policy code. The camera
keeps the whole system in view (`default_camera`), frames are taken so that the video plays in
real time (`video_frame_steps`), and the result is an MP4 (H.264, through `imageio-ffmpeg`,
which bundles an ffmpeg binary) or, without that package, an animated GIF (Pillow).
"""

from __future__ import annotations

import copy
import itertools
import math
import time
from pathlib import Path
from typing import Iterator, Optional, Union

import mujoco
import numpy as np

from colmo.environments.base import MujocoEnvironment
from colmo.render.gl import NoGLError, gl_unavailable_reason, select_gl_backend
from colmo.trace import STATE_SPEC, EpisodeTrace

DEFAULT_FPS = 30.0
MIN_FPS = 15.0  # frames a second of simulated time below which a video is a slide show: cut it short instead
Camera = Union[int, str, mujoco.MjvCamera]


def default_camera(model: mujoco.MjModel) -> Camera:
    """A camera that keeps the whole system in view.

    The model's own cameras first: one that follows a moving body (TRACK or TRACKCOM mode),
    preferring the view most nearly sideways, since colmo's runners run along x (the cheetah's
    `side`, the quadruped's `y`); else the first camera that is not riding on a body (the
    pendulum's `fixed`). A model without either (Menagerie's A1) gets a free camera tracking
    its root body from the side and a little above, at a distance set by the model's size.
    """
    tracking_modes = (int(mujoco.mjtCamLight.mjCAMLIGHT_TRACK), int(mujoco.mjtCamLight.mjCAMLIGHT_TRACKCOM))
    trackers = [i for i in range(model.ncam) if model.cam_mode[i] in tracking_modes and model.cam_bodyid[i] != 0]
    if trackers:
        # The optical axis is the camera frame's -z; cam_mat0 is its orientation in the body frame.
        return min(trackers, key=lambda i: abs(model.cam_mat0[i].reshape(3, 3)[0, 2]))
    fixed_in_world = [i for i in range(model.ncam) if model.cam_bodyid[i] == 0]
    if fixed_in_world:
        return fixed_in_world[0]
    camera = mujoco.MjvCamera()
    mujoco.mjv_defaultFreeCamera(model, camera)
    camera.type = mujoco.mjtCamera.mjCAMERA_TRACKING
    camera.trackbodyid = int(model.body_rootid[1]) if model.nbody > 1 else 0
    camera.distance = 1.75 * model.stat.extent
    camera.azimuth = 90.0  # looking along +y: x runs across the image
    camera.elevation = -15.0
    return camera


def default_scene_option(model: mujoco.MjModel) -> mujoco.MjvOption:
    """MuJoCo's default visibility, plus the hidden geom groups when it would show no body at all.

    Models draw visual geoms in groups 0-2 and keep collision geoms in group 3, hidden. A model
    with only collision geoms (colmo's A1 from a Menagerie copy stripped of its visual meshes)
    would render as an empty floor, so then the groups its bodies' geoms are in are shown.
    """
    option = mujoco.MjvOption()
    body_groups = {int(group) for group, body in zip(model.geom_group, model.geom_bodyid) if body != 0}
    if body_groups and not any(option.geomgroup[group] for group in body_groups if group < len(option.geomgroup)):
        for group in body_groups:
            if group < len(option.geomgroup):
                option.geomgroup[group] = 1
    return option


def video_frame_steps(steps: int, control_timestep: float, fps: Optional[float] = None) -> tuple[range, float]:
    """The steps to draw (every k-th state, 0 to `steps`) and the frame rate that plays them in
    real time; `k` is the whole number of control periods closest to one frame at `fps` (30 by default)."""
    stride = max(1, round(1.0 / (control_timestep * (fps or DEFAULT_FPS))))
    return range(0, steps + 1, stride), 1.0 / (control_timestep * stride)


def render_video(
    env: MujocoEnvironment,
    trace: EpisodeTrace,
    path: Path,
    *,
    width: int = 640,
    height: int = 480,
    fps: Optional[float] = None,
    camera: Optional[Camera] = None,
    max_seconds: Optional[float] = None,
) -> Path:
    """Replay `trace`'s states in `env.model` and write them as a real-time video; return its path.

    An MP4 needs `imageio-ffmpeg`; without it, or when `path` ends in `.gif`, an animated GIF
    is written at `path` with its suffix changed to `.gif`. `fps` is the target frame rate
    (`video_frame_steps`). `camera` is a model camera (id or name) or an `MjvCamera`; by default
    `default_camera(env.model)`. With `max_seconds`, the first frame is timed and the frames
    drawn made fewer so that they take about that long: first every k-th one (still in real
    time) down to `MIN_FPS`, then only the first seconds of the episode; the video also ends
    early if drawing takes longer than the first frame said. Raises `NoGLError` if no OpenGL backend works, `ValueError`
    for a trace that does not fit the model.
    """
    if trace.states is None:
        raise ValueError("the trace has no MuJoCo states (not recorded from a MujocoEnvironment)")
    model = env.model
    state_size = mujoco.mj_stateSize(model, STATE_SPEC)
    if trace.states.shape[1] != state_size:
        raise ValueError(f"the trace's states have {trace.states.shape[1]} numbers, this model's {state_size}")
    if width < 2 or height < 2 or width % 2 or height % 2:
        raise ValueError(f"video size {width}x{height}: width and height must be even (H.264 needs it)")
    if trace.control_timestep is None:
        raise ValueError("the trace has no control timestep, so no time base for a video")
    if select_gl_backend() is None:
        raise NoGLError(gl_unavailable_reason())
    if width > model.vis.global_.offwidth or height > model.vis.global_.offheight:
        # A copy with a larger offscreen buffer: the environment's model stays as it is.
        model = copy.copy(model)
        model.vis.global_.offwidth = max(width, model.vis.global_.offwidth)
        model.vis.global_.offheight = max(height, model.vis.global_.offheight)
    frame_steps, frame_rate = video_frame_steps(trace.steps, trace.control_timestep, fps)
    view = default_camera(model) if camera is None else camera
    data = mujoco.MjData(model)  # not env.data: rendering leaves the environment's state alone
    scene_option = default_scene_option(model)

    def frame(renderer: mujoco.Renderer, step: int) -> np.ndarray:
        mujoco.mj_setState(model, data, trace.states[step], STATE_SPEC)
        mujoco.mj_forward(model, data)
        renderer.update_scene(data, camera=view, scene_option=scene_option)
        return renderer.render()

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with mujoco.Renderer(model, height, width) as renderer:
        started = time.monotonic()
        first = frame(renderer, frame_steps[0])
        rest: Iterator[int] = iter(frame_steps[1:])
        if max_seconds is not None and len(frame_steps) > 1:
            # Twice the first frame's time per frame: encoding it costs about as much again.
            allowed = max(2, int(max_seconds / (2 * max(time.monotonic() - started, 1e-3))))
            thin = max(1, min(math.ceil(len(frame_steps) / allowed), math.floor(frame_rate / MIN_FPS)))
            frame_steps, frame_rate = frame_steps[::thin][:allowed], frame_rate / thin
            # Should the machine slow down, the video ends early rather than the run late.
            late = itertools.takewhile(lambda _: time.monotonic() < started + max_seconds, frame_steps[2:])
            rest = itertools.chain(frame_steps[1:2], late)  # two frames at least: a video, not a still
        frames = itertools.chain([first], (frame(renderer, step) for step in rest))
        return _write(frames, path, width, height, frame_rate)


def _write(frames: Iterator[np.ndarray], path: Path, width: int, height: int, frame_rate: float) -> Path:
    """An MP4 through imageio-ffmpeg, else (or for a `.gif` path) an animated GIF."""
    try:
        import imageio_ffmpeg
    except ImportError:
        imageio_ffmpeg = None
    if imageio_ffmpeg is None or path.suffix.lower() == ".gif":
        return _write_gif(frames, path.with_suffix(".gif"), frame_rate)
    writer = imageio_ffmpeg.write_frames(
        str(path), (width, height), fps=frame_rate, quality=7, macro_block_size=2, ffmpeg_log_level="error"
    )
    writer.send(None)  # starts ffmpeg
    try:
        for image in frames:
            writer.send(np.ascontiguousarray(image))
    finally:
        writer.close()
    return path


def _write_gif(frames: Iterator[np.ndarray], path: Path, frame_rate: float) -> Path:
    from PIL import Image

    images = [Image.fromarray(frame).convert("P", palette=Image.Palette.ADAPTIVE) for frame in frames]
    images[0].save(path, save_all=True, append_images=images[1:], duration=round(1000.0 / frame_rate), loop=0)
    return path
