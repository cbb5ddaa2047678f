"""Episode traces and media (colmo.trace, colmo.render): recording by the referee, plots, videos,
GL selection, and `python -m colmo.render`.

Traces of policies come from the real sandbox: the policies are program text, run in a
confined child by a `LocalExecutor` while the worker records the episode (referee mode,
`trace=True`). Tests of plots, videos and the trace format build traces in-process from
numbers only (a `TraceRecorder` fed by the test, or arrays): no policy code runs here. Videos
are small (160x120) and about 3 s long to keep the tests fast on software OpenGL. Without
OpenGL the video tests skip, except in CI (`CI=true`), where they must run (with OSMesa).
"""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import mujoco
import numpy as np
import pytest
from conftest import last_json_line, refused, unavailable
from PIL import Image

from colmo import trace as trace_module
from colmo.environments.base import Environment
from colmo.environments.cheetah import Cheetah
from colmo.environments.pendulum import PendulumSwingup
from colmo.evaluation import FAST, REFEREE, Evaluator
from colmo.executor import LocalExecutor
from colmo.program import parametrize
from colmo.render import PLOT_FILE, EpisodeMedia, gl, render_episode, render_policy
from colmo.render.__main__ import main as colmo_render
from colmo.render.gl import NoGLError
from colmo.render.plot import episode_figure, plot_episode
from colmo.render.video import MIN_FPS, default_camera, render_video, video_frame_steps
from colmo.specs import load_spec
from colmo.trace import STATE_SPEC, EpisodeTrace, TraceError, TraceRecorder

REPO = Path(__file__).resolve().parent.parent
PENDULUM_STEPS = 160  # 3.2 s at 20 ms
CHEETAH_STEPS = 320  # 3.2 s at 10 ms
SIZE = {"width": 160, "height": 120}
MEMORY_MB = 2048
USER_MUJOCO_GL = os.environ.get("MUJOCO_GL")  # before any selection sets it

SWING_UP = """import numpy as np

def policy(obs):
    cos_angle, sin_angle, velocity = obs
    if cos_angle > 0.9:
        return -(3.0 * sin_angle + 0.5 * velocity)
    return 1.0 if velocity >= 0 else -1.0
"""
# A gait whose phase follows the torso's pitch and pitch rate.
GALLOP = """import math
import numpy as np

def policy(obs):
    phase = 4.0 * obs[1] + 0.5 * obs[8]
    return np.sin(phase + np.array([0.0, 1.0, 2.0, math.pi, math.pi + 1.0, math.pi + 2.0]))
"""
WRONG_ACTION_SIZE = """def policy(obs):
    return [obs[0], 2.0]
"""
TASKS = {"pendulum": ("pendulum.py", SWING_UP, 7, PENDULUM_STEPS), "cheetah": ("cheetah.py", GALLOP, 3, CHEETAH_STEPS)}


@pytest.fixture(scope="module")
def executor():
    with LocalExecutor(1, MEMORY_MB) as executor:
        yield executor


def evaluator(spec: str, seeds: tuple[int, ...]) -> Evaluator:
    return Evaluator.for_task(load_spec(spec), {}, seeds, MEMORY_MB, timeout_s=120)


def request(spec: str, code: str, seeds: tuple[int, ...], **fields):
    program = parametrize(code)
    return evaluator(spec, seeds).request(program.skeleton, program.values, **fields)


@pytest.fixture(scope="module")
def refereed(executor) -> dict:
    """Per task: the traced referee evaluation, the same one untraced, and the fast path's."""
    outcomes = {}
    for name, (spec, code, seed, steps) in TASKS.items():
        outcomes[name] = executor.evaluate([
            request(spec, code, (seed,), mode=REFEREE, trace=True, steps=steps),
            request(spec, code, (seed,), mode=REFEREE, steps=steps),
            request(spec, code, (seed,), mode=FAST, steps=steps),
        ])
    return outcomes


@pytest.fixture(scope="module")
def pendulum() -> PendulumSwingup:
    return PendulumSwingup()


@pytest.fixture(scope="module")
def cheetah() -> Cheetah:
    return Cheetah()


@pytest.fixture(scope="module")
def pendulum_trace(refereed) -> EpisodeTrace:
    return EpisodeTrace.from_dict(refereed["pendulum"][0].trace)


@pytest.fixture(scope="module")
def cheetah_trace(refereed) -> EpisodeTrace:
    return EpisodeTrace.from_dict(refereed["cheetah"][0].trace)


def constant_trace(env: Environment, seed: int, steps: int, action: float = 1.0) -> EpisodeTrace:
    """A trace recorded in-process with a constant action: numbers only, no policy code."""
    recorder = TraceRecorder(env)
    recorder.start(env.reset(seed))
    for _ in range(steps):
        command = np.full(env.action_size, action)
        reward, obs = env.step(command)
        recorder.step(command, reward, obs)
    return recorder.finish()


@pytest.fixture(scope="module", autouse=True)
def restore_gl_environment():
    """Selecting a backend sets MUJOCO_GL (and PyOpenGL's PYOPENGL_PLATFORM) for this process;
    unset them afterwards so the subprocesses of later test modules start as they would have."""
    saved = {name: os.environ.get(name) for name in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    yield
    for name, value in saved.items():
        if value is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = value


def no_gl(reason: str) -> None:
    unavailable(reason, "the video tests must run; apt-get install libosmesa6")


@pytest.fixture(scope="module")
def gl_backend() -> str:
    backend = gl.select_gl_backend()
    if backend is None:
        no_gl(f"no OpenGL backend here: {gl.gl_unavailable_reason()}")
    return backend


def mp4_frames_and_seconds(path: Path) -> tuple[int, float]:
    import imageio_ffmpeg

    return imageio_ffmpeg.count_frames_and_secs(str(path))


# --- recording by the referee ------------------------------------------------------------------


@pytest.mark.parametrize("name", ["pendulum", "cheetah"])
def test_the_referee_records_the_episode_it_scores(name, refereed, request):
    env = request.getfixturevalue(name)
    traced, untraced, fast = refereed[name]
    _, _, seed, steps = TASKS[name]
    assert traced.failure is None and untraced.trace is None and fast.trace is None
    trace = EpisodeTrace.from_dict(traced.trace)
    assert trace.steps == steps == traced.steps
    assert trace.observations.shape == (steps + 1, env.observation_size)
    assert trace.actions.shape == (steps, env.action_size)
    assert trace.states.shape == (steps + 1, mujoco.mj_stateSize(env.model, STATE_SPEC))
    assert trace.control_timestep == env.control_timestep
    # Recording changes nothing: the same return traced, untraced and on the fast path.
    assert traced.returns == untraced.returns == fast.returns == (pytest.approx(trace.episode_return, abs=1e-9),)
    # The recorded actions, replayed here, reproduce the recorded rewards and observations,
    # and each recorded state reproduces its observation.
    np.testing.assert_array_equal(env.reset(seed), trace.observations[0])
    for step in range(steps):
        reward, obs = env.step(trace.actions[step].copy())
        assert reward == trace.rewards[step]
        np.testing.assert_array_equal(obs, trace.observations[step + 1])
    for step in (0, steps // 2, steps):
        mujoco.mj_setState(env.model, env.data, trace.states[step], STATE_SPEC)
        mujoco.mj_forward(env.model, env.data)
        np.testing.assert_allclose(env.observation(), trace.observations[step], atol=1e-12)


def test_a_trace_is_of_one_episode(executor):
    two = executor.evaluate([request("pendulum.py", SWING_UP, (1, 2), mode=REFEREE, trace=True)])[0]
    assert two.failure.startswith("invalid: a traced evaluation runs one episode") and two.trace is None


def test_a_policy_failing_in_the_episode_gives_a_note_and_no_files(executor, tmp_path):
    failed = executor.evaluate([request("pendulum.py", WRONG_ACTION_SIZE, (4,), mode=REFEREE, trace=True, steps=50)])[0]
    assert failed.failure.startswith("bad action shape") and "(step 0)" in failed.failure and failed.trace is None
    program = parametrize(WRONG_ACTION_SIZE)
    media = render_policy(executor, evaluator("pendulum.py", (4,)), program.skeleton, program.values, tmp_path, "fails", steps=50)
    assert media.plot is None and media.video is None and media.episode_seed == 4
    assert media.note.startswith("no plot or video: the policy failed in episode 0 (seed 4): bad action shape")
    assert list(tmp_path.iterdir()) == []


class Integrator(Environment):
    """A plain (non-MuJoCo) environment: no physics states, no control timestep."""

    observation_size = 2
    action_size = 1

    def reset(self, seed: int) -> np.ndarray:
        self.position = float(seed % 5)
        return np.array([self.position, 0.0])

    def step(self, action: np.ndarray) -> tuple[float, np.ndarray]:
        self.position += 0.1 * float(action[0])
        return -abs(self.position), np.array([self.position, float(action[0])])


def test_plain_environment_gives_a_plot_and_no_video(tmp_path):
    env = Integrator()
    trace = constant_trace(env, seed=3, steps=50, action=-1.0)
    assert trace.states is None and trace.control_timestep is None
    assert EpisodeTrace.from_json(trace.to_json()).states is None
    media = render_episode(env, trace, tmp_path, "integrator")
    assert media.video is None and "not a MuJoCo environment" in media.note
    assert media.episode_return == pytest.approx(trace.episode_return)
    assert Image.open(media.plot).format == "PNG"
    with pytest.raises(ValueError, match="no MuJoCo states"):
        render_video(PendulumSwingup(), trace, tmp_path / "x.mp4")


# --- the plain-data form -----------------------------------------------------------------------


def test_trace_round_trips_exactly_through_json(cheetah_trace):
    again = EpisodeTrace.from_json(cheetah_trace.to_json().encode())
    for name in ("observations", "actions", "rewards", "states"):
        np.testing.assert_array_equal(getattr(again, name), getattr(cheetah_trace, name))
    assert again.control_timestep == cheetah_trace.control_timestep
    assert not again.states.flags.writeable


def malformed(good: dict) -> list[tuple[str, object]]:
    cases = []

    def case(label, **changes):
        cases.append((label, {**good, **changes}))

    steps = len(good["rewards"])
    case("ragged", observations=[[1.0, 2.0]] + good["observations"][1:])
    case("strings", rewards=["1.5"] * steps)
    case("objects", rewards=[None] * steps)
    case("3-d", actions=[[[0.0]]] * steps)
    case("too few observations", observations=good["observations"][:-1])
    case("too many actions", actions=good["actions"] + good["actions"][:1])
    case("states rows", states=good["states"][:-1])
    case("no steps", observations=good["observations"][:1], actions=[], rewards=[], states=good["states"][:1])
    case("zero width", actions=[[]] * steps)
    case("negative timestep", control_timestep=-0.01)
    case("huge timestep", control_timestep=1e6)
    case("bool timestep", control_timestep=True)
    case("string timestep", control_timestep="0.02")
    case("too many rows", rewards=[0.0] * (trace_module.MAX_STEPS + 2))
    cases.append(("missing key", {k: v for k, v in good.items() if k != "states"}))
    cases.append(("extra key", {**good, "code": "import os"}))
    cases.append(("not an object", [good]))
    cases.append(("absent", None))
    return cases


def test_malformed_traces_are_refused(pendulum_trace):
    good = pendulum_trace.to_dict()
    for _, data in malformed(good):
        with pytest.raises(TraceError):
            EpisodeTrace.from_dict(data)
        with pytest.raises(TraceError):
            EpisodeTrace.from_json(json.dumps(data))
    text = pendulum_trace.to_json()
    for bad in (text[:-10], "not json", "[" * 100_000, text.replace("0.0", "NaN", 1), text.replace("0.0", "1e999", 1)):
        with pytest.raises(TraceError):
            EpisodeTrace.from_json(bad)


def test_oversized_json_is_refused_before_parsing(pendulum_trace):
    text = pendulum_trace.to_json()
    with pytest.raises(TraceError, match="characters"):
        EpisodeTrace.from_json(text, max_chars=len(text) - 1)


def test_video_refuses_a_trace_of_another_model(cheetah, pendulum_trace, tmp_path):
    with pytest.raises(ValueError, match="states have 2 numbers"):
        render_video(cheetah, pendulum_trace, tmp_path / "x.mp4", **SIZE)


# --- plots -------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["pendulum", "cheetah"])
def test_plot_is_a_png(name, request, tmp_path):
    trace = request.getfixturevalue(f"{name}_trace")
    path = plot_episode(trace, tmp_path / "plots" / f"{name}.png", f"{name} seed 7")
    with Image.open(path) as image:
        assert image.format == "PNG" and image.size == (1100, 900)
        image.verify()


def test_plot_handles_many_observation_dimensions(tmp_path):
    rng = np.random.default_rng(0)
    steps = 300
    trace = EpisodeTrace(
        observations=rng.normal(size=(steps + 1, 78)) * np.geomspace(1e-3, 1e3, 78),
        actions=rng.uniform(-1, 1, size=(steps, 12)),
        rewards=rng.uniform(0, 1, size=steps),
        states=None,
        control_timestep=0.02,
    )
    with Image.open(plot_episode(trace, tmp_path / "quadruped.png", "78 observations")) as image:
        assert image.format == "PNG"


def test_the_plot_shows_the_action_the_simulator_applied(pendulum, pendulum_trace, tmp_path):
    raw = np.full_like(pendulum_trace.actions, -40.0)  # a torque bounded to +-1
    applied = pendulum.applied_actions(raw)
    assert np.all(applied == pendulum.model.actuator_ctrlrange[:, 0])
    assert np.array_equal(pendulum.applied_actions(applied), applied)  # within the range: unchanged
    trace = dataclasses.replace(pendulum_trace, actions=raw)
    with Image.open(plot_episode(trace, tmp_path / "clamped.png", "clamped", applied)) as image:
        assert image.format == "PNG" and image.size == (1100, 900)
    # The applied action has the panel's scale; the raw output a scale of its own beside it.
    raw = np.where(np.arange(len(raw))[:, None] % 2, 100.0, -100.0)
    applied = pendulum.applied_actions(raw)
    figure = episode_figure(dataclasses.replace(pendulum_trace, actions=raw), "clamped", applied)
    action_axes = figure.axes[1]
    low, high = action_axes.get_ylim()
    assert -1.5 < low < -1.0 and 1.0 < high < 1.5
    [raw_axes] = [axes for axes in figure.axes if axes.get_ylabel() == "raw output (dashed)"]
    assert raw_axes.get_ylim()[1] >= 100.0


# --- videos ------------------------------------------------------------------------------------


def test_default_cameras(pendulum, cheetah):
    assert pendulum.model.camera(default_camera(pendulum.model)).name == "fixed"
    assert cheetah.model.camera(default_camera(cheetah.model)).name == "side"


def test_frame_steps_play_in_real_time():
    steps, fps = video_frame_steps(1000, 0.001)  # the A1: every 33rd state
    assert steps.step == 33 and fps == pytest.approx(1000 / 33)
    steps, fps = video_frame_steps(200, 0.02)
    assert list(steps)[-1] == 200 and len(steps) / fps >= 200 * 0.02


@pytest.mark.parametrize("name", ["pendulum", "cheetah"])
def test_mp4_video_lasts_the_episode(name, request, tmp_path, gl_backend):
    env = request.getfixturevalue(name)
    trace = request.getfixturevalue(f"{name}_trace")
    path = render_video(env, trace, tmp_path / f"{name}.mp4", **SIZE)
    assert path.suffix == ".mp4"
    frames, seconds = mp4_frames_and_seconds(path)
    assert frames == len(video_frame_steps(trace.steps, trace.control_timestep)[0])
    assert seconds >= 3.0


def test_a_video_under_a_time_budget_is_cut_short_never_a_slide_show(pendulum, pendulum_trace, tmp_path, gl_backend):
    """Too little time to draw the episode: the first seconds of it, in real time and at 15
    frames a second of simulated time or more (it used to be the whole episode at 0.5 fps)."""
    steps, rate = video_frame_steps(pendulum_trace.steps, pendulum_trace.control_timestep)
    path = render_video(pendulum, pendulum_trace, tmp_path / "short.mp4", **SIZE, max_seconds=1e-6)  # as few frames as allowed
    frames, seconds = mp4_frames_and_seconds(path)
    assert 2 <= frames < len(steps) and seconds < len(steps) / rate
    assert frames / seconds >= 0.9 * MIN_FPS


def test_gif_video_and_a_frame_that_shows_the_pendulum(pendulum, pendulum_trace, tmp_path, gl_backend):
    path = render_video(pendulum, pendulum_trace, tmp_path / "pendulum.gif", **SIZE)
    with Image.open(path) as gif:
        assert gif.format == "GIF" and gif.size == (160, 120)
        durations = []
        for index in range(gif.n_frames):
            gif.seek(index)
            durations.append(gif.info["duration"])
            if index == 0:
                first = np.asarray(gif.convert("RGB"))
    assert sum(durations) / 1000 >= 3.0
    # The pole is orange-brown on a blue scene: the first frame must show it.
    reddish = (first[..., 0].astype(int) - first[..., 2]) > 30
    assert reddish.sum() > 20


def test_render_policy_writes_plot_and_video_of_a_sandboxed_episode(executor, tmp_path, gl_backend):
    program = parametrize(SWING_UP)
    media = render_policy(executor, evaluator("pendulum.py", (5, 2)), program.skeleton, program.values, tmp_path / "best", "best", episode=1, steps=40, **SIZE)
    assert media.note is None and media.episode_seed == 2
    assert media.plot == tmp_path / "best" / PLOT_FILE and media.plot.exists()
    assert media.video.suffix == ".mp4" and media.video.stat().st_size > 0
    scored = executor.evaluate([request("pendulum.py", SWING_UP, (2,), mode=REFEREE, steps=40)])[0]
    assert media.episode_return == scored.returns[0]
    assert json.loads(json.dumps(media.as_dict()))["video"] == str(media.video)


def test_gif_without_imageio_ffmpeg(pendulum, tmp_path, gl_backend, monkeypatch):
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)  # makes its import fail
    trace = constant_trace(pendulum, seed=2, steps=20)
    path = render_video(pendulum, trace, tmp_path / "pendulum.mp4", width=64, height=48)
    assert path == tmp_path / "pendulum.gif"
    with Image.open(path) as gif:
        assert gif.n_frames == 11


def test_without_gl_the_plot_is_still_written(pendulum, pendulum_trace, tmp_path, monkeypatch):
    monkeypatch.setenv("MUJOCO_GL", "no-such-backend")  # probed in a subprocess: it fails there
    with pytest.raises(NoGLError, match="apt-get install libosmesa6"):
        render_video(pendulum, pendulum_trace, tmp_path / "x.mp4")
    media = render_episode(pendulum, pendulum_trace, tmp_path, "pendulum")
    assert isinstance(media, EpisodeMedia) and media.video is None and media.plot.exists()
    assert "\n" not in media.note and "libosmesa6" in media.note


# --- GL selection ------------------------------------------------------------------------------


def test_selected_backend_is_made_this_process_s(gl_backend):
    if USER_MUJOCO_GL:
        assert gl_backend == USER_MUJOCO_GL.strip().lower()  # the user's choice is the only one tried
    else:
        assert gl_backend in ("egl", "osmesa")
    assert os.environ["MUJOCO_GL"] == gl_backend
    from mujoco.rendering.classic import gl_context

    assert gl_context.GLContext.__module__ == f"mujoco.{gl_backend}"
    assert gl.select_gl_backend() == gl_backend  # cached: no second probe


def test_disabled_or_broken_mujoco_gl_is_reported(monkeypatch):
    monkeypatch.setenv("MUJOCO_GL", "disable")
    assert (gl.select_gl_backend(), gl.gl_unavailable_reason()) == (None, "rendering is disabled (MUJOCO_GL=disable)")
    monkeypatch.setenv("MUJOCO_GL", "nonsense")
    backend, reason = gl.select_gl_backend(), gl.gl_unavailable_reason()
    assert backend is None
    assert "MUJOCO_GL=nonsense" in reason and "apt-get install libosmesa6" in reason and "\n" not in reason


_OSMESA_FALLBACK = textwrap.dedent(
    """
    import sys
    from pathlib import Path
    import numpy as np
    from colmo.environments.pendulum import PendulumSwingup
    from colmo.render import gl
    from colmo.render.video import render_video
    from colmo.trace import TraceRecorder
    probe = gl.probe
    # EGL is refused, as on machines without it: the selection must fall back to OSMesa.
    gl.probe = lambda backend: "refused by the test" if backend == "egl" else probe(backend)
    backend = gl.select_gl_backend()
    if backend is None:
        print(gl.gl_unavailable_reason())
        sys.exit(77)
    env = PendulumSwingup()
    recorder = TraceRecorder(env)
    recorder.start(env.reset(1))
    for _ in range(160):
        recorder.step(np.ones(1), *env.step(np.ones(1)))
    print(backend, render_video(env, recorder.finish(), Path(sys.argv[1]) / "osmesa.gif", width=64, height=48))
    """
)


def test_falls_back_to_osmesa_and_renders(tmp_path):
    environment = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    result = subprocess.run(
        [sys.executable, "-c", _OSMESA_FALLBACK, str(tmp_path)],
        cwd=REPO, env=environment, capture_output=True, text=True, timeout=300,
    )
    if result.returncode == 77:
        no_gl(f"OSMesa is not installed (apt-get install libosmesa6): {result.stdout.strip()}")
    assert result.returncode == 0, result.stderr
    backend, path = result.stdout.split()[-2:]
    assert backend == "osmesa"
    with Image.open(path) as gif:
        assert gif.n_frames == 81


# --- python -m colmo.render --------------------------------------------------------------------


# A short pendulum episode: 150 steps (3 s), a small video, time limits calibrated on one training episode.
SHORT_EPISODE = ("task=pendulum", "steps=150", "width=160", "height=120", "task.episodes=1")


def run_render(*overrides: str, cwd: Path, env: dict | None = None) -> subprocess.CompletedProcess:
    """`python -m colmo.render` on `SHORT_EPISODE`."""
    command = [sys.executable, "-m", "colmo.render", *SHORT_EPISODE, *overrides]
    return subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True, timeout=300)


def test_cli_writes_a_video_and_a_plot_and_never_overwrites(tmp_path, monkeypatch, gl_backend):
    policy_file = tmp_path / "swing_up.py"
    policy_file.write_text(SWING_UP)
    out = tmp_path / "media"
    result = run_render(f"policy_file={policy_file}", f"out={out}", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    report = last_json_line(result.stdout)
    assert report["video"] == str(out / "episode.mp4") and report["plot"] == str(out / PLOT_FILE)
    assert report["note"] is None and isinstance(report["episode_return"], float) and report["seconds"] > 0
    frames, seconds = mp4_frames_and_seconds(Path(report["video"]))
    assert frames == 76 and seconds >= 3.0  # every other 20 ms step of 150, at 25 frames per second
    with Image.open(report["plot"]) as image:
        assert image.format == "PNG"
    monkeypatch.chdir(tmp_path)  # the same command again, refused before it runs: checked in process
    again = refused(colmo_render, *SHORT_EPISODE, f"policy_file={policy_file}", f"out={out}")
    assert again == (2, f"colmo: error: out={out} already holds {PLOT_FILE}: choose a new directory (nothing is overwritten)")


def test_cli_without_gl_writes_the_plot_into_the_run_directory(tmp_path):
    policy_file = tmp_path / "swing_up.py"
    policy_file.write_text(SWING_UP)
    environment = dict(os.environ, MUJOCO_GL="disable")
    result = run_render(f"policy_file={policy_file}", "hydra.run.dir=run", cwd=tmp_path, env=environment)
    assert result.returncode == 0, result.stderr
    report = last_json_line(result.stdout)
    assert report["video"] is None and report["plot"] == str(tmp_path / "run" / PLOT_FILE)
    assert report["note"] == "no video: rendering is disabled (MUJOCO_GL=disable)"
    assert result.stdout.splitlines()[-2] == report["note"]  # said in one line
    assert (tmp_path / "run" / PLOT_FILE).is_file()
