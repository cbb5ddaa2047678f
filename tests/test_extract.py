import ast
import math
import textwrap
from pathlib import Path

import pytest

from colmo.errors import ConfigError
from colmo.extract import ExtractionError, extract_policy
from colmo.intake import Unusable, read_policy_file, read_program
from colmo.program import parametrize


def answer(text: str) -> str:
    return textwrap.dedent(text).lstrip("\n")


# (id, model answer, the extracted module exactly as returned)
GOOD = [
    (
        "bare_code",
        answer("""
            import numpy as np

            def policy(obs):
                # proportional control
                return np.clip(-1.5 * obs[0], -1.0, 1.0)
        """),
        "import numpy as np\n\ndef policy(obs):\n    return np.clip(-1.5 * obs[0], -1.0, 1.0)",
    ),
    (
        "chatty_python_fence",
        answer("""
            Sure! Looking at the previous attempts, the controller lacks damping. Here is an improved version:

            ```python
            import numpy as np

            def policy_v2(obs):
                \"\"\"Improved version of policy_v1.\"\"\"
                angle = np.arctan2(obs[1], obs[0])
                return np.clip(-8.0 * angle - 1.2 * obs[2], -1.0, 1.0)
            ```

            The new term `-1.2 * obs[2]` adds damping, which should reduce overshoot. Let me know if you want me to tune it further!
        """),
        'import numpy as np\n\ndef policy(obs):\n    """Improved version of policy_v1."""\n'
        "    angle = np.arctan2(obs[1], obs[0])\n    return np.clip(-8.0 * angle - 1.2 * obs[2], -1.0, 1.0)",
    ),
    (
        "py_fence_without_import",
        answer("""
            ```py
            def policy(obs):
                return np.tanh(2.0 * obs[0]) + math.pi * obs[1]
            ```
        """),
        "import numpy as np\nimport math\n\ndef policy(obs):\n    return np.tanh(2.0 * obs[0]) + math.pi * obs[1]",
    ),
    (
        "fence_without_language",
        answer("""
            Here you go:
            ```
            def policy(obs):
                action = np.zeros(6)
                action[0] = -12.2 * obs[3]
                return action
            ```
        """),
        "import numpy as np\n\ndef policy(obs):\n    action = np.zeros(6)\n    action[0] = -12.2 * obs[3]\n    return action",
    ),
    (
        "several_versions_in_one_block",
        answer("""
            ```python
            import numpy as np

            def policy_v0(obs):
                return np.random.uniform()

            def policy_v1(obs):
                return 0.0

            def policy_v2(obs):
                return 0.7 * obs[0]
            ```
        """),
        "def policy(obs):\n    return 0.7 * obs[0]",
    ),
    (
        "newest_block_wins_and_usage_example_is_dropped",
        answer("""
            First attempt:
            ```python
            def policy_v2(obs):
                return 0.5 * obs[0]
            ```
            A better one uses the velocity too:
            ```python
            def policy_v3(obs):
                return 0.5 * obs[0] - 0.1 * obs[1]
            ```
            You can call it like this:
            ```python
            obs = env.reset()
            print(policy_v3(obs))
            ```
        """),
        "def policy(obs):\n    return 0.5 * obs[0] - 0.1 * obs[1]",
    ),
    (
        "last_definition_is_newest_not_highest_number",
        answer("""
            def policy_v3(obs):
                return 3.0 * obs[0]

            def policy_v2(obs):
                return 2.0 * obs[0]
        """),
        "def policy(obs):\n    return 2.0 * obs[0]",
    ),
    (
        "plain_name_after_versions",
        answer("""
            def policy_v1(obs):
                return obs[0]

            def policy(obs):
                return -obs[0]
        """),
        "def policy(obs):\n    return -obs[0]",
    ),
    (
        "self_reference_is_renamed",
        answer("""
            def policy_v2(obs, depth=0):
                if depth > 1:
                    return 0.0
                return obs[0] + 0.5 * policy_v2(obs, depth + 1)
        """),
        "def policy(obs, depth=0):\n    if depth > 1:\n        return 0.0\n    return obs[0] + 0.5 * policy(obs, depth + 1)",
    ),
    (
        "older_version_kept_when_called",
        answer("""
            def policy_v1(obs):
                return -2.0 * obs[0]

            def policy_v2(obs):
                return 1.1 * policy_v1(obs)
        """),
        "def policy_v1(obs):\n    return -2.0 * obs[0]\n\ndef policy(obs):\n    return 1.1 * policy_v1(obs)",
    ),
    (
        "helpers_constants_and_test_code",
        answer("""
            Below, a helper clips the action and a constant holds the gains.

            ```python
            import numpy as np
            import math

            GAINS = np.array([1.5, -0.3])
            UNUSED = 42

            def saturate(x, limit=1.0):
                return np.clip(x, -limit, limit)

            def unused_helper(x):
                return math.sqrt(x)

            def policy(obs):
                return saturate(GAINS @ obs[:2])

            obs = np.zeros(8)
            print(policy(obs))

            if __name__ == "__main__":
                for _ in range(3):
                    print(policy(np.random.randn(8)))
            ```
        """),
        "import numpy as np\nGAINS = np.array([1.5, -0.3])\n\ndef saturate(x, limit=1.0):\n    return np.clip(x, -limit, limit)\n\n"
        "def policy(obs):\n    return saturate(GAINS @ obs[:2])",
    ),
    (
        "helper_redefined_later_wins",
        answer("""
            ```python
            def gain():
                return 1.0
            ```
            Actually, a larger gain works better:
            ```python
            def gain():
                return 3.0

            def policy(obs):
                return gain() * obs[0]
            ```
        """),
        "def gain():\n    return 3.0\n\ndef policy(obs):\n    return gain() * obs[0]",
    ),
    (
        "imports_in_separate_block",
        answer("""
            You will need these imports:
            ```python
            import numpy as np
            from math import pi
            ```
            And the policy:
            ```python
            def policy(obs):
                return np.sin(pi * obs[0])
            ```
        """),
        "import numpy as np\nfrom math import pi\n\ndef policy(obs):\n    return np.sin(pi * obs[0])",
    ),
    (
        "import_inside_function",
        answer("""
            def policy(obs):
                import math
                return math.tanh(3.0 * obs[0])
        """),
        "def policy(obs):\n    import math\n    return math.tanh(3.0 * obs[0])",
    ),
    (
        "uniform_indent_as_in_a_class",
        "```python\n    def policy(obs):\n        if obs[0] > 0.2:\n            return 1.0\n        return -1.0\n```",
        "def policy(obs):\n    if obs[0] > 0.2:\n        return 1.0\n    return -1.0",
    ),
    (
        "indented_code_in_prose",
        "The policy is:\n\n    def policy(obs):\n        return 0.3 * obs[2]\n\nIt is a plain P controller.",
        "def policy(obs):\n    return 0.3 * obs[2]",
    ),
    (
        "truncated_mid_line",
        answer("""
            ```python
            import numpy as np

            def policy(obs):
                ball = obs[:3]
                cup = obs[3:]
                action = np.zeros(2)
                action[0] = 4.2 * (cup[0] - ball[0])
                action[1] = 1.1 * (cup[2] - ball[2]) + 0.5 * (cup[1
        """).rstrip("\n"),
        "import numpy as np\n\ndef policy(obs):\n    ball = obs[:3]\n    cup = obs[3:]\n    action = np.zeros(2)\n    action[0] = 4.2 * (cup[0] - ball[0])",
    ),
    (
        # A cut that still parses is kept: `0.` reads as 0.0, a constant the optimizer tunes anyway.
        "truncated_inside_a_number",
        "```python\ndef policy(obs):\n    action = 1.1 * obs[0]\n    return action + 0.",
        "def policy(obs):\n    action = 1.1 * obs[0]\n    return action + 0.0",
    ),
    (
        "truncated_mid_block",
        answer("""
            ```python
            def policy(obs):
                torque = -5.0 * obs[1]
                if abs(obs[2]) > 3.0:
                    torque = np.array([
                        1.0,
                        -1.
        """).rstrip("\n"),
        "def policy(obs):\n    torque = -5.0 * obs[1]",  # np is no longer used: no import
    ),
    (
        "truncated_new_version_falls_back",
        answer("""
            ```python
            def policy_v1(obs):
                return 0.9 * obs[0]

            def policy_v2(obs):
                \"\"\"Improved version of policy_v1.\"\"\"
                gain = 1.2 *
        """).rstrip("\n"),
        "def policy(obs):\n    return 0.9 * obs[0]",
    ),
]


@pytest.mark.parametrize("text, expected", [case[1:] for case in GOOD], ids=[case[0] for case in GOOD])
def test_extracts_policy(text, expected):
    extracted = extract_policy(text)
    assert extracted == expected
    parametrize(extracted)  # what comes out is always a program the optimizer can use


# (id, model answer, error message)
BAD = [
    ("refusal", "I'm sorry, but I can't write a control policy without knowing the system dynamics.", "no function named 'policy'"),
    ("empty", "", "no function named 'policy'"),
    ("garbage", "}}{{ ))) ## ``` @@ 0x;; def ( :\n\t\t=>", "no function named 'policy'"),
    ("other_name_only", "```python\ndef controller(obs):\n    return 0.5 * obs[0]\n```", "no function named 'policy'"),
    ("pass_body", "```python\ndef policy(obs):\n    pass\n```", "empty policy body"),
    ("docstring_body", 'def policy_v2(obs):\n    """Improved version of policy_v1."""\n', "empty policy body"),
    ("ellipsis_body", "Fill in the body:\n\ndef policy(obs):\n    ...\n", "empty policy body"),
    ("unparseable_definition", "```python\ndef policy(obs) return obs[0] * 2\n```",
     "found 'def policy' but no complete top-level definition of it: syntax error at line 2: expected ':'"),
    ("truncated_in_signature", "```python\nimport numpy as np\n\ndef policy(obs,",
     "found 'def policy' but no complete top-level definition of it: syntax error at line 4: '(' was never closed"),
    ("truncated_in_docstring", '```python\ndef policy(obs):\n    """Improved version of',
     "found 'def policy' but no complete top-level definition of it: syntax error at line 3: unterminated triple-quoted string literal (detected at line 3)"),
    ("method_of_a_class", "class Controller:\n    def policy(self, obs):\n        return 1.0\n", "found 'def policy' but no complete top-level definition of it"),
]


@pytest.mark.parametrize("text, message", [case[1:] for case in BAD], ids=[case[0] for case in BAD])
def test_rejects_answer(text, message):
    with pytest.raises(ExtractionError) as error:
        extract_policy(text)
    assert str(error.value) == message


def test_function_name():
    text = "def controller_v4(obs):\n    return 2.0 * obs[0]\n\ndef policy(obs):\n    return 0.0"
    assert extract_policy(text, function_name="controller") == "def controller(obs):\n    return 2.0 * obs[0]"


def test_extraction_error_is_a_value_error():
    assert issubclass(ExtractionError, ValueError)


def test_deeply_nested_answer_is_an_extraction_error_not_a_crash():
    with pytest.raises(ExtractionError, match="nested too deeply"):
        extract_policy("def policy(obs):\n    return " + "-" * 100000 + "1\n")


# ------------------------------------------------------------- completions of the prompt text

def completion_prompt() -> str:
    """The prompt text a completion model continues (`prompt_format=completion`): two
    versions, a helper, and the header of policy_v2."""
    from colmo.database import Selection, StoredProgram
    from colmo.prompt import build_prompt

    helper = "import numpy as np\n\ndef angle(obs):\n    return np.arctan2(obs[1], obs[0])\n\ndef policy(obs):\n    return -2.0 * angle(obs)"
    programs = [StoredProgram("a", "def policy(obs):\n    return 0.0", 0.0, 0, 0), StoredProgram("b", helper, 1.0, 0, 1)]
    return build_prompt("Swing the pole up.", Selection(0, programs)).text


BODY = "    x = angle(obs)\n    return np.clip(-3.0 * x - 0.5 * obs[2], -1.0, 1.0)\n"


def as_chat_answer(prefix: str, body: str) -> str:
    """The same function written out whole, as a chat model answers."""
    header = prefix[prefix.rindex("def policy_v2") :]
    return f"```python\nimport numpy as np\n\ndef angle(obs):\n    return np.arctan2(obs[1], obs[0])\n\n{header}{body}```"


@pytest.mark.parametrize("completion", [
    BODY,
    BODY + "\n\n",
    BODY + '\n\ndef policy_v3(obs):\n    """Improved version of policy_v2."""\n    x = np.arctan2(obs[1],',  # cut by max_tokens
    BODY + "\n\ndef policy_v3(obs",
    BODY + "\n\nThis policy damps the swing.",
])
def test_a_completion_body_extracts_to_the_same_program_as_the_whole_function(completion):
    prefix = completion_prompt()
    assert prefix.endswith('def policy_v2(obs):\n    """Improved version of policy_v1."""\n')
    expected = extract_policy(as_chat_answer(prefix, BODY))
    assert extract_policy(completion, prefix=prefix) == expected
    assert expected == (
        "import numpy as np\n\ndef angle(obs):\n    return np.arctan2(obs[1], obs[0])\n\n"
        'def policy(obs):\n    """Improved version of policy_v1."""\n    x = angle(obs)\n'
        "    return np.clip(-3.0 * x - 0.5 * obs[2], -1.0, 1.0)"
    )


def test_a_completion_with_its_own_docstring_and_a_truncated_last_line():
    prefix = completion_prompt()
    completion = '    """Pumps energy, then balances."""\n    x = angle(obs)\n    return -3.0 * x\n    y = np.clip(x,'
    extracted = extract_policy(completion, prefix=prefix)
    assert extracted.endswith('"""Improved version of policy_v1."""\n    \'Pumps energy, then balances.\'\n    x = angle(obs)\n    return -3.0 * x')


def test_a_newer_version_the_completion_wrote_after_its_body_wins():
    completion = BODY + '\n\ndef policy_v3(obs):\n    """Improved version of policy_v2."""\n    return 0.5 * policy_v2(obs)\n'
    extracted = extract_policy(completion, prefix=completion_prompt())
    assert "def policy(obs):" in extracted and "return 0.5 * policy_v2(obs)" in extracted
    assert "def policy_v2(obs):" in extracted  # the version it calls comes along


@pytest.mark.parametrize("completion", ["", "\n", "    x = (obs[0] +* 2)\n    return x\n", "I cannot help with that."])
def test_a_completion_without_a_usable_body_never_falls_back_to_a_prompt_version(completion):
    with pytest.raises(ExtractionError, match="the completion holds no complete body of 'policy'"):
        extract_policy(completion, prefix=completion_prompt())


def shown_code() -> str:
    """The code the prompt of `completion_prompt` shows (a chat answer's context)."""
    from colmo.database import Selection, StoredProgram
    from colmo.prompt import build_prompt

    helper = "import numpy as np\n\ndef angle(obs):\n    return np.arctan2(obs[1], obs[0])\n\ndef policy(obs):\n    return -2.0 * angle(obs)"
    programs = [StoredProgram("a", "def policy(obs):\n    return 0.0", 0.0, 0, 0), StoredProgram("b", helper, 1.0, 0, 1)]
    return build_prompt("Swing the pole up.", Selection(0, programs)).shown_code


def test_a_chat_answer_may_call_a_version_its_prompt_showed():
    # The 1.5B model's chat answers often build on a shown version without copying it
    # (`policy_v0(obs) + ...`): read without the prompt's code they failed with a NameError.
    answer = "```python\ndef policy(obs):\n    return 0.5 * policy_v1(obs) - 0.1 * obs[2]\n```"
    extracted = extract_policy(answer, shown=shown_code())
    namespace: dict = {}
    exec(extracted, namespace)  # the program stands alone: the version and its helper came along
    assert namespace["policy"]([0.0, 1.0, 2.0]) == pytest.approx(0.5 * -2.0 * (math.pi / 2) - 0.2)
    assert "def policy_v1(obs):" in extracted and "def angle(obs):" in extracted
    assert "def policy_v0" not in extracted  # what the answer does not use stays out
    assert extract_policy(answer) == "def policy(obs):\n    return 0.5 * policy_v1(obs) - 0.1 * obs[2]"  # no prompt, no context


def test_a_chat_answers_own_definitions_win_over_the_shown_ones():
    answer = "```python\ndef angle(obs):\n    return obs[1]\n\ndef policy(obs):\n    return -angle(obs)\n```"
    extracted = extract_policy(answer, shown=shown_code())
    assert extracted == "def angle(obs):\n    return obs[1]\n\ndef policy(obs):\n    return -angle(obs)"


@pytest.mark.parametrize("answer", ["I would keep policy_v1.", "```python\nx = policy_v1\n```"])
def test_the_shown_code_is_never_the_chosen_policy(answer):
    with pytest.raises(ExtractionError, match="no function named 'policy'"):
        extract_policy(answer, shown=shown_code())


# ------------------------------------------------------------------------- math module names

def test_math_names_used_unbound_are_imported_from_math():
    text = "def policy(obs):\n    return sqrt(abs(obs[0])) * pi - exp(-obs[2])"
    assert extract_policy(text) == "from math import exp, pi, sqrt\n\ndef policy(obs):\n    return sqrt(abs(obs[0])) * pi - exp(-obs[2])"


def test_names_the_program_binds_itself_are_not_taken_from_math():
    text = "def policy(obs, e=1.0):\n    pi = 3.0\n    for tau in range(2):\n        pi += tau\n    return pi * e * obs[0]"
    assert extract_policy(text).startswith("def policy(obs, e=1.0):")


# ---------------------------------------------- answers Qwen2.5-Coder-1.5B-Instruct really wrote

REAL_ANSWERS = [
    # It copies the task description into a module docstring, then writes `policy`.
    answer('''
        ```python
        """Improved pendulum swing-up policy.

        Observation (size 3): [cos(theta), sin(theta), angular velocity], where theta is the pole's
        angle from upright (theta = 0 is upright). Action: one torque in [-1, 1] (values outside are
        clipped).

        On every iteration, improve policy_v0 over the policy_vX methods from previous iterations.
        """

        import numpy as np


        def policy(obs):
            # Define deadzone parameters
            deadzone = 0.1
            theta, _, omega = obs
            if np.abs(theta) < deadzone or abs(omega) < deadzone:
                return 1.0 - deadzone / (abs(omega) + np.sign(omega))
            return np.clip(4 * np.sin(theta) - omega, -1, 1)
        ```'''),
    # It uses `sqrt` without importing it (the sandbox once failed it with a NameError).
    answer('''
        ```python
        def policy(obs):
            """Final version of policy."""
            theta = obs[0]
            if abs(theta) > 1.57:  # Check if the pole is in a dangerous position
                return -1.0
            action = sqrt(8.32 * abs(theta) / (2.46 + sqrt(2.83)))
            return action
        ```'''),
    # It repeats a prompt version, then writes its own as `policy`, and ends with a stub.
    answer('''
        ```python
        import numpy as np
        from math import pi, sqrt


        def policy_v0(obs):
            theta, sin_theta, angular_velocity = obs
            return (np.abs(theta) < 1.039) * 0.5939


        def policy(obs):
            """Final improved version of policy."""
            theta, sin_theta, angular_velocity = obs
            return -sqrt(20.28 * abs(theta) / (1.716 + sqrt(2.46)))

        def policy_vX(obs):
            # Your previous policy_vX function goes here
            pass
        ```'''),
]


def test_answers_a_small_model_really_wrote():
    copied, sqrt_unbound, several = (extract_policy(text) for text in REAL_ANSWERS)
    assert copied.startswith("import numpy as np\n\ndef policy(obs):\n    deadzone = 0.1") and "Observation" not in copied
    assert sqrt_unbound.startswith("from math import sqrt\n\ndef policy(obs):")
    # `policy_vX` is no version name: the stub after `policy` is dropped with the other unused code.
    assert several == "from math import pi, sqrt\n\ndef policy(obs):\n    \"\"\"Final improved version of policy.\"\"\"\n    theta, sin_theta, angular_velocity = obs\n    return -sqrt(20.28 * abs(theta) / (1.716 + sqrt(2.46)))"


# A model stuck repeating a line, after a good policy or alone (issue 24 part 5): the policy is
# still read, and the parser reads each character about once, not once per line (the old cut
# re-parsed the rest of the answer from every line: minutes for 600 `@x` lines).
POLICY = (Path(__file__).parent.parent / "examples" / "paper_quadruped.py").read_text()
REPEATED = [
    ("decorators_after_a_policy", POLICY + "\n" + "@x\n" * 600, "ok"),
    ("definitions_after_a_policy", POLICY + "\n" + "def f():\n" * 10_000, "ok"),
    ("definitions_alone", "def f():\n" * 11_000, "no function named 'policy'"),
]


@pytest.mark.parametrize("text, outcome", [r[1:] for r in REPEATED], ids=[r[0] for r in REPEATED])
def test_repeated_lines_are_read_in_linear_time(monkeypatch, text, outcome):
    parsed = []
    real_parse = ast.parse

    def counting_parse(source, *args, **kwargs):
        parsed.append(len(source))
        return real_parse(source, *args, **kwargs)

    monkeypatch.setattr(ast, "parse", counting_parse)
    if outcome == "ok":
        assert "def policy(obs)" in extract_policy(text)
    else:
        with pytest.raises(ExtractionError, match=outcome):
            extract_policy(text)
    assert sum(parsed) < 10 * len(text)


def test_an_answer_that_would_cost_quadratic_parsing_is_refused():
    # Every line opens a bracket: each start reads to the end before failing.
    with pytest.raises(ExtractionError, match="too irregular to read"):
        extract_policy("x = (\n" * 16_000)


def test_annotations_are_stripped():
    text = "```python\nimport numpy as np\nGAIN: float = 2.0\n\ndef policy_v2(obs: np.ndarray, *rest: float) -> float:\n    k: float = GAIN\n    n: int\n    return float(-k * obs[0])\n```"
    assert extract_policy(text) == "import numpy as np\nGAIN = 2.0\n\ndef policy(obs, *rest):\n    k = GAIN\n    return float(-k * obs[0])"


# The one-file tools (colmo-optimize, -evaluate, -simplify, -render) read policies with
# `read_policy_file` (issue 20 part 6).
@pytest.mark.parametrize("code, message", [
    ("import numpy as np\n\ndef policy(obs):\n    x = obs[0]\n    return -2.0 * x)\n", r"syntax error at line 5: unmatched '\)'"),
    ("import numpy as np\n\ndef policy(obs:\n    return -2.0 * obs[0]\n", r"syntax error at line 3: '\(' was never closed"),
])
def test_a_policy_file_with_a_syntax_error_says_where(tmp_path, code, message):
    file = tmp_path / "policy.py"
    file.write_text(code)
    with pytest.raises(ConfigError, match=message):
        read_policy_file(str(file), ["numpy", "math"])


def test_an_annotated_policy_file_is_read(tmp_path):
    file = tmp_path / "policy.py"
    file.write_text("import numpy as np\n\ndef policy(obs: np.ndarray) -> float:\n    return float(-2.0 * obs[0])\n")
    assert read_policy_file(str(file), ["numpy", "math"]).values == (-2.0,)


@pytest.mark.parametrize("indent", ["    ", ""])
def test_a_raw_completion_body_in_a_file_is_read(tmp_path, indent):
    file = tmp_path / "completion.txt"
    file.write_text(textwrap.indent('"""Damped proportional control."""\nangle = np.arctan2(obs[1], obs[0])\nreturn float(np.clip(-8.0 * angle - 1.2 * obs[2], -1.0, 1.0))\n', indent))
    program = read_policy_file(str(file), ["numpy", "math"])
    assert program.values == (-8.0, 1.2, -1.0, 1.0) and "def policy(obs):" in program.skeleton


def test_a_raw_completion_body_with_an_unfinished_next_version_reads_as_the_search_reads_it(tmp_path):
    # What a completion model writes when no stop sequence cuts it: the body, then the start of
    # the next version. The search reads it after its prompt; the one-file tools after the signature.
    body = '    """Damped."""\n    return float(-2.0 * obs[2])\n\n\ndef policy_v3(obs):\n    """Improved version of'
    file = tmp_path / "completion.txt"
    file.write_text(body)
    searched = read_program(body, ["numpy", "math"], prefix="import numpy as np\n\ndef policy_v2(obs):\n")
    assert read_policy_file(str(file), ["numpy", "math"]).values == searched.values == (-2.0,)


def test_a_policy_file_without_a_policy_function_says_so_and_names_what_it_defines(tmp_path):
    file = tmp_path / "controller.py"
    file.write_text("import numpy as np\n\ndef controller(obs):\n    return -obs[2]\n")
    with pytest.raises(ConfigError, match=r"no function named 'policy' \(it defines controller; a policy file's function is `def policy\(obs\)`\)"):
        read_policy_file(str(file), ["numpy", "math"])


@pytest.mark.parametrize("body, undefined", [
    ("    return -theta * 2.0", "`theta` is"),  # a shown version's variable, never defined here
    ("    if obs[0] > 0:\n        return omega\n    return theta", "`omega` and `theta` are"),
    ("    return policy_v0(obs)", "`policy_v0` is"),  # a completion-form answer of no prompt
])
def test_a_program_that_reads_a_name_nothing_defines_is_refused_before_it_runs(body, undefined):
    with pytest.raises(Unusable, match=f"{undefined} used but never defined"):
        read_program(f"import numpy as np\n\ndef policy(obs):\n{body}\n", ("numpy", "math"))


def test_builtins_constants_and_names_bound_anywhere_are_defined():
    code = textwrap.dedent("""
        import numpy as np
        GAIN = 2.0

        def helper(x):
            scale = abs(x) + sum([1.0, 2.0])
            return scale * GAIN

        def policy(obs):
            total = 0.0
            for value in obs:
                total += helper(value)
            return float(np.clip(total, -1, 1)) if isinstance(total, float) else 0.0
    """)
    assert read_program(code, ("numpy", "math")).skeleton.count("params[") >= 3


def hostile_shown(module_code: str) -> str:
    """The code a prompt shows when a stored program holds `module_code` beside a good policy."""
    from colmo.database import Selection, StoredProgram
    from colmo.prompt import build_prompt

    hostile = f"import math\nimport numpy as np\n{module_code}\n\ndef policy(obs):\n    return -2.0 * np.arctan2(obs[1], obs[0])"
    programs = [StoredProgram("a", "def policy(obs):\n    return 0.0", 0.0, 0, 0), StoredProgram("b", hostile, 500.0, 0, 1)]
    return build_prompt("Swing the pole up.", Selection(0, programs)).shown_code


@pytest.mark.parametrize("module_code", ["np = math", "import math as np", "np = None"])
def test_a_shown_program_cannot_rebind_a_name_of_the_answer(module_code):
    # A stored `np = math` scored (math.sin works on floats) and was kept in every later answer
    # whose prompt showed it: "module 'math' has no attribute 'arctan2'".
    shown = hostile_shown(module_code)
    assert module_code in shown
    for answer in ("```python\nimport numpy as np\n\ndef policy(obs):\n    return -np.arctan2(obs[1], obs[0])\n```",
                   "```python\ndef policy(obs):\n    return -np.arctan2(obs[1], obs[0])\n```"):  # np from the standard import
        extracted = extract_policy(answer, shown=shown)
        assert module_code not in extracted and "import numpy as np" in extracted
        namespace: dict = {}
        exec(extracted, namespace)
        assert namespace["policy"]([0.0, 1.0, 0.0]) == pytest.approx(-math.pi / 2)


@pytest.mark.parametrize("name", ["float", "abs", "min", "max", "round", "params"])
def test_a_shown_program_cannot_take_over_a_builtin_or_predefined_name(name):
    shown = hostile_shown(f"def {name}(*args):\n    return 0.05")
    answer = f"```python\ndef policy(obs):\n    return {name}(-0.5 * obs[2])\n```"
    assert f"def {name}(" not in extract_policy(answer, shown=shown)


def test_a_name_the_answer_binds_is_never_taken_from_the_shown_code():
    shown = hostile_shown("def sin(x):\n    return 0.0\n\ndef gain(obs):\n    return 99.0")
    answer = "```python\nfrom math import sin\ngain = 2.0\n\ndef policy(obs):\n    return -gain * sin(obs[1])\n```"
    extracted = extract_policy(answer, shown=shown)
    assert "def sin" not in extracted and "def gain" not in extracted and "return 99.0" not in extracted
    namespace: dict = {}
    exec(extracted, namespace)
    assert namespace["policy"]([0.0, math.pi / 2, 0.0]) == pytest.approx(-2.0)


def test_the_size_caps_refuse_a_program_with_more_nodes_or_constants():
    from colmo.sandbox.check import ForbiddenProgram

    code = "import numpy as np\n\ndef policy(obs):\n    return 1.5 * obs[0] - 0.5 * obs[1] + 0.25 * obs[2]\n"
    assert read_program(code, ("numpy",), max_constants=3, max_nodes=22).n_params == 3
    with pytest.raises(ForbiddenProgram, match=r"^too many constants: 3 tunable constants \(database.max_constants=2\)$"):
        read_program(code, ("numpy",), max_constants=2)
    with pytest.raises(ForbiddenProgram, match=r"^too large: 22 AST nodes \(database.max_nodes=21\)$"):
        read_program(code, ("numpy",), max_nodes=21)
