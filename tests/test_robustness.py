"""Model mismatch (`task.perturb`) and the robustness report of `colmo-evaluate robustness=true` and of
a search's finish (`finish.robustness`)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import compose, last_json_line, run_colmo
from mlflow import MlflowClient

from colmo.config import FinishConfig, PerturbConfig
from colmo.environments.perturb import PerturbedEnvironment, with_perturbation
from colmo.errors import ConfigError
from colmo.finish_plan import RefereeCost, plan_finish
from colmo.help import help_text
from colmo.rollout import episode_seeds, evaluate_policy
from colmo.specs import load_spec
from colmo.store import run_settings

SEEDS = episode_seeds(3, 3)
STEPS = 150
ACTIONS = np.random.default_rng(7).uniform(-1, 1, (STEPS, 1))  # one fixed open-loop action sequence
EVERYTHING = PerturbConfig(mass=0.3, damping=0.3, frictionloss=0.3, friction=0.3, gain=0.3, obs_noise=0.05, action_noise=0.1)


def pendulum(perturb: PerturbConfig | None = None):
    options = {} if perturb is None else with_perturbation({}, perturb)
    return load_spec("pendulum.py").make_environment(**options)


def trajectory(env, seed: int, actions: np.ndarray = ACTIONS) -> np.ndarray:
    """Observations of one episode under `actions`, its end included (which restores the model)."""
    observations = [env.reset(seed)]
    observations += [env.step(action)[1] for action in actions]
    env.check_episode()
    return np.array(observations)


def swing(obs: np.ndarray) -> float:
    """The paper's pendulum policy (examples/paper_pendulum.py): it earns reward a perturbation changes."""
    angle = np.arctan2(-obs[1], obs[0])
    return float(np.sign(obs[2]) if abs(angle) > np.pi / 6.512 else 9.437 * np.sin(angle) - 2.746 * obs[2])


def test_perturbation_off_leaves_the_environment_and_its_scores_untouched():
    assert with_perturbation({"angle_bound": 0.3}, PerturbConfig()) == {"angle_bound": 0.3}
    assert not isinstance(pendulum(PerturbConfig()), PerturbedEnvironment)
    nominal = evaluate_policy(pendulum(), swing, SEEDS)
    assert nominal.score > 0
    # The wrapper itself at magnitude 0 (every factor drawn, each exactly 1) changes no bit either.
    zero = PerturbedEnvironment(pendulum(), PerturbConfig())
    assert evaluate_policy(zero, swing, SEEDS).returns == nominal.returns
    assert np.array_equal(trajectory(zero, SEEDS[0]), trajectory(pendulum(), SEEDS[0]))


def test_perturbed_episodes_are_deterministic_per_seed_and_differ_from_nominal():
    nominal = trajectory(pendulum(), SEEDS[0])
    first = trajectory(pendulum(EVERYTHING), SEEDS[0])
    again = trajectory(pendulum(EVERYTHING), SEEDS[0])
    assert np.array_equal(first, again)
    assert not np.allclose(first, nominal)
    # The environment's own draw (the initial angle) is untouched: only noise separates the first observations.
    assert np.allclose(first[0], nominal[0], atol=0.5)
    assert not np.allclose(trajectory(pendulum(EVERYTHING), SEEDS[1]), first)
    # One environment replaying a seed after another seed's episode gives the same episode.
    env = pendulum(EVERYTHING)
    trajectory(env, SEEDS[1])
    assert np.array_equal(trajectory(env, SEEDS[0]), first)


@pytest.mark.parametrize("factor", ["mass", "damping", "gain", "obs_noise", "action_noise"])
def test_each_factor_alone_changes_the_episode(factor):
    alone = PerturbConfig(**{factor: 0.3})
    assert not np.allclose(trajectory(pendulum(alone), SEEDS[0]), trajectory(pendulum(), SEEDS[0]))


def test_the_model_is_perturbed_during_the_episode_and_restored_after_it():
    fields = ("body_mass", "body_inertia", "dof_damping", "geom_friction", "actuator_gainprm", "actuator_biasprm")
    env = load_spec("quadruped.py").make_environment(**with_perturbation({}, EVERYTHING))
    nominal = {name: getattr(env.model, name).copy() for name in fields}
    env.reset(SEEDS[0])
    during = {name: getattr(env.model, name).copy() for name in fields}
    for _ in range(3):
        env.step(np.zeros(env.action_size))
    env.check_episode()
    for name in fields:
        assert not np.array_equal(during[name], nominal[name]), name
        assert np.array_equal(getattr(env.model, name), nominal[name]), name


def test_environments_of_a_task_each_have_their_own_model():
    """A task's model is compiled once per process and copied for each environment: one whose
    model a perturbation changes leaves the others, and their episodes, nominal."""
    expected = trajectory(pendulum(), SEEDS[0])
    perturbed, other = pendulum(EVERYTHING), pendulum()
    perturbed.reset(SEEDS[0])  # its model perturbed until the episode ends
    assert not np.array_equal(perturbed.model.body_mass, other.model.body_mass)
    assert np.array_equal(trajectory(other, SEEDS[0]), expected)
    assert np.array_equal(trajectory(pendulum(), SEEDS[0]), expected)


def test_a_delay_of_k_steps_applies_each_action_k_steps_late():
    k = 3
    delayed = trajectory(pendulum(PerturbConfig(delay=k)), SEEDS[0])
    # The pendulum's actuators hold their reset control, 0, until the first action arrives.
    shifted = np.concatenate((np.zeros((k, 1)), ACTIONS[:-k]))
    assert np.array_equal(delayed, trajectory(pendulum(), SEEDS[0], shifted))


def test_out_of_range_magnitudes_are_configuration_errors():
    with pytest.raises(ConfigError, match="task.perturb.mass"):
        PerturbConfig(mass=1.0)
    with pytest.raises(ConfigError, match="task.perturb.delay"):
        PerturbConfig(delay=-1)
    with pytest.raises(ConfigError, match=r"finish.robustness_magnitudes must lie in \(0, 1\), got \[1.5\]"):
        FinishConfig(robustness_magnitudes=[1.5])
    with pytest.raises(ConfigError, match="finish.robustness_episodes must be >= 1"):
        FinishConfig(robustness_episodes=0)


def test_colmo_evaluate_robustness_reports_each_magnitude_nominal_first_and_repeats(tmp_path, examples):
    overrides = (
        "task=pendulum", f"policy_file={examples / 'paper_pendulum.py'}", "robustness=true", "episodes=3",
        "robustness_episodes=2", "robustness_magnitudes=[0.1,0.4]", "robustness_delays=[2]",
    )
    results = []
    for _ in range(2):
        run = run_colmo("colmo.heldout", *overrides, cwd=tmp_path, timeout=600)
        assert run.returncode == 0, run.stderr[-2000:]
        results.append(last_json_line(run.stdout))
    first, second = results
    assert (first["episodes"], len(first["returns"]), first["robustness_episodes"]) == (3, 3, 2)  # the held-out score's, the grid's
    assert [entry["magnitude"] for entry in first["robustness"]] == [0.0, 0.1, 0.4]
    assert [entry["delay_steps"] for entry in first["delay"]] == [0, 2]
    assert first["robustness"] == second["robustness"] and first["delay"] == second["delay"]
    nominal = first["robustness"][0]
    assert len({nominal[factor] for factor in nominal if factor != "magnitude"}) == 1
    assert first["robustness"][2]["all"] != nominal["all"]
    assert "magnitude" in run.stdout and len(list(tmp_path.rglob("robustness.png"))) == 2


def test_each_point_has_its_interval_and_its_paired_change_from_nominal():
    from scipy import stats

    from colmo.evaluation import Evaluation
    from colmo.robustness import robustness_report, table

    nominal = (100.0, 300.0, 500.0, 700.0)

    def score(perturb: PerturbConfig) -> Evaluation:
        # a point loses 10 + 20 * magnitude on every episode: its change is exact, its score as spread as nominal
        loss = 0.0 if perturb == PerturbConfig() else 10.0 + 20.0 * (perturb.mass or perturb.delay or 0.5)
        return Evaluation(tuple(r - loss for r in nominal))

    report = robustness_report(score, [0.1], [2])
    saved = report.as_json()
    expected = stats.t.ppf(0.975, 3) * np.std(nominal, ddof=1) / 2
    assert saved["robustness_interval"][0]["all"] == pytest.approx(expected)
    assert saved["robustness_change"][1]["mass"] == pytest.approx(-12.0) and saved["robustness_change_interval"][1]["mass"] == pytest.approx(0.0)
    assert saved["delay_change"][1]["score"] == pytest.approx(-50.0)
    assert saved["confidence"] == 0.95 and saved["episodes"] == 4
    assert f"388.0±{expected:.1f}" in table(report) and "-12.0±0.0" in table(report)


def test_the_finish_plans_the_robustness_report_whole_or_not_at_all():
    grid = ("finish.robustness_magnitudes=[0.1,0.2]", "finish.robustness_delays=[1]", "finish.robustness_episodes=3")
    quiet = ("finish.simplify=false", "finish.render=false", "finish.top=1", "heldout.episodes=2")
    assert plan_finish(compose("search", *quiet, *grid), RefereeCost(1.0, 0.0), 2).robustness_seconds == 0  # off by default
    on = compose("search", *quiet, *grid, "finish.robustness=true")
    full = plan_finish(on, RefereeCost(1.0, 0.0), 2)
    # 1 + 8 x 2 + 1 = 18 points of 3 episodes on 2 workers (2 rounds), each episode 1.5 s on a loaded machine
    assert full.robustness_seconds == pytest.approx(18 * 2 * 1.5) and full.seconds == pytest.approx(full.heldout_seconds + 54)
    assert "robustness report" in full.describe(on) and not full.reduced
    short = plan_finish(on, RefereeCost(1.0, 0.0), 2, available=30.0)
    assert short.reduced and short.robustness_seconds == 0 and "no robustness report" in short.describe(on)
    # Short of time, the report keeps its whole cost where that fits in an equal share (here a half: held-out,
    # robustness), and the held-out scores of 3 programs over 100 episodes (225 s) get the rest.
    heavy = compose("search", *quiet, *grid, "finish.robustness=true", "finish.top=3", "heldout.episodes=100")
    kept = plan_finish(heavy, RefereeCost(1.0, 0.0), 2, available=110.0)
    assert kept.reduced and kept.robustness_seconds == 54 and kept.seconds <= 110
    assert plan_finish(heavy, RefereeCost(1.0, 0.0), 2, available=100.0).robustness_seconds == 0


def test_a_search_with_finish_robustness_saves_and_logs_its_best_policys_report(tmp_path):
    run = run_colmo(
        "colmo", "task=pendulum", "search.max_samples=2", "llm.batch_size=2", "gfo=none", "task.episodes=1",
        "heldout.episodes=1", "finish.top=1", "finish.render=false", "finish.simplify=false",
        "executor.workers=1", "search.progress=false", "finish.robustness=true", "finish.robustness_episodes=2",
        # A precision no 4 episodes reach: the report doubles its episodes once, to the cap.
        "finish.robustness_precision=0.0001", "finish.robustness_max_episodes=4",
        "finish.robustness_magnitudes=[0.1]", "finish.robustness_delays=[]", f"hydra.run.dir={tmp_path / 'run'}",
        cwd=tmp_path, timeout=600,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    robustness = summary["robustness"]
    assert robustness["files"] == ["robustness.json", "robustness.csv", "robustness.png"]
    assert all((tmp_path / "run" / name).is_file() for name in robustness["files"])
    saved = json.loads((tmp_path / "run" / "robustness.json").read_text())
    assert [entry["magnitude"] for entry in saved["robustness"]] == [0.0, 0.1]
    assert saved["episodes"] == robustness["episodes"] == 4
    assert robustness["robustness_nominal"] == saved["robustness"][0]["all"]
    assert robustness["robustness_all_10"] == saved["robustness"][1]["all"]
    assert robustness["robustness_worst"] == min(value for entry in saved["robustness"] for name, value in entry.items() if name != "magnitude")
    client = MlflowClient(f"sqlite:///{tmp_path / 'mlruns.db'}")
    (logged,) = client.search_runs([client.get_experiment_by_name("pendulum").experiment_id])
    for name in ("robustness_nominal", "robustness_worst", "robustness_all_10", "robustness_failures"):
        assert logged.data.metrics[name] == pytest.approx(robustness[name], rel=5e-4), name  # logged at 4 significant digits
    assert {f.path for f in client.list_artifacts(logged.info.run_id, "robustness")} == {f"robustness/{name}" for name in robustness["files"]}


def test_help_lists_each_perturbation_field_with_its_value():
    text = help_text("search", "", ["task=cheetah", "task.perturb.mass=0.2"])
    assert "  task.perturb.*:\n" in text and "  task.perturb.mass=0.2\n" in text and "  task.perturb.delay=0\n" in text
    assert "task.perturb={" not in text


def test_a_search_under_a_perturbation_is_a_run_of_its_own():
    nominal, perturbed = run_settings(compose("search")), run_settings(compose("search", "task.perturb.mass=0.2"))
    assert "task.perturb" not in nominal  # runs from before task.perturb existed still resume
    assert perturbed["task.perturb"]["mass"] == 0.2 and perturbed != nominal


def test_with_a_precision_every_point_gets_more_episodes_until_its_interval_holds_it():
    """Episode i returns 500 ± 100 (a fixed spread), every point alike less its loss: at 4
    episodes the interval is ±183.7 (37% of nominal), at 8 ±89.4, at 16 ±55.0 (11%), at 32
    ±36.6, within 10%: there it stops; the same episodes for every point, so the changes stay
    paired (exact).
    A point that fails is not run again; without a precision, or at the cap, no more are added."""
    from colmo.evaluation import Evaluation
    from colmo.robustness import adaptive_report, precise

    asked: list[tuple[str, int, int]] = []

    def score(perturb: PerturbConfig, start: int, stop: int) -> Evaluation:
        asked.append((repr(perturb), start, stop))
        if perturb.delay == 3:
            return Evaluation(failure="exception: ValueError: x (step 1)")
        loss = 0.0 if perturb == PerturbConfig() else 50.0
        return Evaluation(tuple(500.0 + 100.0 * (-1) ** i - loss for i in range(start, stop)))

    report = adaptive_report(score, [0.1], [2, 3], episodes=4, precision=0.1, max_episodes=100)
    assert len(report.nominal.returns) == 32 and precise(report, 0.1)
    assert all(len(point.evaluation.returns) == 32 for point in report.points if point.score is not None)
    assert report.change(report.point("mass", 0.1)) == pytest.approx(-50.0) and report.change_interval(report.point("mass", 0.1)) == pytest.approx(0.0)
    assert sorted({(start, stop) for _, start, stop in asked}) == [(0, 4), (4, 8), (8, 16), (16, 32)]
    assert sum(1 for key, *_ in asked if "delay=3" in key) == 1  # failed at once: never again
    assert len(adaptive_report(score, [0.1], [], episodes=4).nominal.returns) == 4  # no precision: as asked
    assert len(adaptive_report(score, [0.1], [], episodes=4, precision=0.01, max_episodes=12).nominal.returns) == 12  # the cap
    # Out of time: asked before each doubling with the episodes scored and those it would add.
    questions = []
    timed = adaptive_report(
        score, [0.1], [], episodes=4, precision=0.01, max_episodes=100, may_add=lambda scored, added: questions.append((scored, added)) or scored < 8,
    )
    assert len(timed.nominal.returns) == 8 and questions == [(4, 4), (8, 8)]
