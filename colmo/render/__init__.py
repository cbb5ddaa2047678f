"""Episode media: a video and a plot of one episode of a policy, for a person to watch.

The policy is untrusted, so it never runs here: `render_policy` asks the referee for the
episode (one `EvalRequest` with `trace=True` through an executor; the sandbox worker steps the
simulator, records the episode and sends it back as a `colmo.trace.EpisodeTrace`, validated on
arrival), then draws from those numbers alone: `plot.plot_episode` writes a PNG of the
observations, actions and cumulative reward, `video.render_video` replays the physics states
through `mujoco.Renderer` into an MP4 (or a GIF), with OpenGL found by `gl.select_gl_backend`.
A missing OpenGL, or a policy that fails in the episode, is not an error here: what could be
written is, and `EpisodeMedia.note` says in one line what could not and why, so a search logs
it and goes on. `python -m colmo.render` (`__main__`) does this for a policy file.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Sequence

from colmo.environments.base import Environment, MujocoEnvironment
from colmo.evaluation import REFEREE, Evaluator, Executor
from colmo.render.gl import NoGLError, select_gl_backend
from colmo.render.plot import plot_episode
from colmo.render.video import render_video
from colmo.specs import load_spec
from colmo.trace import EpisodeTrace, TraceError

PLOT_FILE, VIDEO_FILE = "episode.png", "episode.mp4"


def warm_up() -> None:
    """Import what drawing needs (matplotlib, imageio-ffmpeg) and find the OpenGL backend (a
    probe in a fresh interpreter), so that a render that follows starts at once: a search runs
    this in a thread while its last programs are scored (on a loaded machine they are most of a
    render's time). Never raises; a missing piece is found again, and said, by the render."""
    try:
        import matplotlib.backends.backend_agg  # noqa: F401
        import matplotlib.figure  # noqa: F401
    except ImportError:
        pass
    try:
        import imageio_ffmpeg  # noqa: F401
    except ImportError:
        pass
    select_gl_backend()


@dataclass(frozen=True)
class EpisodeMedia:
    """What was written for one episode: the plot and the video where they could be (else
    `note` says why not), the episode's return and seed, and the seconds it all took."""

    plot: Optional[Path]
    video: Optional[Path]
    note: Optional[str]
    episode_return: Optional[float] = None
    episode_seed: Optional[int] = None
    seconds: float = 0.0

    def as_dict(self) -> dict:
        """JSON-compatible: paths as strings, absent ones as null."""
        return {
            "video": None if self.video is None else str(self.video),
            "plot": None if self.plot is None else str(self.plot),
            "episode_return": self.episode_return,
            "episode_seed": self.episode_seed,
            "seconds": round(self.seconds, 3),
            "note": self.note,
        }


def render_episode(
    env: Environment, trace: EpisodeTrace, directory: Path, title: str, *, width: int = 640, height: int = 480,
    video_seconds: Optional[float] = None,
) -> EpisodeMedia:
    """Write `episode.png` and, for a MuJoCo environment with OpenGL, `episode.mp4` (or `.gif`
    without imageio-ffmpeg) in `directory`, from a trace of an episode of `env`; the video's
    frames take about `video_seconds` if given (fewer frames a second down to 15, then the first seconds only: `render_video`)."""
    start = time.monotonic()
    directory = Path(directory)
    applied = env.applied_actions(trace.actions) if isinstance(env, MujocoEnvironment) else None
    plot = plot_episode(trace, directory / PLOT_FILE, title, applied)
    video, note = None, None
    if not isinstance(env, MujocoEnvironment) or trace.states is None:
        note = f"no video: {type(env).__name__} is not a MuJoCo environment"
    else:
        try:
            video = render_video(env, trace, directory / VIDEO_FILE, width=width, height=height, max_seconds=video_seconds)
        except NoGLError as error:
            note = f"no video: {error}"
    return EpisodeMedia(plot, video, note, trace.episode_return, seconds=time.monotonic() - start)


def render_policy(
    executor: Executor,
    evaluator: Evaluator,
    skeleton: str,
    params: Sequence[float],
    directory: Path,
    title: str,
    *,
    episode: int = 0,
    steps: Optional[int] = None,
    width: int = 640,
    height: int = 480,
    video_seconds: Optional[float] = None,
) -> EpisodeMedia:
    """The plot and video (`render_episode`) of episode `evaluator.seeds[episode]` of a program,
    recorded by the referee (pass a held-out evaluator: `colmo.heldout.heldout_evaluator`),
    cut to `steps` control steps if given, its video's frames drawn in about `video_seconds`
    if given (`render_video`). Never raises for a missing OpenGL, a policy that
    fails in the episode or an invalid trace: then `note` says why, and `plot` is None where
    there is no trace to draw."""
    start = time.monotonic()
    seed = evaluator.seeds[episode]
    request = evaluator.request(skeleton, params, seeds=(seed,), mode=REFEREE, trace=True, steps=steps)
    evaluation = executor.evaluate([request])[0]
    where = f"episode {episode} (seed {seed})"
    trace, reason = None, None
    if evaluation.failure:
        reason = f"the policy failed in {where}: {evaluation.failure}"
    else:
        try:
            trace = EpisodeTrace.from_dict(evaluation.trace)  # from a sandbox process: checked like any reply
        except TraceError as error:
            reason = str(error)
    if trace is None:
        return EpisodeMedia(None, None, f"no plot or video: {reason}", episode_seed=seed, seconds=time.monotonic() - start)
    env = load_spec(evaluator.spec).make_environment(**dict(evaluator.env))
    media = render_episode(env, trace, directory, f"{title}\n{where}, {trace.steps} steps", width=width, height=height, video_seconds=video_seconds)
    return dataclasses.replace(media, episode_seed=seed, seconds=time.monotonic() - start)
