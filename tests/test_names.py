"""Names that do not lie (issue 38 part 3): the prompt shows the observation's names as code, and a
policy whose variables contradict them is flagged in its best_policy.py header."""

from __future__ import annotations

import dataclasses

import pytest

from colmo.names import bound_entries, misnamed
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
