"""The bundled tasks: parity with dm_control, spec claims, and evaluation behaviour.

ball_in_cup, cheetah and quadruped must reproduce dm_control's suite tasks bit for bit (same
seed and actions give identical observations and rewards); every bundled task, pendulum and
A1 included, must match its spec's stated sizes and score policies deterministically.
"""

from __future__ import annotations

import math
import os
import re

import mujoco_menagerie
import numpy as np
import pytest
from conftest import last_json_line, run_colmo

from colmo.environments.ball_in_cup import BallInCup
from colmo.environments.cheetah import Cheetah
from colmo.environments.quadruped import Quadruped
from colmo.rollout import evaluate_policy
from colmo.specs import load_spec

TASKS = ("pendulum", "ball_in_cup", "cheetah", "quadruped", "a1")


def a1_available() -> bool:
    """Whether the A1 model can be found without downloading it."""
    return bool(os.environ.get("MENAGERIE_ROOT")) or mujoco_menagerie.Cache().is_cached(
        mujoco_menagerie.get("unitree_a1")
    )


def skip_without_a1(task: str) -> None:
    if task == "a1" and not a1_available():
        pytest.skip("Unitree A1 model not found: set MENAGERIE_ROOT to a Menagerie folder holding unitree_a1/")


@pytest.fixture(scope="module")
def suite():
    """dm_control's suite, imported only by the parity tests (it loads every domain)."""
    with pytest.MonkeyPatch.context() as patch:
        # No rendering here: without this the import probes for a display and warns.
        patch.setenv("MUJOCO_GL", os.environ.get("MUJOCO_GL", "disable"))
        from dm_control import suite
    return suite


def flat(observation) -> np.ndarray:
    from dm_control.rl.control import flatten_observation

    return flatten_observation(observation)["observations"]


PARITY = [
    # (domain, task, colmo environment, seed): one full episode each.
    ("ball_in_cup", "catch", lambda: BallInCup(observation="dm_control"), 0),
    ("ball_in_cup", "catch", lambda: BallInCup(observation="dm_control"), 5),
    ("cheetah", "run", Cheetah, 0),
    ("cheetah", "run", Cheetah, 5),
    ("quadruped", "run", lambda: Quadruped(reward="dm_control", start="random"), 0),
    ("quadruped", "run", lambda: Quadruped(reward="dm_control", start="random"), 5),
]


@pytest.mark.parametrize("domain,task,make,seed", PARITY, ids=[f"{p[0]}-{p[3]}" for p in PARITY])
def test_matches_dm_control_exactly(suite, domain, task, make, seed):
    reference = suite.load(domain, task, task_kwargs={"random": seed})
    env = make()
    spec = reference.action_spec()
    # Actions reach past the bounds too: colmo clips them, dm_control lets MuJoCo clamp them.
    low, high = spec.minimum - 0.5, spec.maximum + 0.5
    rng = np.random.default_rng(seed)

    timestep = reference.reset()
    assert np.array_equal(env.reset(seed), flat(timestep.observation))
    for step in range(env.horizon):
        action = rng.uniform(low, high)
        timestep = reference.step(action)
        reward, observation = env.step(action)
        assert np.array_equal(observation, flat(timestep.observation)), f"observation differs at step {step}"
        assert reward == timestep.reward, f"reward differs at step {step}"
    assert timestep.last(), "dm_control's episode is longer than the colmo horizon"


def test_ball_in_cup_observes_the_ball_as_the_papers_code_did(suite, examples):
    # The paper's ball height is dm_control's less 0.3 m; its published policy reads that layout.
    reference, env = suite.load("ball_in_cup", "catch", task_kwargs={"random": 2}), BallInCup()
    expected = flat(reference.reset().observation)
    expected[3] -= 0.3
    assert np.array_equal(env.reset(2), expected)
    namespace: dict = {}
    exec((examples / "paper_ball_in_cup.py").read_text(), namespace)
    assert evaluate_policy(env, namespace["policy"], range(10)).score > 500  # the paper: 755 over 1000 episodes
    assert evaluate_policy(BallInCup(observation="dm_control"), namespace["policy"], range(10)).score < 200


def test_the_quadruped_starts_upright_as_the_papers_policy_needs(examples):
    namespace: dict = {}
    exec((examples / "paper_quadruped.py").read_text(), namespace)
    upright = Quadruped()
    assert upright.reset(3)[47] == pytest.approx(1.0)  # torso_upright
    assert evaluate_policy(upright, namespace["policy"], range(6)).score > 150  # the paper: 181.3
    assert evaluate_policy(Quadruped(start="random"), namespace["policy"], range(6)).score < 120


def test_quadruped_joint_noise_makes_upright_starts_differ_and_none_touches_the_floor():
    plain, noisy = Quadruped(), Quadruped(joint_noise=0.05)
    assert np.array_equal(plain.reset(1), plain.reset(2))  # without it, every upright episode is one episode
    first, second = noisy.reset(1), noisy.reset(2)
    assert not np.array_equal(first, second)
    rest = noisy.model.qpos0[7:]  # the 16 hinge angles follow the root's 7 coordinates
    for seed in range(5):
        noisy.reset(seed)
        offsets = noisy.data.qpos[7:] - rest
        assert np.all(np.abs(offsets) <= 0.05) and np.any(np.abs(offsets) > 0.01)
        assert noisy.data.ncon == 0 and noisy.data.xmat[noisy.model.body("torso").id, 8] == pytest.approx(1.0)  # level, above the floor
    assert np.array_equal(noisy.reset(1), first)  # the draw is the episode seed's


@pytest.mark.parametrize("noise", [-0.01, 0.6])
def test_quadruped_joint_noise_out_of_range_is_refused(noise):
    with pytest.raises(ValueError, match="joint_noise must be in"):
        Quadruped(joint_noise=noise)


def test_cheetah_reward_is_the_papers(suite):
    """The paper's clip(v / 10, 0, 1), v dm_control's `speed()`: equal up to rounding."""
    reference = suite.load("cheetah", "run", task_kwargs={"random": 3})
    env = Cheetah()
    reference.reset()
    env.reset(3)
    rng = np.random.default_rng(3)
    rewards = []
    for _ in range(300):
        action = rng.uniform(-1, 1, 6) + 0.8  # a push to get some nonzero speeds
        reference.step(action)
        reward, _ = env.step(action)
        rewards.append(reward)
        assert reward == pytest.approx(min(max(reference.physics.speed() / 10, 0.0), 1.0), abs=1e-15)
    assert max(rewards) > 0, "the check never saw a positive speed"


def test_quadruped_paper_reward(suite):
    """reward="paper" is clip(v / 10, 0, 1) of dm_control's torso velocity, exactly."""
    reference = suite.load("quadruped", "run", task_kwargs={"random": 2})
    env = Quadruped(start="random")  # dm_control's start, to compare step by step
    reference.reset()
    env.reset(2)
    rng = np.random.default_rng(2)
    for _ in range(100):
        action = rng.uniform(-1, 1, 12)
        reference.step(action)
        reward, _ = env.step(action)
        assert reward == min(max(reference.physics.torso_velocity()[0] / 10, 0.0), 1.0)


def test_quadruped_rejects_unknown_reward_and_start():
    with pytest.raises(ValueError, match="unknown start"):
        Quadruped(start="sideways")
    with pytest.raises(ValueError, match="unknown reward"):
        Quadruped(reward="fast")


@pytest.fixture(scope="module", params=TASKS)
def task(request):
    """(spec, environment) for one bundled task, built once per module."""
    skip_without_a1(request.param)
    spec = load_spec(f"{request.param}.py")  # a bundled spec, by name
    return spec, spec.make_environment()


def test_sizes_match_the_spec(task):
    spec, env = task
    # The starter's docstring is what the language model reads: "obs size is N ... return shape is (M,)".
    claimed = re.search(r"obs size is (\d+).*return shape is \(([\d,\s]*)\)", spec.starter_code, re.S)
    assert claimed, "the starter policy's docstring does not state the sizes"
    assert env.observation_size == int(claimed.group(1))
    assert env.action_size == math.prod(int(n) for n in claimed.group(2).replace(",", " ").split())
    assert f"Observation (size {env.observation_size})" in spec.description
    assert env.reset(0).shape == (env.observation_size,)


def test_starter_policy_scores_deterministically(task):
    spec, env = task
    namespace: dict = {}
    exec(spec.starter_code, namespace)
    seeds = [11, 12]
    first = evaluate_policy(env, namespace["policy"], seeds)
    again = evaluate_policy(env, namespace["policy"], seeds)
    fresh = evaluate_policy(spec.make_environment(), namespace["policy"], seeds)
    assert first.failure is None
    assert len(first.returns) == 2 and all(math.isfinite(r) for r in first.returns)
    assert first == again == fresh


def test_a_replayed_reset_is_the_first_reset(task):
    # A seed's second reset restores the state the first one kept: the same episode follows.
    _, env = task
    actions = np.random.default_rng(0).uniform(-1, 1, (100, env.action_size))

    def episode(seed: int) -> np.ndarray:
        observations = [env.reset(seed)] + [env.step(action)[1] for action in actions]
        return np.concatenate(observations)

    first = episode(7)
    episode(8)
    assert np.array_equal(episode(7), first)


def resident_bytes() -> int:
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def test_the_initial_states_a_task_keeps_are_small(task):
    # Each seed's initial state is kept for the next candidate; held-out scoring resets one
    # environment with hundreds of seeds, so what it keeps must not be a whole MjData (~25 MB).
    _, env = task
    before = resident_bytes()
    for seed in range(1000):
        env.reset(seed)
    assert resident_bytes() - before < 100 * 2**20


def raises(obs):
    raise ZeroDivisionError("boom")


BAD_POLICIES = {
    # name: (policy for an action size, the failure reason it must produce)
    "nan": (lambda size: lambda obs: np.full(size, np.nan), "non-finite action"),
    "wrong-shape": (lambda size: lambda obs: np.zeros(size + 1), "bad action shape"),
    "raises": (lambda size: raises, "exception: ZeroDivisionError: boom"),
}


@pytest.mark.parametrize("bad", BAD_POLICIES)
def test_bad_policy_fails_with_a_reason(task, bad):
    _, env = task
    make_policy, reason = BAD_POLICIES[bad]
    evaluation = evaluate_policy(env, make_policy(env.action_size), [0])
    assert evaluation.failure is not None and reason in evaluation.failure
    assert evaluation.score == -math.inf


def test_a1_start_and_reward():
    skip_without_a1("a1")
    from colmo.environments.a1 import UnitreeA1

    env = UnitreeA1()
    assert env.model.opt.timestep == 0.001 and env.n_sub_steps == 1
    home = env.model.key("home").qpos[7:]
    obs = env.reset(4)
    assert np.all(np.abs(obs[:12] - home) <= 0.05) and not np.array_equal(obs[:12], home)
    rng = np.random.default_rng(4)
    for _ in range(200):
        reward, obs = env.step(home + rng.normal(0, 0.3, 12))
        assert reward == min(max(-obs[24] / 10, 0.0), 1.0)


def test_colmo_evaluate_scores_the_papers_1000_held_out_episodes(tmp_path, examples):
    # The paper scores the pendulum over 1000 episodes; a worker resets hundreds of seeds for it.
    run = run_colmo("colmo.heldout", "task=pendulum", f"policy_file={examples / 'paper_pendulum.py'}", "episodes=1000", cwd=tmp_path, timeout=900)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    result = last_json_line(run.stdout)
    assert result["failure"] is None and len(result["returns"]) == 1000
    assert result["score"] == pytest.approx(np.mean(result["returns"]), abs=1e-3)
