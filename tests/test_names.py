"""Names that do not lie (issue 38 part 3): the prompt shows the observation's names as code, a
policy whose variables contradict them is flagged in its best_policy.py header, and the
simplified policy takes the spec's names where renaming cannot change what it does."""

from __future__ import annotations

import dataclasses

import pytest

from colmo.names import bound_entries, misnamed, renamed
from colmo.record import Summary
from colmo.specs import SpecError, load_spec
from colmo.store import write_outputs

PENDULUM = ("cos_theta", "sin_theta", "angular_velocity")


def policy(*lines: str) -> str:
    return "import numpy as np\n\ndef policy(obs):\n" + "".join(f"    {line}\n" for line in lines) + "    return 0.0\n"


@pytest.mark.parametrize("line, flagged", [
    ("theta = obs[0]", ["`theta` holds obs[0], which the task calls cos_theta"]),  # every entry is about θ: only "cos" tells
    ("angle = obs[0]", ["`angle` holds obs[0], which the task calls cos_theta"]),
    ("sin_theta = obs[0]", ["`sin_theta` holds obs[0], which the task calls cos_theta"]),
    ("velocity = obs[1]", ["`velocity` holds obs[1], which the task calls sin_theta"]),
    ("theta, cos_theta, omega = obs", ["`theta` holds obs[0], which the task calls cos_theta", "`cos_theta` holds obs[1], which the task calls sin_theta"]),
    ("cos_theta = obs[0]", []),
    ("cosTheta = obs[0]", []),
    ("c = obs[0]", []),  # says nothing of what it holds
    ("omega = obs[2]", []),  # an angular velocity
    ("theta_dot = obs[2]", []),
    ("error = obs[2] - 1.0", []),  # not an entry of the observation
], ids=lambda value: value if isinstance(value, str) else "")
def test_pendulum_names(line, flagged):
    assert misnamed(policy(line), PENDULUM) == flagged


def test_cheetah_legs_and_joints_are_told_apart():
    names = load_spec("cheetah.py").observation_names
    code = policy("thigh_angle = obs[2]", "front_thigh = obs[2]", "back_thigh_velocity = obs[2]", "forward_velocity = obs[8]")
    assert misnamed(code, names) == [
        "`front_thigh` holds obs[2], which the task calls back_thigh_angle",
        "`back_thigh_velocity` holds obs[2], which the task calls back_thigh_angle",
    ]


def test_only_entries_bound_straight_from_the_observation_are_read():
    code = policy("a = obs[0]", "b = obs[-1]", "c = obs[0:2]", "d, e = obs[0], obs[1]", "f = obs")
    assert bound_entries(code) == [("a", 0)]
    assert misnamed(policy("theta = obs[0]"), ()) == []  # a spec that names nothing flags nothing


def test_the_prompt_states_the_observation_as_code():
    spec = load_spec("pendulum.py")
    assert spec.observation_names == PENDULUM
    assert spec.prompt_text == spec.description + "\n\nThe observation, in code: `cos_theta, sin_theta, angular_velocity = obs`."
    assert load_spec("quadruped.py").prompt_text == load_spec("quadruped.py").description  # it names nothing


def test_a_spec_s_observation_names_must_be_identifiers(tmp_path):
    source = (load_spec("pendulum.py").path).read_text().replace('"cos_theta",', '"cos theta",')
    (tmp_path / "bad.py").write_text(source)
    with pytest.raises(SpecError, match="OBSERVATION_NAMES must be a tuple of Python identifiers"):
        load_spec(str(tmp_path / "bad.py"))


def test_best_policy_header_names_the_misleading_variables(tmp_path):
    values = dict(
        task="pendulum", best_score=3.0, best_heldout_score=2.5, best_key="k1", best_code=policy("theta = obs[0]"), best_so_far=((0, 3.0),),
        stop_reason="max_samples", run_dir=str(tmp_path), misnamed=("`theta` holds obs[0], which the task calls cos_theta",),
    )
    required = [f for f in dataclasses.fields(Summary) if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING]
    summary = Summary(**{f.name: values.get(f.name, 0) for f in required}, **{k: v for k, v in values.items() if k not in {f.name for f in required}})
    write_outputs(summary, tmp_path)
    header = (tmp_path / "best_policy.py").read_text().splitlines()[:2]
    assert header[1] == "# misleading name: `theta` holds obs[0], which the task calls cos_theta"


def test_a_misnamed_variable_takes_the_spec_s_name_and_does_the_same():
    code = policy("theta = obs[0]", "velocity = obs[2]", "u = -2.0 * velocity if theta > 0.9 else np.sign(velocity)")
    new, said = renamed(code, PENDULUM)
    assert said == ["renamed `theta` to `cos_theta`: it holds obs[0], which the task calls cos_theta"]
    assert "cos_theta = obs[0]" in new and "if cos_theta > 0.9" in new and "theta" not in new.replace("cos_theta", "")
    namespace_old, namespace_new = {}, {}
    exec(code, namespace_old)
    exec(new, namespace_new)
    for obs in ([1.0, 0.0, 0.5], [0.0, 1.0, -2.0]):
        assert namespace_old["policy"](obs) == namespace_new["policy"](obs)


@pytest.mark.parametrize("code", [
    policy("theta = obs[0]", "theta = theta * 2.0"),  # bound twice: the name would hold something else later
    policy("theta = obs[0]", "cos_theta = 1.0"),  # the spec's name is taken
    "def helper(theta):\n    return theta\n\ndef policy(obs):\n    theta = obs[0]\n    return helper(theta)\n",  # a helper's argument
    "theta = 0.5\n\ndef policy(obs):\n    global theta\n    theta = obs[0]\n    return theta\n",  # a global
    policy("theta = obs[0]", "u = [theta for theta in obs]"),  # a comprehension's
], ids=["rebound", "name taken", "helper argument", "global", "comprehension"])
def test_a_name_is_left_where_renaming_could_change_the_program(code):
    assert renamed(code, PENDULUM) == (code, [])


def test_the_simplified_policy_takes_the_spec_s_names(tmp_path):
    from conftest import last_json_line, run_colmo

    policy_file = tmp_path / "policy.py"
    policy_file.write_text(
        "def policy(obs):\n    angle = obs[0]\n    sin_theta = obs[1]\n    omega = obs[2]\n"
        "    if angle < 0.0:\n        return 1.0 if omega > 0.0 else -1.0\n    return -10.0 * sin_theta - 1.0 * omega\n"
    )
    result = run_colmo(
        "colmo.simplify", f"policy_file={policy_file}", "task=pendulum", "task.episodes=2", "heldout.episodes=2", "gfo=none",
        "simplify.tolerance=0.0", "executor.workers=2", cwd=tmp_path,
    )
    assert result.returncode == 0, result.stderr
    summary = last_json_line(result.stdout)
    assert "cos_theta = obs[0]" in summary["code"] and "angle" not in summary["code"], summary["code"]
    assert summary["steps"][-1]["description"] == "renamed `angle` to `cos_theta`: it holds obs[0], which the task calls cos_theta"
    scores = [summary["score_initial"]] + [step["score"] for step in summary["steps"]]
    assert scores[-1] == scores[-2] == summary["score"]  # renaming changes no score
