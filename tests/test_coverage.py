"""Branch coverage (issue 38 part 1): what each branch of a policy did, counted in the sandbox on
the fast path, and written as comments into the policy's text."""

from __future__ import annotations

import ast
import json
import re

import numpy as np
import pytest
from conftest import compose, last_json_line, run_colmo

from colmo import coverage
from colmo.evaluation import REFEREE, EvalRequest, Evaluation
from colmo.optimize.tune import CandidateEvaluator
from colmo.program import parametrize
from colmo.sandbox.namespace import Program

# The pendulum (obs = [cos θ, sin θ, ω]) with a balance branch that can never run (cos θ > 1.5),
# a branch that runs now and then, a clip whose limits are inverted (a constant in disguise),
# a conditional expression and an np.where.
DEAD_BRANCH = """import numpy as np


def policy(obs):
    cos_theta, sin_theta, omega = obs
    if cos_theta > 1.5:
        return -5.0 * sin_theta - omega
    push = 1.0 if omega > 0.0 else -1.0
    if sin_theta > 0.9:
        push = np.where(omega > 0.0, 0.5, -0.5)
    return np.clip(push, 1.2, -0.8)
"""


def test_the_sites_of_a_program_in_walk_order_with_their_statements_lines():
    found = coverage.sites(DEAD_BRANCH)
    assert [(s.kind, s.line, s.text) for s in found] == [
        ("if", 6, "cos_theta > 1.5"),
        ("conditional", 8, "omega > 0.0"),
        ("if", 9, "sin_theta > 0.9"),
        ("where", 10, "np.where(omega > 0.0, 0.5, -0.5)"),
        ("clip", 11, "np.clip(push, 1.2, -0.8)"),
    ]
    program = parametrize(DEAD_BRANCH)
    assert coverage.same_sites(DEAD_BRANCH, program.skeleton)  # the skeleton's counts describe the code


def test_the_probe_counts_each_branch_and_leaves_the_program_s_actions_unchanged():
    program = parametrize(DEAD_BRANCH)
    plain = Program(program.skeleton, ("numpy",), program.values).load()
    counted = Program(program.skeleton, ("numpy",), program.values, coverage=True)
    policy = counted.load()
    observations = [np.array([np.cos(t), np.sin(t), w]) for t, w in ((0.1, 1.0), (1.5, -2.0), (1.5, 2.0), (3.0, 0.0))]
    for obs in observations:
        assert np.array_equal(policy(obs), plain(obs))
    assert counted.probe.result() == (
        (4, 0, 0),  # cos θ > 1.5: never
        (4, 2, 0),  # ω > 0
        (4, 2, 0),  # sin θ > 0.9: the two at θ = 1.5
        (2, 1, 0),  # np.where: one value of two chose 0.5
        (4, 1, 3),  # the inverted clip returns its upper limit, -0.8, whatever it is given: -1 raised, the rest lowered
    )


def test_an_array_s_own_clip_counts_against_the_array_it_is_bound_to():
    program = parametrize("import numpy as np\n\ndef policy(obs):\n    return (obs * 10.0).clip(-1.0, 1.0)\n")
    counted = Program(program.skeleton, ("numpy",), program.values, coverage=True)
    counted.load()(np.array([0.05, 0.5, -0.5]))
    assert counted.probe.result() == ((3, 1, 1),)


def test_annotated_code_carries_one_comment_per_site_and_is_the_same_program():
    counts = [(2000, 0, 0), (2000, 1000, 0), (2000, 100, 0), (100, 50, 0), (2000, 0, 2000)]
    text = coverage.annotate(DEAD_BRANCH, counts)
    assert ast.dump(ast.parse(text)) == ast.dump(ast.parse(DEAD_BRANCH))
    lines = text.splitlines()
    dead = lines.index("    if cos_theta > 1.5:")
    assert lines[dead - 1] == "    # coverage: if `cos_theta > 1.5`: true 0% of 2,000 tests (never true)"
    clip = lines.index("    return np.clip(push, 1.2, -0.8)")
    assert lines[clip - 1] == "    # coverage: `np.clip(push, 1.2, -0.8)`: changed 100% of 2,000 values (0% raised, 100% lowered): always at a limit"
    assert coverage.annotate(DEAD_BRANCH, counts[:-1]) is None  # counts of another program


def test_a_reply_s_coverage_is_checked_like_the_rest_of_it():
    request = EvalRequest("spec", (), (1, 2), "code", (), ("numpy",), coverage=True)
    good = Evaluation(returns=(1.0, 2.0), steps=10, coverage=((10, 3, 0),))
    assert Evaluation.from_bytes(good.to_bytes(), request).coverage == ((10, 3, 0),)
    for forged in ([[10, 11, 0]], [[10, -1, 0]], [[1.5, 0, 0]], "all", [[1, 0]]):
        reply = json.loads(good.to_bytes()) | {"coverage": forged}
        with pytest.raises(ValueError):
            Evaluation.from_bytes(json.dumps(reply).encode(), request)
    with pytest.raises(ValueError, match="not asked for"):
        Evaluation.from_bytes(good.to_bytes(), EvalRequest("spec", (), (1, 2), "code", (), ("numpy",), mode=REFEREE))
    halves = Evaluation.joined([Evaluation((1.0,), coverage=((5, 1, 0),)), Evaluation((2.0,), coverage=((5, 2, 1),))])
    assert halves.coverage == ((10, 3, 1),)


@pytest.mark.parametrize("workers", [1, 2])
def test_counted_in_sandbox_workers_the_dead_branch_is_never_taken(workers):
    """The hand-written policy through the real executor, its episodes split over the workers:
    the counts add up over the requests, the score is the fast path's own."""
    from colmo.executor import LocalExecutor
    from colmo.heldout import task_evaluator

    cfg = compose("optimize", "task=pendulum", "task.episodes=3", "policy_file=unused.py")
    program = parametrize(DEAD_BRANCH)
    with LocalExecutor(workers) as executor:
        _, evaluator = task_evaluator(cfg.task, cfg.executor, executor, seed=0)
        evaluate = CandidateEvaluator(executor, evaluator, program.skeleton, workers, count_branches=True)
        counted = evaluate.coverage(program.values)
        [fast] = evaluate.fast([program.values])
        refereed = evaluate.referee(program.values)
    assert counted.failure is None and counted.returns == fast.returns and fast.coverage is None
    # The referee's child counts the same, and sends them after the episodes.
    assert refereed.returns == fast.returns and refereed.coverage == counted.coverage
    steps = counted.steps
    assert steps == 3 * 1000
    dead, conditional, sometimes, where, clip = counted.coverage
    assert dead == (steps, 0, 0) and conditional[0] == steps
    assert clip[0] == clip[1] + clip[2] == steps  # every value moved to the constant -0.8
    assert 0 < sometimes[1] < steps and where[0] == sometimes[1]
    text = coverage.annotate(DEAD_BRANCH, counted.coverage)
    assert "# coverage: if `cos_theta > 1.5`: true 0% of 3,000 tests (never true)" in text



def test_colmo_evaluate_prints_the_policy_with_its_branch_counts(tmp_path):
    (tmp_path / "dead.py").write_text(DEAD_BRANCH)
    result = run_colmo("colmo.heldout", "task=pendulum", "policy_file=dead.py", "episodes=3", "coverage=true", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "    # coverage: if `cos_theta > 1.5`: true 0% of 3,000 tests (never true)\n    if cos_theta > 1.5:" in result.stdout
    counted = last_json_line(result.stdout)["coverage"]
    assert counted["episodes"] == 3 and [site["kind"] for site in counted["sites"]] == ["if", "conditional", "if", "where", "clip"]
    said = "`cos_theta > 1.5` is never true (`cos_theta` is in [-1, 1])"  # read from the code and the spec's bounds
    assert f"decided by the code: {said}\n" in result.stdout and last_json_line(result.stdout)["decided"] == [said]
    (written,) = tmp_path.glob("outputs/**/result.json")  # the JSON line, kept with what produced it
    kept = json.loads(written.read_text())
    assert kept.pop("provenance")["libraries"]["mujoco"] and kept == last_json_line(result.stdout)


def test_pruning_keeps_the_side_of_each_branch_that_ran_and_nothing_undecided():
    counts = [(2000, 0, 0), (2000, 1000, 0), (2000, 2000, 0), (100, 50, 0), (2000, 0, 2000)]
    code, said, branches = coverage.prune(DEAD_BRANCH, counts)
    assert branches == 2
    assert ast.dump(ast.parse(code)) == ast.dump(ast.parse(
        "import numpy as np\n\ndef policy(obs):\n    cos_theta, sin_theta, omega = obs\n    push = 1.0 if omega > 0.0 else -1.0\n"
        "    push = np.where(omega > 0.0, 0.5, -0.5)\n    return np.clip(push, 1.2, -0.8)\n"
    ))
    assert said == (
        "removed the branches never taken: `cos_theta > 1.5` (never true in 2,000 tests), `sin_theta > 0.9` (always true in 2,000 tests)"
    )
    # Not reached at all, or taken both ways: nothing is known, nothing goes.
    assert coverage.prune(DEAD_BRANCH, [(0, 0, 0), (2000, 1000, 0), (2000, 5, 0), (0, 0, 0), (2000, 0, 2000)]) is None
    assert coverage.prune(DEAD_BRANCH, counts[:2]) is None  # another program's counts
    only = "def policy(obs):\n    if obs[0] > 2.0:\n        return 1.0\n    return 0.0\n"
    assert coverage.prune("def policy(obs):\n    while obs[0] > 2.0:\n        obs = obs - 1\n    return obs[0]\n", [(10, 0, 0)])[0] == (
        "def policy(obs):\n    return obs[0]"
    )
    assert coverage.prune(only, [(10, 10, 0)])[0] == "def policy(obs):\n    return 1.0\n    return 0.0"


def test_the_simplifier_takes_the_pruned_program_first_when_it_scores_the_same():
    from colmo.simplify.greedy import Scores, Scoring, simplify

    def score_batch(codes):  # the dead branch never counts: the pruned program scores the same
        return [Scores(100.0, 90.0) for _ in codes]

    pruned = coverage.prune(DEAD_BRANCH, [(2000, 0, 0), (2000, 1000, 0), (2000, 5, 0), (5, 3, 0), (2000, 0, 2000)])
    result = simplify(DEAD_BRANCH, Scoring(lambda c: [s.train for s in score_batch(c)], lambda c: [s.heldout for s in score_batch(c)]), hint=pruned)
    assert result.steps[0].description == "removed the branches never taken: `cos_theta > 1.5` (never true in 2,000 tests)"
    assert "cos_theta > 1.5" not in result.code

    def worse(codes):  # here the branch did matter (other episodes than the counted ones)
        return [Scores(100.0 if "1.5" in c else 50.0, 90.0) for c in codes]

    kept = simplify(DEAD_BRANCH, Scoring(lambda c: [s.train for s in worse(c)], lambda c: [s.heldout for s in worse(c)]), hint=pruned, max_rounds=0)
    assert kept.steps == () and "cos_theta > 1.5" in kept.code


def test_colmo_simplify_first_removes_the_branch_the_policy_never_took(tmp_path):
    (tmp_path / "dead.py").write_text(DEAD_BRANCH)
    result = run_colmo(
        "colmo.simplify", "task=pendulum", "policy_file=dead.py", "task.episodes=3", "heldout.episodes=3", "gfo=none", cwd=tmp_path,
    )
    assert result.returncode == 0, result.stderr
    simplified = last_json_line(result.stdout)
    assert [step["description"] for step in simplified["steps"]][0] == "removed the branches never taken: `cos_theta > 1.5` (never true in 6,000 tests)"
    assert simplified["branches_never_taken"] == 1


def test_the_readability_report_counts_what_the_finish_measured():
    from colmo.readability import describe, report

    counted = coverage.summary(DEAD_BRANCH, [(2000, 0, 0), (2000, 1000, 0), (2000, 2000, 0), (100, 50, 0), (2000, 900, 1100)], 2)
    simplified = {"score": 48.6, "lines": 2, "n_params": 1, "steps": [{"description": "removed the branches never taken: ..."}]}
    readable = report(DEAD_BRANCH, counted, simplified, ["`theta` holds obs[0], which the task calls cos_theta"])
    assert {key: readable[key] for key in ("lines", "branches", "branches_never_taken", "clips_at_a_limit", "misleading_names")} == {
        "lines": 9, "branches": 3, "branches_never_taken": 2, "clips_at_a_limit": 1, "misleading_names": 1,
    }
    assert (readable["simplified_lines"], readable["simplified_parameters"], readable["removed"]) == (2, 1, ["removed the branches never taken: ..."])
    assert describe(readable) == (
        "9 lines, 11 parameters; 2 of 3 branches decided the same way at every test; 1 clip(s) returning a limit for every value; "
        "1 misleading name(s); simplified: 2 lines, 1 parameters"
    )
    nothing = report(DEAD_BRANCH, {}, {"failure": "the policy fails"}, [])
    assert nothing["branches"] is None and nothing["simplified_lines"] is None and nothing["removed"] == []


DIVIDES = """import numpy as np


def policy(obs):
    cos_theta, sin_theta, omega = obs
    gain = 2.0 / (2 * np.pi)
    damping = sin_theta / omega
    return np.clip(gain * sin_theta - damping, -1.0, 1.0)
"""


def test_a_division_by_a_velocity_that_is_zero_at_reset_is_counted():
    """Issue 38: `x / omega` reads as physics and is inf at every reset (the pendulum starts at
    rest). A divisor of constants (`2 * np.pi`) is no site."""
    from colmo.executor import LocalExecutor
    from colmo.heldout import branch_counts, task_evaluator
    from colmo.readability import describe, report

    assert [(s.kind, s.text) for s in coverage.sites(DIVIDES)] == [("division", "sin_theta / omega"), ("clip", "np.clip(gain * sin_theta - damping, -1.0, 1.0)")]
    cfg = compose("optimize", "task=pendulum", "task.episodes=2", "policy_file=unused.py")
    program = parametrize(DIVIDES)
    with LocalExecutor(2) as executor:
        _, evaluator = task_evaluator(cfg.task, cfg.executor, executor, seed=0)
        counted = branch_counts(executor, evaluator, program.skeleton, program.values)
        [fast] = CandidateEvaluator(executor, evaluator, program.skeleton, 2).fast([program.values])
    assert counted.failure is None and counted.returns == fast.returns  # counting changes no return
    (values, zero, not_finite), _ = counted.coverage
    assert values == 2 * 1000 and 2 <= zero < values and not_finite == 0  # at least each episode's first step
    text = coverage.annotate(DIVIDES, counted.coverage)
    assert re.search(r"    # coverage: `sin_theta / omega`: divisor 0 for [0-9.]+% of 2,000 values\n    damping = sin_theta / omega\n", text), text
    readable = report(DIVIDES, coverage.summary(DIVIDES, counted.coverage, 2), {}, [])
    assert readable["divisions_by_zero"] == 1 and "1 division(s) by zero" in describe(readable)
