"""colmo.simplify: the static dead-code pass, the size measure, the deletion candidates, the
acceptance rule, the pendulum winner of docs/pendulum-10min shrunk for real, and the sandboxed
scoring and command line.

TRUSTED TEST CODE: some tests run programs in this process (`_run_policy`, `trusted_scoring`).
They only ever run the hand-written programs of this file, the repository's examples, and
programs derived from them by colmo.simplify; colmo itself scores candidates in sandboxed workers
(`simplify_program`, `python -m colmo.simplify`, tested at the end).
"""

from __future__ import annotations

import ast
import json
import math
import os
import re
import signal
from pathlib import Path

import numpy as np
import pytest

from colmo.astutil import node_count
from colmo.environments.pendulum import PendulumSwingup
from colmo.program import ProgramSize, instantiate, measure, parametrize
from colmo.rollout import episode_seeds, evaluate_policy
from colmo.simplify import (
    Candidate,
    ProgramFails,
    Scores,
    Scoring,
    SimplifyResult,
    Step,
    deletion_candidates,
    remove_dead_code,
    simplify,
)
from colmo.specs import load_spec

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"

# The no-GFO winner of docs/pendulum-10min/report.md (score 842.3 after 2684 samples).
PENDULUM_WINNER = """\
import numpy as np

def policy(obs):
    return ((-5.74 + 1.75 * np.tanh(obs[0])) * (obs[1] - (-0.143 * obs[0] + 0.757 * obs[1] * obs[1] - 0.283 * obs[1] * obs[0] - 0.203 * obs[0]) * obs[2]) - 0.407 * (0.461 * obs[0] + 0.212 * obs[2]) + 0.268 * np.arctan2(obs[2], obs[0]) if obs[1] > 0.552 else -5.74 * (obs[1] - np.tanh((-0.143 * obs[0] + 0.757 * obs[1] * obs[1] - 0.203 * obs[0]) * obs[2])) - 0.407 * np.sign(obs[1]) + 0.268 * np.arctan2(obs[2], obs[0])) + 1.02 * obs[1] if np.abs(obs[1]) > 0.217 else -5.74 * (obs[1] - np.tanh((-0.143 * obs[0] + 0.757 * obs[1] * obs[1] - 0.203 * obs[0]) * obs[2])) - 0.407 * np.sign(obs[1]) + 1.02 * obs[1]
"""


def _run_policy(code: str):
    """TRUSTED TEST CODE: the policy function of a program from this file, run in-process."""
    namespace: dict = {}
    exec(compile(code, "<trusted test program>", "exec"), namespace)
    return namespace["policy"]


def trusted_scoring(train: list[int], heldout: list[int], steps: int | None = None) -> Scoring:
    """TRUSTED TEST CODE: a Scoring that runs programs in this process on the pendulum."""
    env = PendulumSwingup()

    def score_batch(seeds):
        def scores(codes):
            results = []
            for code in codes:
                try:
                    policy = _run_policy(code)
                except Exception:
                    results.append(-math.inf)
                    continue
                results.append(evaluate_policy(env, policy, seeds, steps).score)
            return results

        return scores

    return Scoring(score_batch(train), score_batch(heldout))


def scoring(score_batch) -> Scoring:
    """A Scoring from a function giving the Scores of a batch of codes (constructed scores)."""
    return Scoring(lambda codes: [s.train for s in score_batch(codes)], lambda codes: [s.heldout for s in score_batch(codes)])


def count_nodes(code: str) -> int:
    return measure(code).nodes


def _same(code: str, expected: str) -> bool:
    return ast.dump(ast.parse(code)) == ast.dump(ast.parse(expected))


# --- the static pass ------------------------------------------------------------------------------


def test_dead_code_second_return_unused_assignment_and_literal_call_are_removed_exactly():
    code = '''
import numpy as np
import math
import os
import re
import signal

def helper(x):
    return x

def policy(obs):
    """Docstring."""
    unused = obs[0] * 2.0
    action = np.abs(4.4) * obs[1]
    return action
    return 0.0
'''
    assert remove_dead_code(code) == "def policy(obs):\n    action = 4.4 * obs[1]\n    return action"


@pytest.mark.parametrize(
    "code, expected",
    [
        pytest.param(
            "def policy(obs):\n    if obs[0] > 0:\n        return 1.0\n    else:\n        return -1.0\n    x = 3.0\n    return x",
            "def policy(obs):\n    if obs[0] > 0:\n        return 1.0\n    else:\n        return -1.0",
            id="after an if whose branches all return",
        ),
        pytest.param(
            "def policy(obs):\n    if 2 > 1:\n        a = obs[0]\n    else:\n        a = obs[1]\n    while False:\n        a = 0.0\n    return a",
            "def policy(obs):\n    a = obs[0]\n    return a",
            id="constant if and while",
        ),
        pytest.param(
            "def policy(obs):\n    return (obs[0] if 1.0 else obs[1]) + (True and obs[2] > 0.5) * 2.0",
            "def policy(obs):\n    return obs[0] + (obs[2] > 0.5) * 2.0",
            id="constant conditional expression and boolean",
        ),
        pytest.param(
            "import numpy as np\nimport math\ndef policy(obs):\n    return 2.0 * 3.0 * obs[0] + np.pi / 2.0 + -(-obs[1]) + math.sqrt(4.0) + obs[1 + 1] + np.sign(-3.0)",
            "def policy(obs):\n    return 6.0 * obs[0] + 1.5707963267948966 + obs[1] + 2.0 + obs[2] - 1.0",
            id="folding, integer index stays an integer",
        ),
        pytest.param(
            "def policy(obs):\n    return obs[0] - -18.15 * obs[5] * obs[1] + -0.5 + -2 * obs[2] - -0.25 - obs[1] * -3.0",
            "def policy(obs):\n    return obs[0] + 18.15 * obs[5] * obs[1] - 0.5 + -2 * obs[2] + 0.25 - obs[1] * -3.0",
            id="a negative float leading a term as the opposite operation (not an int: -2 * [x] is not -(2 * [x]))",
        ),
        pytest.param(
            "import numpy as np\ndef policy(obs):\n    return np.pi * obs[0] + 1.0 / 0.0 * obs[1] + np.log(0.0) + np.sqrt(-1.0) + 2.0 * obs[0] * 3.0",
            "import numpy as np\ndef policy(obs):\n    return np.pi * obs[0] + 1.0 / 0.0 * obs[1] + np.log(0.0) + np.sqrt(-1.0) + 2.0 * obs[0] * 3.0",
            id="nothing to fold: a lone pi, errors, warnings, non-literal operands",
        ),
        pytest.param(
            "import numpy as np\ndef policy(obs):\n    y = -(-obs)\n    noise = np.random.normal()\n    out = np.zeros(3, out=None)\n    return y",
            "import numpy as np\ndef policy(obs):\n    y = -(-obs)\n    noise = np.random.normal()\n    out = np.zeros(3, out=None)\n    return y",
            id="kept: a negated copy, a random draw, an out= call",
        ),
        pytest.param(
            "def policy(obs):\n    view = obs[:2]\n    view += 1.0\n    return obs",
            "def policy(obs):\n    view = obs[:2]\n    view += 1.0\n    return obs",
            id="kept: an augmented assignment into a view",
        ),
        pytest.param(
            "import numpy as np\ndef policy(obs):\n    scratch = np.zeros(3)\n    scratch[0] = obs[0]\n    scratch += 1.0\n    total = 0.0\n    total += obs[1]\n    return obs[2]",
            "def policy(obs):\n    return obs[2]",
            id="write-only fresh locals",
        ),
        pytest.param(
            "import numpy as np\nMEMORY = np.zeros(2)\ndef policy(obs):\n    MEMORY[0] = obs[0]\n    MEMORY[1] += 1.0\n    return obs[1]",
            "import numpy as np\nMEMORY = np.zeros(2)\ndef policy(obs):\n    MEMORY[0] = obs[0]\n    MEMORY[1] += 1.0\n    return obs[1]",
            id="kept: writes into a module-level array",
        ),
        pytest.param(
            "GAIN = 1.0\nGAIN = 2.0\nUNUSED = 5.0\ndef policy(obs):\n    return GAIN * obs[0]",
            "GAIN = 2.0\ndef policy(obs):\n    return GAIN * obs[0]",
            id="overwritten and unused module constants",
        ),
        pytest.param(
            "count = 0\ndef policy(obs):\n    global count\n    count += 1\n    k = 2.0\n    f = lambda x: k * x\n    return f(obs[0])",
            "count = 0\ndef policy(obs):\n    global count\n    count += 1\n    k = 2.0\n    f = lambda x: k * x\n    return f(obs[0])",
            id="kept: globals and names a lambda reads",
        ),
        pytest.param(
            "def policy(obs):\n    x = 1.0\n    del x\n    x = obs[0]\n    return x",
            "def policy(obs):\n    x = 1.0\n    del x\n    x = obs[0]\n    return x",
            id="kept: a name deleted later",
        ),
        pytest.param(
            "def policy(obs):\n    pass\n    'a string'\n    obs[0] + 1.0\n    if obs[1] > 0:\n        pass\n    return obs[0]",
            "def policy(obs):\n    return obs[0]",
            id="pass, bare strings, pure expressions, empty ifs",
        ),
        pytest.param(
            "def abs(x):\n    return x\ndef policy(obs):\n    return abs(-2.0) * obs[0]",
            "def abs(x):\n    return x\ndef policy(obs):\n    return abs(-2.0) * obs[0]",
            id="a rebound builtin is not folded",
        ),
        pytest.param(
            "import numpy as np\ndef policy(obs):\n    match obs[0]:\n        case np:\n            return np.abs(-4.4)",
            "import numpy as np\ndef policy(obs):\n    match obs[0]:\n        case np:\n            return np.abs(-4.4)",
            id="a name a match pattern captures is not the module",
        ),
    ],
)
def test_dead_code_cases(code, expected):
    cleaned = remove_dead_code(code)
    assert _same(cleaned, expected), cleaned


# Hand-written programs full of dead code in loops, branches, closures and module state.
TRICKY_PROGRAMS = [
    """
import numpy as np
def policy(obs):
    total = 0.0
    last = 0.0
    unused = 0.0
    for i in range(3):
        unused = obs[i] * 2.0
        if obs[i] > 0.5:
            last = obs[i]
            break
        if obs[i] < -0.5:
            continue
        total += obs[i]
    else:
        total -= 1.0
    return total + last
""",
    """
def policy(obs):
    prev = 0.0
    out = 0.0
    dead = 1.0
    i = 0
    while i < 3:
        out = out + prev
        prev = obs[i]
        dead = out * 2.0
        i += 1
    return out
""",
    """
import numpy as np
K = np.array([1.0, -2.0, 0.5])
K = K * 2.0
def helper(x):
    return np.tanh(x)
def unused_helper(x):
    return x * 3.0
def policy(obs):
    a = np.zeros(3)
    a[0] = helper(obs[0])
    a[1:] = obs[1:] * K[1:]
    b = a
    b[2] += 1.0
    c, d = obs[0], obs[1]
    return a.sum() + c
""",
    """
import math
import os
import re
import signal
def policy(obs):
    try:
        v = 1.0 / obs[0]
    except ZeroDivisionError:
        v = 0.0
    w = v
    vals = [o * 2.0 for o in obs]
    if vals[0] > 0.0:
        w = -w
    elif vals[1] > math.pi / 4.0:
        w = w * 2.0
    else:
        return sum(vals) + -(-w)
    return w + math.exp(0.5) * obs[2]
""",
    """
import numpy as np
def policy(obs):
    x = obs.copy()
    x *= 2.0
    y = np.clip(x, -1.0, 1.0)
    while True:
        if y[0] > 0.0:
            z = y[0]
            break
        z = -y[1]
        break
        z = 0.0
    spare = np.tanh(y)
    return z + x[2]
""",
]


@pytest.mark.parametrize("index", range(len(TRICKY_PROGRAMS)))
def test_dead_code_removal_computes_the_same_actions(index):
    code = TRICKY_PROGRAMS[index]
    cleaned = remove_dead_code(code)
    assert count_nodes(cleaned) < count_nodes(code)
    original, simplified = _run_policy(code), _run_policy(cleaned)
    for obs in np.random.default_rng(index).uniform(-1.5, 1.5, size=(40, 3)):
        before, after = original(obs.copy()), simplified(obs.copy())
        assert np.array_equal(before, after), (obs, before, after, cleaned)


@pytest.mark.parametrize(
    "task, example",
    [("pendulum", "paper_pendulum"), ("pendulum", "pendulum_mistuned"), ("cheetah", "paper_cheetah"),
     ("ball_in_cup", "paper_ball_in_cup"), ("quadruped", "paper_quadruped"), ("a1", "paper_a1")],
)
def test_dead_code_removal_keeps_the_examples_returns(task, example):
    code = (EXAMPLES / f"{example}.py").read_text()
    env = load_spec(f"{task}.py").make_environment()
    seeds = episode_seeds(0, 2)
    before = evaluate_policy(env, _run_policy(code), seeds, steps=200)
    after = evaluate_policy(env, _run_policy(remove_dead_code(code)), seeds, steps=200)
    assert before.failure is None and before == after


def test_dead_code_removal_is_idempotent():
    for code in [PENDULUM_WINNER, *TRICKY_PROGRAMS]:
        once = remove_dead_code(code)
        assert remove_dead_code(once) == once


# --- size and candidates ----------------------------------------------------------------------------


def test_size_counts_nodes_without_labels_and_signs():
    # Module, FunctionDef, arguments, arg, Return, BinOp, 3.2, Subscript, Name, 0
    assert count_nodes("def policy(obs):\n    return 3.2 * obs[0]") == 10
    assert count_nodes('def policy(obs):\n    """Doc."""\n    return -3.2 * obs[0]  # comment') == 10
    assert measure("import numpy as np\n\ndef policy(obs):\n    x = 2.0 * obs[1]\n    return np.tanh(x)") == ProgramSize(lines=4, nodes=18, params=1)
    assert measure(PENDULUM_WINNER) == ProgramSize(lines=3, nodes=208, params=25)
    # One count everywhere: the intake's node limit, the search's stored sizes and the simplifier's.
    assert node_count(ast.parse("x = -3.2 + +1")) == node_count(ast.parse("x = 3.2 + 1")) == 6  # Module, Assign, x, BinOp, 3.2, 1


def test_deletion_candidates():
    code = "import numpy as np\n\ndef policy(obs):\n    if obs[0] > 0.5:\n        a = np.clip(2.0 * obs[1] - 0.3 * obs[2], -1.0, 1.0)\n    else:\n        a = 0.1\n    return a"
    candidates = deletion_candidates(code)
    codes = {c.code for c in candidates}
    assert len(codes) == len(candidates), "duplicates are dropped"
    assert all(c.nodes == count_nodes(c.code) < count_nodes(code) for c in candidates)
    by_code = {ast.dump(ast.parse(c.code)): c.description for c in candidates}

    def described(expected: str) -> str:
        return by_code[ast.dump(ast.parse(expected))]

    assert described("def policy(obs):\n    a = 0.1\n    return a") == "kept only the else branch of `if obs[0] > 0.5` at line 4"
    assert described(  # numpy is no longer used, so its import went with the call
        "def policy(obs):\n    if obs[0] > 0.5:\n        a = 2.0 * obs[1] - 0.3 * obs[2]\n    else:\n        a = 0.1\n    return a"
    ) == "unwrapped `np.clip(2.0 * obs[1] - 0.3 * obs[2], -1.0, 1.0)` to `2.0 * obs[1] - 0.3 * obs[2]` at line 5"
    assert described(
        "import numpy as np\n\ndef policy(obs):\n    if obs[0] > 0.5:\n        a = np.clip(2.0 * obs[1], -1.0, 1.0)\n    else:\n        a = 0.1\n    return a"
    ) == "dropped the term `0.3 * obs[2]` at line 5"
    assert described(
        "import numpy as np\n\ndef policy(obs):\n    if obs[0] > 0.5:\n        a = np.clip(obs[1] - 0.3 * obs[2], -1.0, 1.0)\n    else:\n        a = 0.1\n    return a"
    ) == "dropped the factor `2.0` at line 5"
    # Dropping the first term of a difference keeps the sign of the second.
    assert "import numpy as np\n\ndef policy(obs):\n    if obs[0] > 0.5:\n        a = np.clip(-0.3 * obs[2], -1.0, 1.0)\n    else:\n        a = 0.1\n    return a" in codes
    assert "def policy(obs):\n    pass" not in codes  # a policy returning None always fails
    assert "def policy(obs):\n    return 0.0" in codes  # the returned value replaced by 0.0, the rest dead


def test_constant_factors_are_merged_by_a_measured_candidate_not_folded():
    code = "def policy(obs):\n    return 1.34 * (4.69 * obs[0])"
    assert remove_dead_code(code) == code  # 1.34 * 4.69 * x would round differently
    (merged,) = [c for c in deletion_candidates(code) if c.description.startswith("merged")]
    assert merged.code == "def policy(obs):\n    return 6.285 * obs[0]" and merged.nodes == count_nodes(code) - 2
    # Wherever the numbers stand among a product's factors (a joint term and its feature's gain).
    code = "import numpy as np\n\ndef policy(obs):\n    return obs[0] + 7.422 * np.eye(6)[3] * (1.545 * obs[6])"
    (merged,) = [c for c in deletion_candidates(code) if c.description.startswith("merged")]
    assert merged.code.endswith("return obs[0] + 11.47 * np.eye(6)[3] * obs[6]") and measure(merged.code).params == 1
    merged = {c.code for c in deletion_candidates("def policy(obs):\n    return 2.0 * obs[1] * 3.0 * (obs[2] * 0.5)") if c.description.startswith("merged")}
    assert merged == {"def policy(obs):\n    return 3.0 * obs[1] * obs[2]", "def policy(obs):\n    return 6.0 * obs[1] * (obs[2] * 0.5)"}


def test_a_constant_factor_is_merged_into_an_array_literal_by_a_measured_candidate():
    # The cheetah's seed-2 winner after simplification kept `0.3349 * (np.array([...]) * obs[12])`.
    code = "import numpy as np\n\ndef policy(obs):\n    return 0.3349 * (np.array([-0.2635, 3.418, 2]) * obs[12]) + obs[1]"
    assert remove_dead_code(code) == code
    (merged,) = [c for c in deletion_candidates(code) if c.description.startswith("merged")]
    assert merged.code.endswith("return np.array([-0.08825, 1.145, 0.6698]) * obs[12] + obs[1]")
    assert merged.nodes == count_nodes(code) - 2
    alone = "import numpy as np\n\ndef policy(obs):\n    return obs[0] * np.array([1.5, -2.0]) * 0.5"
    (merged,) = [c for c in deletion_candidates(alone) if c.description.startswith("merged")]
    assert merged.code.endswith("return obs[0] * np.array([0.75, -1.0])")
    for kept in ("np.array([1.5, obs[1]])", "np.array([1.5, -2.0], dtype=float)", "np.array([[1.5], [2.0]])", "np.zeros(2)"):
        code = f"import numpy as np\n\ndef policy(obs):\n    return 0.5 * ({kept} * obs[0])"
        assert not [c for c in deletion_candidates(code) if c.description.startswith("merged")], kept


def test_an_array_literal_keeps_one_entry_or_shares_one_value_by_measured_candidates():
    # The cheetah's by_yield seed-2 winner, simplified: 12 constants, 7 of them in the second gain
    # vector, whose entry 3 does nearly all the work; dropping the whole term loses ~170 points.
    code = "import numpy as np\n\ndef policy(obs):\n    return obs[0] + np.array([-0.068, 0.2022, 0.0, 7.422, 0.2798, -0.1]) * obs[6]"
    edits = {c.description: c.code for c in deletion_candidates(code) if "entry" in c.description or "shared" in c.description}
    array = "`np.array([-0.068, 0.2022, 0.0, 7.422, 0.2798, -0.1])`"
    assert edits[f"kept only entry 3, `7.422`, of {array} at line 4"].endswith("return obs[0] + 7.422 * np.eye(6)[3] * obs[6]")
    assert edits[f"shared one value, their mean 1.289, across the entries of {array} at line 4"].endswith(
        "return obs[0] + np.full(6, 1.289) * obs[6]"
    )
    assert not [d for d in edits if d.startswith("kept only entry 2,")]  # a 0 entry left alone is all zeros
    assert len(edits) == 6  # five entries kept one at a time, one mean
    # The array is never unwrapped to its list: `[...] * obs[6]` is an array only while obs[6] is a numpy number.
    assert not [c for c in deletion_candidates(code) if c.description.startswith("unwrapped `np.array")]
    # The size and index are structural: one constant left where there were six.
    for kept in edits.values():
        assert measure(kept).params == 1
        assert _run_policy(kept)(np.ones(7)).shape == (6,)
    # An entry that is an expression is kept whole; no mean where an entry is not a number.
    mixed = "import numpy as np\n\ndef policy(obs):\n    return np.array([0.5, -2.0 * obs[1], 1.5, 0.25, 3.0]) * obs[0]"
    edits = {c.description: c.code for c in deletion_candidates(mixed) if "entry" in c.description or "shared" in c.description}
    assert edits["kept only entry 1, `-2.0 * obs[1]`, of `np.array([0.5, -2.0 * obs[1], 1.5, 0.25, 3.0])` at line 4"].endswith(
        "return -2.0 * obs[1] * np.eye(5)[1] * obs[0]"
    )
    assert len(edits) == 5
    # Two entries: `c * np.eye(2)[i]` is no smaller than the array, so it is not a candidate.
    assert not [c for c in deletion_candidates("import numpy as np\n\ndef policy(obs):\n    return np.array([0.5, 2.0]) * obs[0]") if "entry" in c.description]


def _collected(code: str) -> list[Candidate]:
    return [c for c in deletion_candidates(code) if c.description.startswith("collected the like terms")]


def test_a_sums_like_terms_are_collected_and_its_numbers_added_by_a_measured_candidate():
    # The cheetah's by_yield seed-0 winner after simplification ended in this sum (17 constants).
    code = "def policy(obs):\n    action = 2.0 * obs[1]\n    action_b = obs[2]\n    return action + 1.663 * (0.3931 - action_b + 1.142 * action_b)"
    collected, written_in = _collected(code)
    assert collected.code.endswith("return action + 0.6537 + 0.2361 * action_b")  # 1.663 * 0.3931 and 1.663 * 0.142
    assert collected.description == "collected the like terms of `action + 1.663 * (0.3931 - action_b + 1.142 * action_b)` at line 4"
    assert written_in.code.endswith("return 2.0 * obs[1] + 0.6537 + 0.2361 * action_b")  # `action`, read once, written in
    for before, after in (
        ("-(0.5 * obs[0]) + 0.2 * obs[0] + 1", "-0.3 * obs[0] + 1.0"),
        ("obs[0] / 2.0 + obs[0] / 4.0 - obs[1]", "0.75 * obs[0] - obs[1]"),
        ("obs[0] * obs[1] - 1.5 * (obs[0] * obs[1]) + obs[2]", "-0.5 * (obs[0] * obs[1]) + obs[2]"),
        ("-obs[0] - obs[1] + obs[0]", "-obs[1]"),
        ("np.tanh(obs[0] + 2.0 * obs[1] - 0.5 * obs[0])", "np.tanh(0.5 * obs[0] + 2.0 * obs[1])"),
    ):
        (collected,) = _collected(f"import numpy as np\n\ndef policy(obs):\n    return {before}")
        assert collected.code.endswith(f"return {after}"), before
    # Nothing to collect, or nothing smaller: no candidate (a scaled sum keeps its factor if distributing it is no smaller).
    for kept in ("0.1111 * obs[9] - 4.351 * obs[3]", "obs[0] / 0.1413", "np.pi / 1.102 - obs[0]", "0.5 * (obs[0] + obs[1])"):
        assert not _collected(f"import numpy as np\n\ndef policy(obs):\n    return {kept}"), kept


def test_like_terms_are_collected_once_for_the_whole_sum_not_for_each_part():
    code = "def policy(obs):\n    return obs[0] + 0.5 * obs[1] + 2.0 * (obs[0] - obs[1]) + obs[2]"
    (collected,) = _collected(code)
    assert collected.code.endswith("return 3.0 * obs[0] - 1.5 * obs[1] + obs[2]")


def test_names_assigned_once_and_read_only_in_a_sum_are_written_in_where_that_collects_terms():
    # The pendulum's by_yield seed-1 winner after simplification kept `action = 0.1671` for one read.
    code = "def policy(obs):\n    action = 0.1671\n    b = obs[2]\n    return action - 11.97 * (obs[1] - b * b) + 0.3294"
    assert [(c.description, c.code) for c in _collected(code)] == [(
        "collected the like terms of `action - 11.97 * (obs[1] - b * b) + 0.3294` with `action` written in at line 4",
        "def policy(obs):\n    b = obs[2]\n    return 0.4965 - 11.97 * (obs[1] - b * b)",  # `b`, read twice, stays
    )]
    # A number read twice is written in twice (the constant a constant budget's cut left there).
    twice = "def policy(obs):\n    action = 1.0\n    return action + 2.0 * np.tanh(obs[1]) + action"
    assert [c.code for c in _collected(twice)] == ["def policy(obs):\n    return 2.0 + 2.0 * np.tanh(obs[1])"]
    blend = "def policy(obs):\n    a = 2.0 * obs[0] + obs[1]\n    a_b = obs[0] - 0.5 * obs[1]\n    return a + 1.5 * a_b"
    (collected,) = _collected(blend)
    assert collected.code == "def policy(obs):\n    return 3.5 * obs[0] + 0.25 * obs[1]"
    for kept in (
        "def policy(obs):\n    a = obs[0]\n    a = a * 2.0\n    return a + 1.0 + a",  # assigned twice
        "def policy(obs):\n    obs = obs * 2.0\n    a = 0.5 * obs[1]\n    return a * obs[0] + 1.0 + 2.0 * a",  # an expression read twice
        "def policy(obs):\n    a = np.tanh(obs[0])\n    return a + 2.0 * obs[1]",  # nothing to collect
    ):
        assert not _collected(kept), kept


# The A1's seed-2 winner of docs/locomotion-search.md, shortened: mutation's blend of two related
# programs, each assigned to its own name, alike but for their constants.
BLEND = """import numpy as np

def policy(obs):
    action = 0.0162 * obs[21] + np.array([0.9069, 0.13, -0.3416]) * obs[3] ** 2
    action_b = 0.0146 * obs[21] + np.array([0.8374, 0.1259, -0.3418]) * obs[3] ** 2
    return 0.5068 * action + 0.4948 * action_b
"""


def _merged(code: str) -> list[str]:
    return [c.code for c in deletion_candidates(code) if c.description.startswith("merged the alike terms")]


def test_terms_alike_but_for_their_constants_are_merged_into_one_by_a_measured_candidate():
    (merged,) = [c for c in deletion_candidates(BLEND) if c.description.startswith("merged the alike terms")]
    assert merged.description == "merged the alike terms of `0.5068 * action + 0.4948 * action_b` into one at line 6"
    # Each constant the weighted mean of the pair, (0.5068 * 0.9069 + 0.4948 * 0.8374) / 1.0016 = 0.8726; the weights' sum in front.
    assert merged.code.endswith("return 1.002 * (0.01541 * obs[21] + np.array([0.8726, 0.128, -0.3417]) * obs[3] ** 2)")
    # Terms written out, a difference, one name twice: 0.3 * 1.5 - 0.1 * 2.5 = 0.2 * 1.0.
    assert _merged("import numpy as np\n\ndef policy(obs):\n    return 0.3 * np.tanh(1.5 * obs[0]) - 0.1 * np.tanh(2.5 * obs[0])") == [
        "import numpy as np\n\ndef policy(obs):\n    return 0.2 * np.tanh(1.0 * obs[0])"
    ]
    assert _merged("def policy(obs):\n    a = 2.0 * obs[0]\n    return 0.25 * a + a * 0.75") == ["def policy(obs):\n    a = 2.0 * obs[0]\n    return a"]
    for differs in (
        BLEND.replace("    return", "    action_b = action_b + 1.0\n    return"),  # a name assigned twice
        BLEND.replace("    action = 0.0162 * obs[21]", "    obs = 2.0 * obs\n    action = 0.0162 * obs[21]"),  # read from a rebound name
        BLEND.replace("0.5068 * action + 0.4948", "0.5 * action - 0.5"),  # weights that cancel
        BLEND.replace("obs[21] + np", "obs[20] + np", 1).replace("0.13, -0.3416", "0.13 * obs[0], -0.3416"),  # two subexpressions
        BLEND.replace("0.0162 * obs[21] + np", "0.0162 * obs[21] - np"),  # at their root
    ):
        assert _merged(differs) == [], differs
    # One subexpression that differs (here an expression where the other has a constant; or
    # `obs[3] ** 2` against `obs[4] ** 3`): the weighted sum of the two.
    (one,) = _merged(BLEND.replace("0.9069, 0.13, -0.3416", "0.9069, 2.143 * obs[13], -0.3416"))
    assert one.endswith("return 1.002 * (0.01541 * obs[21] + np.array([0.8726, 0.506 * (2.143 * obs[13]) + 0.0622, -0.3417]) * obs[3] ** 2)")


def test_a_blend_of_two_near_equal_programs_is_simplified_to_one():
    """TRUSTED TEST CODE: the programs run in this process; a program's score is how close its
    actions come to the blend's, so the merge, exact here, passes and every other deletion fails."""
    observations = np.random.default_rng(0).normal(size=(64, 27))

    def actions(code: str) -> np.ndarray:
        policy = _run_policy(code)
        return np.array([np.broadcast_to(policy(o), 3) for o in observations])  # a constant action, too

    blended = actions(BLEND)

    def score(code: str) -> Scores:
        try:
            closeness = 100.0 - 100.0 * float(np.mean(np.abs(actions(code) - blended)))
        except Exception:  # a deletion can break a program: a name left unassigned, a list times a float
            closeness = -math.inf
        return Scores(closeness, closeness)

    def score_batch(codes):
        return [score(code) for code in codes]

    result = simplify(BLEND, scoring(score_batch))
    assert result.steps[0].description.startswith("merged the alike terms of `0.5068 * action + 0.4948 * action_b`")
    assert result.code.endswith("return 0.01541 * obs[21] + np.array([0.8726, 0.128, -0.3417]) * obs[3] ** 2")  # and the 1.002 dropped
    assert measure(result.code).params == 4 < measure(BLEND).params == 10


# --- the acceptance rule, with constructed scores -------------------------------------------------

SUM_OF_TERMS = "def policy(obs):\n    return 1.0 * obs[0] + 2.0 * obs[1] + 3.0 * obs[2]"


def _terms_left(code: str) -> set[str]:
    return {term for term in ("obs[0]", "obs[1]", "obs[2]") if term in code}


def test_a_deletion_that_raises_the_heldout_gap_is_refused():
    def score_batch(codes):
        # Every program fits the training episodes alike; only obs[2] carries to the held-out ones.
        return [Scores(100.0, 100.0 if "obs[2]" in code else 50.0) for code in codes]

    result = simplify(SUM_OF_TERMS, scoring(score_batch))
    assert _same(result.code, "def policy(obs):\n    return obs[2]")
    assert result.scores == Scores(100.0, 100.0)
    assert all("obs[2]" in step.code for step in result.steps)


def test_losses_are_measured_against_the_original_and_do_not_compound():
    def score(code: str) -> Scores:
        lost = 0.6 * (3 - len(_terms_left(code)))  # each dropped term costs 0.6% of 100
        return Scores(100.0 - lost, 100.0 - lost)

    def score_batch(codes):
        return [score(code) for code in codes]

    result = simplify(SUM_OF_TERMS, scoring(score_batch), tolerance=0.01)
    assert len(_terms_left(result.code)) == 2  # a second drop would lose 1.2% in all
    assert result.scores.train == pytest.approx(99.4)


def test_negative_and_zero_scores():
    def score_batch_from(base: float):
        def score_batch(codes):
            return [Scores(base - 0.6 * abs(base) / 100 * (3 - len(_terms_left(code))), base) for code in codes]
        return score_batch

    negative = simplify(SUM_OF_TERMS, scoring(score_batch_from(-200.0)), tolerance=0.01)
    assert len(_terms_left(negative.code)) == 2 and negative.scores.train == pytest.approx(-201.2)
    # A zero reference allows no loss at all, but equal scores pass.
    zero = simplify(SUM_OF_TERMS, scoring(lambda codes: [Scores(0.0, 0.0) for _ in codes]), tolerance=0.01)
    assert count_nodes(zero.code) < count_nodes(SUM_OF_TERMS)
    lossy_zero = simplify(SUM_OF_TERMS, scoring(lambda codes: [Scores(-1e-6 * (3 - len(_terms_left(c))), 0.0) for c in codes]))
    assert _terms_left(lossy_zero.code) == {"obs[0]", "obs[1]", "obs[2]"}


def _scale_constants(code: str, factor: float) -> str:
    program = parametrize(code)
    return instantiate(program.skeleton, [v * factor for v in program.values])


def test_retuned_code_is_kept_only_if_it_scores_better():
    code = "def policy(obs):\n    return 2.0 * obs[0]"

    def score(code: str) -> Scores:  # best with a gain of 3 on obs[0]
        gain = (parametrize(code).values or (1.0,))[0] if "obs[0]" in code else math.inf
        return Scores(-abs(gain - 3.0), -abs(gain - 3.0))

    def score_batch(codes):
        return [score(code) for code in codes]

    better = simplify(code, scoring(score_batch), retune=lambda c: _scale_constants(c, 1.5))
    assert better.retuned and _same(better.code, "def policy(obs):\n    return 3.0 * obs[0]")
    assert better.steps[-1].description == "re-tuned the constants" and better.scores == Scores(0.0, 0.0)
    worse = simplify(code, scoring(score_batch), retune=lambda c: _scale_constants(c, 0.5))
    assert not worse.retuned and _same(worse.code, code) and worse.scores == Scores(-1.0, -1.0)


def test_a_static_pass_that_changes_scores_is_not_used():
    code = "def policy(obs):\n    unused = 1.0\n    return 2.0 * obs[0]"

    def score_batch(codes):
        # A deliberately inconsistent scorer: the cleaned program scores differently.
        return [Scores(10.0, 10.0) if "unused" in c else Scores(5.0, 5.0) for c in codes]

    result = simplify(code, scoring(score_batch))
    assert not result.static_pass_confirmed
    assert result.code == code and result.steps == () and result.scores == Scores(10.0, 10.0)


@pytest.mark.parametrize("code, expected", [
    ("def policy(obs):\n    x = 0.0\n    x += obs[2]\n    return x", "def policy(obs):\n    x = obs[2]\n    return x"),
    ("def policy(obs):\n    x = 0\n    x -= obs[2]\n    return x", "def policy(obs):\n    x = -obs[2]\n    return x"),
    ("def policy(obs):\n    x = 1.0\n    x *= obs[2]\n    return x", "def policy(obs):\n    x = obs[2]\n    return x"),
], ids=["add", "subtract", "multiply"])
def test_an_accumulator_started_from_its_identity_is_written_as_its_one_term(code, expected):
    cleaned = remove_dead_code(code)
    assert _same(cleaned, expected), cleaned


@pytest.mark.parametrize("code", [
    "def policy(obs):\n    x = 0.0\n    x += obs\n    x[0] = 1.0\n    return x[1]",  # x would be obs itself, then changed
    "def policy(obs):\n    x = 0.0\n    x += obs\n    x += obs\n    return x[1]",
    "def policy(obs):\n    x = 0.0\n    for v in obs:\n        x += v\n    return x",
    "def policy(obs):\n    x = 0.0\n    x += x + obs[0]\n    return x",
    "def policy(obs):\n    x = 2.0\n    x += obs[0]\n    return x",
], ids=["changed in place", "updated twice", "in a loop", "reads itself", "not the identity"])
def test_an_accumulator_that_is_not_just_its_one_term_stays(code):
    assert _same(remove_dead_code(code), code)


def test_the_simplified_program_writes_its_constants_to_4_significant_digits():
    code = "import numpy as np\n\ndef policy(obs):\n    return np.pi / 6.512 * obs[0]"

    def score_batch(codes):  # every deletion costs the score; the constant's last digits do not
        return [Scores(1.0, 1.0) if "* obs[0]" in c else Scores(0.0, 0.0) for c in codes]

    result = simplify(code, scoring(score_batch))
    assert _same(result.code, "def policy(obs):\n    return 0.4824 * obs[0]"), result.code
    assert result.steps[-1].description == "constants written to 4 significant digits"


def test_an_inverted_clip_is_replaced_by_the_constant_it_returns():
    # The disguise: a clip whose lower limit exceeds its upper one reads as a controller.
    code = "import numpy as np\n\ndef policy(obs):\n    torque = 3.771 * obs[1] / (obs[2] ** 2 + 0.5)\n    return np.clip(torque, 1.744, -0.8151)"
    result = simplify(code, trusted_scoring(train=[0, 1], heldout=[2], steps=200))
    assert _same(result.code, "def policy(obs):\n    return -0.8151"), result.code
    assert any("exceeds its upper one" in step.description for step in result.steps)
    assert result.scores == result.scores_initial


def test_a_failing_program_cannot_be_simplified():
    with pytest.raises(ProgramFails, match="fails on the training episodes"):
        simplify(SUM_OF_TERMS, scoring(lambda codes: [Scores(-math.inf, -math.inf) for _ in codes]))


def test_batching_chooses_as_one_batch_does():
    def score_batch(codes):
        return [Scores(100.0 - 0.3 * (3 - len(_terms_left(c))), 100.0) for c in codes]

    batches: list[int] = []

    def counting(codes):
        batches.append(len(codes))
        return [s.train for s in score_batch(codes)]

    whole = simplify(SUM_OF_TERMS, scoring(score_batch))
    chunked = simplify(SUM_OF_TERMS, Scoring(counting, scoring(score_batch).heldout), batch_size=2)
    assert chunked.code == whole.code and chunked.steps == whole.steps
    assert max(batches[1:]) <= 2 and chunked.programs_scored <= whole.programs_scored  # the first: original and cleaned



def _tuned_terms(code: str) -> set[str]:
    """The terms `c * obs[i]` of `code` that keep their constant."""
    return {f"obs[{i}]" for i in re.findall(r"\d+\.\d+ \* obs\[(\d)\]", code)}


def test_a_constant_budget_deletes_what_loses_least_per_constant_removed():
    code = "def policy(obs):\n    return 2.0 * obs[0] + 2.0 * obs[1] + 2.0 * obs[2]"

    def score(code: str) -> Scores:  # obs[0]'s and obs[1]'s terms cancel: one without the other costs 50
        terms = _tuned_terms(code)
        pair = len(terms & {"obs[0]", "obs[1]"})
        value = 100.0 - 2.0 * ("obs[2]" not in terms) - 3.0 * (pair == 0) - 50.0 * (pair == 1)
        return Scores(value, value)

    def budget_steps(result: SimplifyResult) -> list[Step]:
        return [step for step in result.steps if step.description.endswith("(for the constant budget)")]

    within = simplify(code, scoring(lambda codes: [score(c) for c in codes]), tolerance=0.01)
    assert within.code == code and within.within_budget  # every deletion costs more than 1%, and there is no budget
    # Two constants to go: the pair's term (3.0 lost, 1.5 a constant), not obs[2]'s (2.0 for one).
    one = simplify(code, scoring(lambda codes: [score(c) for c in codes]), tolerance=0.01, max_constants=1)
    assert [_tuned_terms(step.code) for step in budget_steps(one)] == [{"obs[2]"}]
    assert one.scores == Scores(97.0, 97.0) and one.within_budget and one.size.params == 1
    # One constant to go: the pair's second constant earns nothing, so obs[2]'s term goes.
    two = simplify(code, scoring(lambda codes: [score(c) for c in codes]), tolerance=0.01, max_constants=2)
    assert [_tuned_terms(step.code) for step in budget_steps(two)] == [{"obs[0]", "obs[1]"}]
    assert two.scores == Scores(98.0, 98.0) and two.to_json()["max_constants"] == 2 and two.to_json()["within_budget"] is True


def test_after_a_constant_budget_the_retuning_is_judged_against_the_budgets_program():
    code = "def policy(obs):\n    return 2.0 * obs[0] + 2.0 * obs[1] + 2.0 * obs[2]"

    def score(code: str) -> Scores:  # a term earns its weight times c / 3, at most its weight
        found = re.findall(r"(\d+\.\d+) \* obs\[(\d)\]", code)
        value = sum({"0": 10.0, "1": 30.0, "2": 60.0}[i] * min(1.0, float(c) / 3.0) for c, i in found)
        return Scores(value, value)

    def retune(code: str) -> str:  # every constant to 3.0: each term's best
        return _scale_constants(code, 1.5)

    result = simplify(code, scoring(lambda codes: [score(c) for c in codes]), retune=retune, tolerance=0.01, max_constants=1)
    assert [step.scores.train for step in result.steps] == pytest.approx([60.0, 40.0, 60.0])  # 66.7 at first
    # 60.0 is 10% below the original's 66.7, but above the 40.0 the budget left: kept.
    assert result.retuned and _same(result.code, "def policy(obs):\n    return 3.0 * obs[2]") and result.within_budget


def test_after_a_constant_budget_the_deletions_go_on_within_the_tolerance_of_the_budgets_program():
    code = "import numpy as np\n\ndef policy(obs):\n    return 2.0 * obs[0] + 2.0 * obs[1] + np.tanh(obs[2])"

    def score(code: str) -> Scores:  # the tanh matters only beside obs[1]'s term
        kept = {term: term in code for term in ("2.0 * obs[0]", "2.0 * obs[1]", "obs[2]", "tanh")}
        value = 100.0 - 20.0 * (not kept["2.0 * obs[0]"]) - 3.0 * (not kept["2.0 * obs[1]"]) - 30.0 * (not kept["obs[2]"])
        value -= 5.0 * (kept["2.0 * obs[1]"] and not kept["tanh"])
        return Scores(value, value)

    result = simplify(code, scoring(lambda codes: [score(c) for c in codes]), tolerance=0.01, max_constants=1)
    assert [step.description.split(" `")[0] for step in result.steps] == ["dropped the term", "unwrapped"]
    assert result.steps[0].description.endswith("(for the constant budget)") and not result.steps[1].description.endswith("budget)")
    assert _same(result.code, "def policy(obs):\n    return 2.0 * obs[0] + obs[2]") and result.scores == Scores(97.0, 97.0)


def test_under_a_constant_budget_no_deletion_takes_the_program_over_it():
    # Replacing a compared value or a branch by 0.0 or 1.0 costs nothing here, but adds a constant.
    code = "def policy(obs):\n    return 2.0 * obs[0] if obs[1] > obs[2] else obs[1]"

    def score_batch(codes):
        return [Scores(100.0, 100.0) if "2.0 * obs[0]" in c and ">" in c else Scores(0.0, 0.0) for c in codes]

    assert simplify(code, scoring(score_batch)).size.params > 1
    within = simplify(code, scoring(score_batch), max_constants=1)
    assert within.code == code and within.within_budget and not within.steps and within.over_budget is None


def test_a_budget_no_deletion_can_meet_is_reported_as_missed():
    result = simplify("def policy(obs):\n    return 0.5", scoring(lambda codes: [Scores(1.0, 1.0) for _ in codes]), max_constants=0)
    assert result.size.params == 1 and not result.within_budget and result.to_json()["within_budget"] is False
    assert result.over_budget == "over the constant budget: 1 constants left, at most 0 asked"  # the CLI's line, the finish's header
    with pytest.raises(ValueError, match="max_constants must be >= 0"):
        simplify(SUM_OF_TERMS, scoring(lambda codes: [Scores(1.0, 1.0) for _ in codes]), max_constants=-1)


# --- the pendulum winner, measured -------------------------------------------------------------------


def _check_winner(result: SimplifyResult) -> None:
    assert result.static_pass_confirmed
    assert result.size.nodes <= 0.6 * result.size_initial.nodes
    assert result.scores.train >= 0.97 * result.scores_initial.train
    report = result.to_json()
    assert {"score_initial", "score", "heldout_score", "size_initial", "size", "lines", "n_params", "code"} <= report.keys()
    assert report["size_initial"] == 208 and report["size"] == count_nodes(result.code)
    json.dumps(report, allow_nan=False)
    # Every step was measured and kept the training score within 1% of the original's.
    assert all(step.scores.train >= 0.99 * result.scores_initial.train for step in result.steps)


def test_pendulum_winner_shrinks_on_short_evaluations():
    train = episode_seeds(0, 2)
    heldout = [s for s in episode_seeds(1, 4) if s not in train][:2]
    trusted = trusted_scoring(train, heldout, steps=300)
    result = simplify(PENDULUM_WINNER, trusted, retune=lambda code: code, batch_size=16)
    _check_winner(result)


@pytest.mark.slow
def test_pendulum_winner_shrinks_to_60_percent_keeping_97_percent_as_the_search_scores_it(tmp_path):
    """The issue's criterion, through the command line: the referee in the sandbox, the search's
    10 training episodes of 1000 steps at seed 0, 100 held-out episodes, oneplusone re-tuning."""
    from conftest import last_json_line, run_colmo

    policy_file = tmp_path / "winner.py"
    policy_file.write_text(PENDULUM_WINNER)
    result = run_colmo("colmo.simplify", f"policy_file={policy_file}", "task=pendulum", "executor.workers=2", cwd=tmp_path, timeout=1800)
    assert result.returncode == 0, result.stderr
    summary = last_json_line(result.stdout)
    assert summary["score_initial"] == pytest.approx(842.3) and summary["size_initial"] == 208
    assert summary["size"] <= 0.6 * summary["size_initial"]
    assert summary["score"] >= 0.97 * summary["score_initial"]
    assert all(step["score"] >= 0.99 * summary["score_initial"] for step in summary["steps"])
    assert summary["heldout_score"] >= summary["heldout_score_initial"] - 2 * 0.01 * summary["score_initial"] - 1e-6


# --- the greedy search's control -------------------------------------------------------------------


def test_only_programs_that_pass_on_training_get_a_heldout_score():
    heldout_scored: list[str] = []

    def train(codes):
        return [100.0 if "obs[2]" in code else 10.0 for code in codes]

    def heldout(codes):
        heldout_scored.extend(codes)
        return [100.0 for _ in codes]

    result = simplify(SUM_OF_TERMS, Scoring(train, heldout))
    assert _same(result.code, "def policy(obs):\n    return obs[2]")
    assert all("obs[2]" in code for code in heldout_scored)
    assert result.heldout_scored == len(set(heldout_scored)) < result.programs_scored


def test_runs_are_deterministic_and_max_rounds_cuts_them_short():
    def score_batch(codes):  # every term is needed; its constant factor is not
        return [Scores(100.0, 100.0) if len(_terms_left(c)) == 3 else Scores(0.0, 0.0) for c in codes]

    whole = simplify(SUM_OF_TERMS, scoring(score_batch))
    assert _same(whole.code, "def policy(obs):\n    return obs[0] + obs[1] + obs[2]") and len(whole.steps) == 3
    assert simplify(SUM_OF_TERMS, scoring(score_batch)).steps == whole.steps
    again = simplify(SUM_OF_TERMS, scoring(score_batch), max_rounds=1)
    assert again.steps == whole.steps[:1] and again.rounds == 1
    assert not whole.cut_short and not again.cut_short  # it found nothing more, or was told to stop at a round count


def test_stop_keeps_the_program_so_far_and_skips_retuning():
    retuned: list[str] = []
    result = simplify(SUM_OF_TERMS, scoring(lambda codes: [Scores(1.0, 1.0) for _ in codes]), retune=lambda c: retuned.append(c) or c, stop=lambda: True)
    assert result.rounds == 0 and result.code == SUM_OF_TERMS and not retuned
    assert result.cut_short and result.to_json()["cut_short"] is True


# --- through the sandbox: simplify_program and `python -m colmo.simplify` ----------------------------

# A hand-written pendulum policy with dead code: a docstring, an unused assignment, a literal
# call, a term multiplied by zero and a second `return`.
DEAD_CODE_POLICY = '''import numpy as np

def policy(obs):
    """Energy pumping far from upright, a PD law near it."""
    unused = np.abs(4.4) * obs[0]
    angle = np.arctan2(obs[1], obs[0])
    if np.abs(angle) > 0.52:
        action = np.sign(obs[2]) + 0.0 * obs[1]
    else:
        action = 9.4 * np.sin(-angle) - 2.7 * obs[2]
    return action
    return 0.0
'''
SHORT = {"horizon": 200}  # PendulumSwingup's episode length, cut for speed
REPORT_KEYS = {"score_initial", "score", "heldout_score", "size_initial", "size", "lines", "n_params", "code", "seconds"}


@pytest.fixture(scope="module")
def executor():
    from colmo.executor import LocalExecutor

    with LocalExecutor(2, memory_mb=1024) as local:
        yield local


@pytest.fixture(scope="module")
def evaluators():
    from colmo.evaluation import Evaluator
    from colmo.heldout import heldout_evaluator

    spec = load_spec("pendulum.py")
    train = Evaluator.for_task(spec, SHORT, episode_seeds(0, 2), memory_mb=1024, timeout_s=120.0)
    return train, heldout_evaluator(train, 0, 2)


def test_referee_scores_match_an_in_process_evaluation_and_refuse_what_the_check_refuses(executor, evaluators):
    from colmo.simplify import RefereeScores

    train, _ = evaluators
    forbidden = "import os\n\ndef policy(obs):\n    return float(len(os.listdir('/')))"
    scores = RefereeScores(executor, train)
    # One program on two workers: its two episodes go to two requests, joined in order.
    (sandboxed,) = scores([DEAD_CODE_POLICY])
    trusted = evaluate_policy(PendulumSwingup(**SHORT), _run_policy(DEAD_CODE_POLICY), train.seeds).score
    assert sandboxed == pytest.approx(trusted, rel=1e-12)
    assert scores([forbidden, DEAD_CODE_POLICY]) == [-math.inf, sandboxed]
    assert scores.failures[forbidden].startswith("refused:") and "os" in scores.failures[forbidden]


def test_simplify_program_shrinks_within_tolerance_in_the_sandbox(executor, evaluators):
    from colmo.config import GFOConfig
    from colmo.simplify import simplify_program

    train, heldout = evaluators
    result = simplify_program(executor, train, heldout, DEAD_CODE_POLICY, GFOConfig(method="oneplusone", budget=6), tolerance=0.01, seed=0)
    assert result.static_pass_confirmed and "return 0.0" not in result.code and "unused" not in result.code
    assert result.size.nodes < result.size_initial.nodes
    assert result.scores.train >= result.scores_initial.train - 0.01 * abs(result.scores_initial.train)
    assert REPORT_KEYS <= result.to_json().keys()


def test_simplify_program_says_why_a_failing_policy_cannot_be_simplified(executor, evaluators):
    from colmo.config import GFOConfig
    from colmo.errors import RunError
    from colmo.simplify import simplify_program

    train, heldout = evaluators
    failing = "def policy(obs):\n    return obs[99]"
    with pytest.raises(RunError, match="fails on the training episodes: exception: IndexError"):
        simplify_program(executor, train, heldout, failing, GFOConfig(method="none", budget=1))


def _simplified_on_short_episodes(tmp_path, option: str) -> tuple[str, dict, Path]:
    """`colmo-simplify` on DEAD_CODE_POLICY, short pendulum episodes: its stdout, its JSON line, the policy it wrote."""
    from conftest import last_json_line, run_colmo

    policy_file = tmp_path / "policy.py"
    policy_file.write_text(DEAD_CODE_POLICY)
    result = run_colmo(
        "colmo.simplify", f"policy_file={policy_file}", "task=pendulum", "+task.env.horizon=200", "task.episodes=2",
        "heldout.episodes=2", "gfo.budget=6", "executor.workers=2", option, cwd=tmp_path,
    )
    assert result.returncode == 0, result.stderr
    (written,) = tmp_path.glob("outputs/simplify/*/*/simplified_policy.py")
    return result.stdout, last_json_line(result.stdout), written


def test_the_command_line_simplifies_a_policy_file(tmp_path):
    stdout, summary, written = _simplified_on_short_episodes(tmp_path, "simplify.tolerance=0.01")
    assert REPORT_KEYS <= summary.keys()
    assert summary["size"] < summary["size_initial"] and summary["lines"] < summary["lines_initial"]
    assert summary["score"] >= summary["score_initial"] - 0.01 * abs(summary["score_initial"])
    assert summary["heldout_score"] is not None and summary["code"] in stdout
    first, second, code = written.read_text().split("\n", 2)
    assert first.startswith("# simplified by colmo-simplify") and second.startswith("# training score") and code.strip() == summary["code"]
    assert json.loads((written.parent / "result.json").read_text())["code"] == summary["code"]


def test_the_command_line_meets_a_constant_budget(tmp_path):
    _, summary, written = _simplified_on_short_episodes(tmp_path, "simplify.max_constants=1")
    assert summary["n_params_initial"] > 1 >= summary["n_params"] and summary["within_budget"] is True and summary["max_constants"] == 1
    assert any(step["description"].endswith("(for the constant budget)") for step in summary["steps"])
    assert "tolerance 0.01, at most 1 constants" in written.read_text().splitlines()[0]


def test_the_command_line_config_composes_and_checks_the_tolerance():
    import importlib

    from conftest import compose

    from colmo.errors import ConfigError

    importlib.import_module("colmo.simplify.__main__")  # registers the command's root schema
    cfg = compose("simplify", "policy_file=p.py", "task=cheetah", "gfo=none", "simplify.tolerance=0.05")
    assert (cfg.task.name, cfg.gfo.method, cfg.simplify.tolerance, cfg.heldout.episodes) == ("cheetah", "none", 0.05, 100)
    assert cfg.simplify.max_constants is None and compose("simplify", "policy_file=p.py", "simplify.max_constants=10").simplify.max_constants == 10
    with pytest.raises(ConfigError, match=r"simplify.tolerance must be in \[0, 1\), got 1.5"):
        compose("simplify", "policy_file=p.py", "simplify.tolerance=1.5")
    with pytest.raises(ConfigError, match=r"simplify.max_constants must be >= 0 or null, got -1"):
        compose("simplify", "policy_file=p.py", "simplify.max_constants=-1")


def chained_assignments(statements: int) -> str:
    """A good controller followed by `statements` chained assignments (issue 33: 1,500 of them
    kept colmo-simplify in its first round for minutes; each deletion parses the whole program)."""
    body = "".join(f"    x{i} = x{i - 1} + 0.001 * obs[{i % 3}]\n" for i in range(1, statements))
    return f"import numpy as np\n\ndef policy(obs):\n    x0 = obs[0]\n{body}    return -2.0 * np.arctan2(obs[1], obs[0]) - 0.5 * obs[2] + 0.0 * x{statements - 1}\n"


def test_making_candidates_stops_when_asked():
    code = chained_assignments(300)
    asked = []
    stop = lambda: asked.append(1) or len(asked) > 5  # noqa: E731
    assert len(deletion_candidates(code, stop=stop)) <= 5 and len(asked) == 6
    assert deletion_candidates(code, stop=lambda: True) == []


def test_a_time_limit_ends_the_simplification_with_the_best_program_so_far(executor, evaluators):
    from colmo.config import GFOConfig
    from colmo.simplify import simplify_program

    train, heldout = evaluators
    code = chained_assignments(300)  # its candidates alone would take over a minute to make
    result = simplify_program(executor, train, heldout, code, GFOConfig(method="none", budget=1), max_seconds=2.0)
    assert result.size.nodes <= result.size_initial.nodes and result.scores.train >= result.scores_initial.train - 0.01 * abs(result.scores_initial.train)
    assert len(result.steps) <= 1  # at most the static pass: no round of deletions had the time


def _simplifying(tmp_path, statements: int):
    """`colmo-simplify` started on a long policy, its workers' temporary directories under
    `tmp_path/tmp`; returns the process once it has begun simplifying."""
    from conftest import start_colmo

    (tmp_path / "tmp").mkdir()
    policy_file = tmp_path / "policy.py"
    policy_file.write_text(chained_assignments(statements))
    process = start_colmo(
        "colmo.simplify", f"policy_file={policy_file}", "task=pendulum", "task.episodes=2", "heldout.episodes=2", "executor.workers=2",
        cwd=tmp_path, env={**os.environ, "TMPDIR": str(tmp_path / "tmp")},
    )
    for line in process.stderr:
        if "simplifying with tolerance" in line:
            return process
    pytest.fail(f"colmo-simplify ended before simplifying: {process.communicate()}")


def test_ctrl_c_stops_the_simplifier_with_the_simplification_so_far(tmp_path):
    from conftest import last_json_line

    process = _simplifying(tmp_path, 400)
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=300)
    assert process.returncode == 130, stderr
    assert "interrupted: stopping with the simplification so far" in stderr and "Traceback" not in stderr
    summary = last_json_line(stdout)
    assert summary["interrupted"] is True and summary["score"] is not None
    (written,) = tmp_path.glob("outputs/simplify/*/*/simplified_policy.py")
    assert written.read_text().endswith(summary["code"] + "\n")
    assert list((tmp_path / "tmp").iterdir()) == []  # the workers' directory is gone


def test_a_second_ctrl_c_quits_the_simplifier_in_one_line(tmp_path):
    process = _simplifying(tmp_path, 400)
    process.send_signal(signal.SIGINT)
    for line in process.stderr:  # signals of one kind do not queue: the second once the first is handled
        if "interrupted: stopping" in line:
            break
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=300)
    assert process.returncode == 130, stderr
    assert stderr.strip().splitlines()[-1] == "colmo: interrupted" and "Traceback" not in stderr
    assert list((tmp_path / "tmp").iterdir()) == []
