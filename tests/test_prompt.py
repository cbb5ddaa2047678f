"""Prompt rendering (paper Fig. 3): versions in ascending score, renaming, helpers, chat form."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from colmo.config import DatabaseConfig
from colmo.database import ProgramDatabase, Selection, StoredProgram
from colmo.program import instantiate, parametrize
from colmo.prompt import build_prompt
from colmo.specs import load_spec

DESCRIPTION = "Balance the pole.\n\nObservation: [angle, velocity]."
LOW = StoredProgram("k-low", "import numpy as np\n\ndef policy(obs):\n    return 0.0", 1.0, 2, 5)
HIGH = StoredProgram("k-high", "import numpy as np\n\ndef policy(obs):\n    return -2.5 * obs[0] - 0.3 * obs[1]", 4.0, 2, 9)

EXPECTED = '''"""Balance the pole.

Observation: [angle, velocity].

On every iteration, improve policy_v1 over the policy_vX methods from previous iterations.
policy_v2 must differ from every version above.
policy_v0 ignores its observation: policy_v2 should compute its action from the observation.
"""

import numpy as np


def policy_v0(obs):
    return 0.0


def policy_v1(obs):
    """Improved version of policy_v0."""
    return -2.5 * obs[0] - 0.3 * obs[1]


def policy_v2(obs):
    """Improved version of policy_v1."""
'''


def stored(code: str, score: float, key: str = "k") -> StoredProgram:
    return StoredProgram(key, code, score, 0, 0)


def test_two_programs_exact_text_and_fields():
    prompt = build_prompt(DESCRIPTION, Selection(2, [LOW, HIGH]))
    assert prompt.text == EXPECTED
    assert prompt.programs == [LOW.code, HIGH.code]
    assert prompt.parent_keys == ["k-low", "k-high"]
    assert prompt.island == 2


def test_chat_messages_hold_the_same_programs_and_ask_for_the_next_version():
    prompt = build_prompt(DESCRIPTION, Selection(2, [LOW, HIGH]))
    assert [m["role"] for m in prompt.messages] == ["system", "user"]
    system, user = (m["content"] for m in prompt.messages)
    for phrase in ("control engineer", "`policy(obs)`", "```python", "only numpy and math", "not a copy"):
        assert phrase in system
    context = EXPECTED[: EXPECTED.index("\n\n\ndef policy_v2")]
    assert user == (
        f"```python\n{context}\n```\n\nWrite policy_v2, a new version that should score higher than policy_v1 and differs from every version above. "
        "policy_v0 ignores its observation: policy_v2 should compute its action from the observation. Name it `policy` in your answer."
    )


def test_pendulum_starter_from_the_database():
    spec = load_spec("pendulum.py")
    program = parametrize(spec.starter_code)
    starter = StoredProgram(program.key, instantiate(program.skeleton, program.values), 0.0, 0, -1)
    selection = ProgramDatabase(DatabaseConfig(num_islands=3), starter, seed=0).select()
    prompt = build_prompt(spec.description, selection)
    assert prompt.text == (
        f'"""{spec.description}\n\n'
        "On every iteration, improve policy_v0 over the policy_vX methods from previous iterations.\n"
        "policy_v1 must differ from every version above.\n"
        "policy_v0 ignores its observation: policy_v1 should compute its action from the observation.\n"
        '"""\n\n'
        "import numpy as np\n\n\n"
        "def policy_v0(obs):\n    action = 0.0\n    return action\n\n\n"
        'def policy_v1(obs):\n    """Improved version of policy_v0."""\n'
    )
    assert prompt.parent_keys == [program.key] and prompt.island == selection.island


def test_first_version_keeps_its_docstring_later_ones_get_improved_version_of():
    codes = [
        'def policy(obs):\n    """Returns a control action."""\n    return 0.0',
        'def policy(obs):\n    """Something else."""\n    return 1.0',
        "def policy(obs):\n    return 2.0",
    ]
    text = build_prompt("Task.", Selection(0, [stored(c, float(i)) for i, c in enumerate(codes)])).text
    assert 'def policy_v0(obs):\n    """Returns a control action."""\n    return 0.0\n' in text
    assert 'def policy_v1(obs):\n    """Improved version of policy_v0."""\n    return 1.0\n' in text
    assert 'def policy_v2(obs):\n    """Improved version of policy_v1."""\n    return 2.0\n' in text
    assert "Something else" not in text
    assert text.endswith('def policy_v3(obs):\n    """Improved version of policy_v2."""\n')
    assert "improve policy_v2 over the policy_vX methods" in text


def test_renaming_covers_recursion_but_not_attributes_or_strings():
    code = 'def policy(obs, depth=2.0):\n    if depth <= 0:\n        return obs.policy + len("policy")\n    return policy(obs, depth - 1.0)'
    text = build_prompt("Task.", Selection(0, [stored("def policy(obs):\n    return 0.0", 0.0), stored(code, 1.0)])).text
    assert (
        'def policy_v1(obs, depth=2.0):\n    """Improved version of policy_v0."""\n    if depth <= 0:\n'
        '        return obs.policy + len(\'policy\')\n    return policy_v1(obs, depth - 1.0)\n'
    ) in text
    # The next version takes the signature of the best program shown.
    assert text.endswith('def policy_v2(obs, depth=2.0):\n    """Improved version of policy_v1."""\n')


HELPERS_V0 = """import math
LIMIT = 1.0

def wrap(angle):
    return (angle + math.pi) % (2 * math.pi) - math.pi

def clip(u):
    return max(-LIMIT, min(LIMIT, u))

def control(x):
    return clip(-x)

def policy(obs):
    return control(wrap(obs[0]))
"""

# Same LIMIT, wrap and control text, but clip differs, so control (which calls it) differs too.
HELPERS_V1 = '''"""Module docstrings are dropped."""
import math
from math import pi
LIMIT = 1.0

def control(x):
    return clip(-x)

def wrap(angle):
    return (angle + math.pi) % (2 * math.pi) - math.pi

def clip(u):
    return np.clip(u, -LIMIT, LIMIT)

def policy(obs):
    return control(wrap(obs[0]) - pi)
'''


def test_helpers_are_shown_once_and_conflicting_ones_get_a_version_suffix():
    text = build_prompt("Task.", Selection(0, [stored(HELPERS_V0, 1.0), stored(HELPERS_V1, 2.0)])).text
    body = text[text.index('"""\n\n') + 5 :]
    assert body == '''import numpy as np
import math
from math import pi


LIMIT = 1.0


def wrap(angle):
    return (angle + math.pi) % (2 * math.pi) - math.pi


def clip(u):
    return max(-LIMIT, min(LIMIT, u))


def control(x):
    return clip(-x)


def control_v1(x):
    return clip_v1(-x)


def clip_v1(u):
    return np.clip(u, -LIMIT, LIMIT)


def policy_v0(obs):
    return control(wrap(obs[0]))


def policy_v1(obs):
    """Improved version of policy_v0."""
    return control_v1(wrap(obs[0]) - pi)


def policy_v2(obs):
    """Improved version of policy_v1."""
'''


# A program an answer wrote that kept the versions it was shown, and calls them (sample 134 of
# docs/llm-gfo-vs-none/runs/gfo-none/s1): shown as a later version, its helpers must not be
# replaced by the versions of the same names.
KEPT_VERSIONS = """import numpy as np

def policy_v0(obs):
    return 0.5 * obs[2]

def policy_v1(obs):
    return 0.7 * obs[2]

def policy(obs):
    return 0.5 * policy_v0(obs) + 0.5 * policy_v1(obs)
"""


def test_helpers_named_like_versions_are_shown_under_names_of_their_own():
    first = "def policy(obs):\n    return -obs[1]"
    prompt = build_prompt("Task.", Selection(0, [stored(first, 1.0), stored(KEPT_VERSIONS, 2.0)]))
    assert "def policy_v0_v1(obs):" in prompt.shown_code and "def policy_v1_v1(obs):" in prompt.shown_code
    namespace: dict = {}
    exec(prompt.shown_code, namespace)  # every version computes what its program computes
    obs = np.array([0.6, 0.8, 2.0])
    assert namespace["policy_v0"](obs) == -0.8
    assert namespace["policy_v1"](obs) == pytest.approx(0.5 * 1.0 + 0.5 * 1.4)  # before: infinite recursion


def reversed_chain(helpers: int, gain: float) -> str:
    """`policy` calls h0, each helper the one defined after it; only the last holds `gain`."""
    lines = [f"def h{i}(obs):\n    return h{i + 1}(obs) + obs[{i % 3}]" for i in range(helpers - 1)]
    lines += [f"def h{helpers - 1}(obs):\n    return {gain} * obs[0]", "def policy(obs):\n    return -h0(obs)"]
    return "\n\n".join(lines)


def test_a_change_deep_in_a_chain_of_helpers_renames_every_helper_that_depends_on_it():
    """Only the last helper of the second program differs from the first's; every helper naming
    it, directly or through others, computes something else too and is renamed (found by
    following who names whom: looking at every helper until nothing changed was quadratic,
    20.8 s for 400 helpers; benchmarks/prompt_helpers.py)."""
    prompt = build_prompt("Task.", Selection(0, [stored(reversed_chain(40, 1.0), 1.0), stored(reversed_chain(40, 2.0), 2.0)]))
    assert all(f"def h{i}_v1(obs):" in prompt.shown_code for i in range(40))
    namespace: dict = {}
    exec(prompt.shown_code, namespace)
    obs = np.array([1.0, 0.5, 0.25])
    chain = sum(obs[i % 3] for i in range(39))
    assert namespace["policy_v0"](obs) == pytest.approx(-(chain + 1.0)) and namespace["policy_v1"](obs) == pytest.approx(-(chain + 2.0))


def test_other_function_name():
    code = "def controller(x):\n    return controller(x)"
    prompt = build_prompt("Task.", Selection(0, [stored(code, 0.0)]), function_name="controller")
    assert "def controller_v0(x):\n    return controller_v0(x)\n" in prompt.text
    assert prompt.text.endswith('def controller_v1(x):\n    """Improved version of controller_v0."""\n')
    assert "`controller(x)`" in prompt.messages[0]["content"]


@pytest.mark.parametrize("score", [float("nan"), float("-inf"), float("inf")])
def test_a_failed_program_is_never_shown(score):
    with pytest.raises(AssertionError, match="failed programs"):
        build_prompt("Task.", Selection(0, [LOW, stored(HIGH.code, score)]))


def test_programs_must_come_in_ascending_score():
    with pytest.raises(AssertionError, match="ascending"):
        build_prompt("Task.", Selection(0, [HIGH, LOW]))


def test_a_program_without_the_function_is_rejected():
    with pytest.raises(ValueError, match=r"defines no policy\(\)"):
        build_prompt("Task.", Selection(0, [stored("def act(obs):\n    return 0.0", 0.0)]))


@pytest.mark.parametrize("spec_name", ["pendulum.py", "cheetah.py", "ball_in_cup.py", "a1.py", "quadruped.py"])
def test_the_task_description_with_observation_layout_and_action_bounds_reaches_both_forms(spec_name):
    spec = load_spec(spec_name)
    program = parametrize(spec.starter_code)
    starter = StoredProgram(program.key, instantiate(program.skeleton, program.values), 0.0, 0, -1)
    prompt = build_prompt(spec.description, Selection(0, [starter]))
    assert "Observation (size" in spec.description and "Action" in spec.description
    assert spec.description in prompt.text and spec.description in prompt.messages[1]["content"]


def test_completion_stop_sequences_end_the_function_at_the_next_top_level_statement():
    from colmo.prompt import COMPLETION_STOP

    body = "    return -obs[0]\n\n\ndef policy_v2(obs):\n    return 0.0\n"
    cut = min(body.index(stop) for stop in COMPLETION_STOP if stop in body)
    assert body[:cut] == "    return -obs[0]\n\n"
    assert len(COMPLETION_STOP) <= 4  # OpenAI's completions endpoint takes at most four


def test_only_a_run_that_tunes_constants_says_so_in_both_forms():
    """With GFO the model is told that constants are tuned and the structure is what to change;
    with gfo=none (programs run as written) neither form says anything of the kind."""
    plain = build_prompt(DESCRIPTION, Selection(2, [LOW, HIGH]), constants_tuned=False)
    tuned = build_prompt(DESCRIPTION, Selection(2, [LOW, HIGH]), constants_tuned=True)
    assert plain.text == EXPECTED
    tuning = "The numeric constants of policy_v2 are tuned automatically afterwards: change its structure, not its numbers.\n"
    assert tuned.text == EXPECTED.replace("above.\n", f"above.\n{tuning}", 1)
    (plain_system, plain_user), (tuned_system, tuned_user) = ([m["content"] for m in p.messages] for p in (plain, tuned))
    assert "optimizer" in tuned_system and "structure" in tuned_system and "tuned" in tuned_system
    assert "optimizer" not in plain_system and "tuned" not in plain_system and "structure" not in plain_system
    assert tuning.strip() in tuned_user and "tuned" not in plain_user


def test_the_chat_form_names_the_imports_the_task_allows():
    """The system message names what the static check lets the task's policies import: numpy and
    math by default, and a spec's `ALLOWED_IMPORTS` besides."""
    default, wider = (
        build_prompt(DESCRIPTION, Selection(2, [LOW, HIGH]), **options).messages[0]["content"]
        for options in ({}, {"allowed_imports": ("numpy", "math", "scipy")})
    )
    assert "use only numpy and math." in default
    assert "use only numpy, math and scipy." in wider


def test_a_follow_up_keeps_the_selection_and_holds_only_the_last_answer():
    prompt = build_prompt(DESCRIPTION, Selection(2, [LOW, HIGH]), constants_tuned=True)
    first = prompt.followed_up("```python\ndef policy(obs):\n    return 1.0\n```", "Your `policy` is `policy_v0` with other numbers.", 1)
    second = first.followed_up("def policy(obs):\n    return theta", "Your answer cannot be used: `theta` is used but never defined.", 2)
    assert [m["role"] for m in second.messages] == ["system", "user", "assistant", "user"]
    assert second.messages[:2] == prompt.messages
    assert second.messages[2]["content"] == "def policy(obs):\n    return theta" and "theta" in second.messages[3]["content"]
    assert (second.retry, second.island, second.parent_keys, second.shown_code, second.text) == (2, 2, prompt.parent_keys, prompt.shown_code, prompt.text)
    assert [m["role"] for m in prompt.messages] == ["system", "user"]  # the prompt itself is unchanged


def test_versions_that_never_read_their_observation_are_named_in_both_forms():
    """Every task's starter returns a constant: a model shown only that answers with another
    constant more often than not, so the prompt says what such versions lack."""
    uses_a_helper = stored("def gain(x):\n    return 2.0 * x\n\ndef policy(obs):\n    return -gain(obs[0])", 5.0)
    blind = build_prompt(DESCRIPTION, Selection(0, [LOW, stored("def policy(obs):\n    x = 1.0\n    return x", 2.0)]))
    sentence = "policy_v0 and policy_v1 ignore their observation: policy_v2 should compute its action from the observation."
    assert sentence in blind.text and sentence in blind.messages[1]["content"]
    seeing = build_prompt(DESCRIPTION, Selection(0, [HIGH, uses_a_helper]))
    assert "ignore" not in seeing.text and "ignore" not in seeing.messages[1]["content"]


MUTATED = '''import math
import numpy as np

def policy(obs):
    """obs size is 3. return shape is ()."""
    unused = np.sin(obs[0]) * 4.0
    total = 0.0
    total += -2.0 * 1.5 * obs[2]
    if 3 > 2:
        gain = 2 * math.pi
    else:
        gain = 0.5
    return float(np.clip(total + gain * obs[1], -1.0, 1.0))
'''


def test_a_mutated_program_is_shown_without_what_mutation_left_in_it():
    """What a prompt shows is the program cleaned for reading (colmo.simplify.deadcode): the
    unused assignment, the branch on a constant condition and the accumulator's start go; its
    docstring (the observation and action sizes) and `2 * math.pi` stay as written. The prompt
    still names the stored program as its parent."""
    program = stored(MUTATED, 5.0)
    prompt = build_prompt("Task.", Selection(0, [program]))
    shown = prompt.shown_code
    assert '"""obs size is 3. return shape is ()."""' in shown
    assert "gain = 2 * math.pi" in shown and "total = -3.0 * obs[2]" in shown
    assert "unused" not in shown and "3 > 2" not in shown and "0.5" not in shown
    assert prompt.programs == [MUTATED] and prompt.parent_keys == [program.key]
    for showing in (prompt.text, prompt.messages[1]["content"]):
        assert shown in showing


def test_a_shown_program_leaves_out_the_branches_it_never_took():
    """Issue 38 part 2: the model improves on what a program does, not on a branch that never ran."""
    code = (
        "import numpy as np\n\ndef policy(obs):\n    if obs[0] > 1.5:\n        return 5.0 * obs[1]\n"
        "    return np.clip(-2.0 * obs[2], -1.0, 1.0)"
    )
    counted = StoredProgram("k-counted", code, 3.0, 2, 7, coverage=((1000, 0, 0), (1000, 120, 90)))
    prompt = build_prompt(DESCRIPTION, Selection(2, [LOW, counted]))
    shown = prompt.shown_code
    assert "obs[0] > 1.5" not in shown and "5.0 * obs[1]" not in shown and "np.clip(-2.0 * obs[2], -1.0, 1.0)" in shown
    assert prompt.programs[-1] == code  # the program as stored and scored
    uncounted = build_prompt(DESCRIPTION, Selection(2, [LOW, dataclasses.replace(counted, coverage=None)]))
    assert "obs[0] > 1.5" in uncounted.shown_code


def test_the_prompt_states_a_configured_episode_length_beside_the_described_one():
    spec = load_spec("pendulum.py")
    assert "episodes of 1000 steps" in spec.description
    assert spec.prompt_text_for({}) == spec.prompt_text_for({"horizon": 1000}) == spec.prompt_text
    assert spec.prompt_text_for({"horizon": 150, "angle_bound": 0.5}) == (
        spec.prompt_text + "\n\nEpisodes in this search last 150 control steps (3 s); the task's default is 1000."
    )


def test_an_environment_without_a_default_length_is_told_only_the_configured_one(tmp_path):
    (tmp_path / "given_length.py").write_text(
        '"""A pendulum whose episodes last as long as the task says."""\n\n'
        "from colmo.environments.pendulum import PendulumSwingup\n\n\n"
        "def make_environment(horizon):\n    return PendulumSwingup(horizon=horizon)\n\n\n"
        "def policy(obs):\n    return 0.0\n"
    )
    spec = load_spec(str(tmp_path / "given_length.py"))
    assert spec.prompt_text_for({"horizon": 50}) == spec.prompt_text + "\n\nEpisodes in this search last 50 control steps (1 s)."
