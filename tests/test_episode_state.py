"""Every episode starts from a freshly loaded program, so that a score cannot depend on how it
was run: the number of workers, the chunking of episodes over requests, racing, fast path or
referee (issue 22). State a policy keeps lives within one episode only.

The programs here run only in sandbox workers.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import compose, last_json_line, run_colmo

from colmo.evaluation import FAST, REFEREE
from colmo.optimize.tune import CandidateEvaluator
from colmo.program import parametrize
from colmo.racing import Race

# Counts its calls in a module global and returns NaN at the 10,000th: the last step of the
# last of 10 training episodes of 1000 steps, were the episodes one call sequence. (A module
# global, not a function attribute: colmo-optimize's intake keeps a program's definitions and
# assignments to names, not a `policy.calls = 0` statement.)
COUNTER = """import numpy as np

CALLS = [0]

def policy(obs):
    CALLS[0] += 1
    if CALLS[0] == 10000:
        return np.nan
    return -1.0 * obs[2]
"""

# An honest stateful policy: a leaky integral of the velocity, reset at its first step.
INTEGRATOR = """import numpy as np

def policy(obs):
    if policy.step == 0:
        policy.integral = 0.0
    policy.step += 1
    policy.integral = 0.95 * policy.integral + obs[2]
    return float(np.clip(0.5 * obs[2] + 0.2 * policy.integral, -1.0, 1.0))

policy.step = 0
policy.integral = 0.0
"""

# Counts the episodes before it in numpy's process-wide settings (print options, error handling),
# which its module code reads and changes (issue 33 finding 4).
NUMPY_SETTINGS_COUNTER = """import numpy as np

EARLIER = np.get_printoptions()["precision"] - 8 + (np.geterr()["divide"] == "ignore")
np.set_printoptions(precision=int(np.get_printoptions()["precision"] + 1))
np.seterr(divide="ignore")

def policy(obs):
    return float(np.clip(0.5 * obs[2] - 0.1 * EARLIER, -1.0, 1.0))
"""

# Fails in some episodes only, at different steps (its module code draws from the episode's
# seeded np.random): the first failing episode in seed order decides, fast path and referee alike.
FAILS_IN_SOME_EPISODES = """import numpy as np

LUCK = np.random.uniform()

def policy(obs):
    policy.step += 1
    if LUCK > 0.7 and policy.step == 600:
        raise ValueError("unlucky")
    if LUCK < 0.3 and policy.step == 20:
        return np.nan
    return 0.5 * obs[2]

policy.step = 0
"""


@pytest.fixture(scope="module")
def pendulum():
    """Three sandbox workers and the pendulum's calibrated evaluator (10 training episodes)."""
    from colmo.executor import LocalExecutor
    from colmo.heldout import task_evaluator

    cfg = compose("optimize", "task=pendulum", "gfo=oneplusone", "policy_file=unused.py")
    with LocalExecutor(3) as executor:
        _, evaluator = task_evaluator(cfg.task, cfg.executor, executor, seed=0)
        assert len(evaluator.seeds) == 10
        yield executor, evaluator


@pytest.mark.parametrize("code", [COUNTER, INTEGRATOR, NUMPY_SETTINGS_COUNTER], ids=["counter", "integrator", "numpy settings"])
def test_a_stateful_programs_score_does_not_depend_on_how_its_episodes_are_run(pendulum, code):
    executor, evaluator = pendulum
    program = parametrize(code)
    results = []
    for chunks in (1, 2, 3):
        evaluate = CandidateEvaluator(executor, evaluator, program.skeleton, chunks)
        [fast] = evaluate.fast([program.values])
        results += [fast, evaluate.referee(program.values)]
    assert all(result.failure is None for result in results), results
    assert len({result.returns for result in results}) == 1 and len(results[0].returns) == 10
    assert len(set(results[0].returns)) > 1  # the episodes differ: not one constant repeated


def test_racing_stops_episodes_but_changes_none_of_their_returns(pendulum):
    executor, evaluator = pendulum
    program = parametrize(INTEGRATOR)
    [full] = CandidateEvaluator(executor, evaluator, program.skeleton).fast([program.values])
    never = Race(tuple(0.0 * r for r in full.returns), min_episodes=2, margin=0.002)
    beaten = Race(tuple(r + 500.0 for r in full.returns), min_episodes=2, margin=0.002)
    for mode in (FAST, REFEREE):
        ran_all, raced = executor.evaluate([evaluator.request(program.skeleton, program.values, mode=mode, race=race) for race in (never, beaten)])
        assert ran_all.returns == full.returns and not ran_all.raced_out
        assert raced.raced_out and 2 <= len(raced.returns) < 10 and raced.returns == full.returns[: len(raced.returns)]


def test_the_first_failing_episode_fails_the_evaluation_in_both_modes(pendulum):
    """Run side by side, a later episode fails first (at step 20, an earlier one at step 600):
    the referee still reports what running the episodes in order reports."""
    executor, evaluator = pendulum
    lucks = [np.random.RandomState(seed % 2**32).uniform() for seed in evaluator.seeds]  # as each instance draws LUCK
    failing = [index for index, luck in enumerate(lucks) if luck > 0.7 or luck < 0.3]
    first = failing[0]
    assert lucks[first] > 0.7 and any(lucks[index] < 0.3 for index in failing[1:])  # the case this test is about
    program = parametrize(FAILS_IN_SOME_EPISODES)
    fast, refereed = executor.evaluate([evaluator.request(program.skeleton, program.values, mode=mode) for mode in (FAST, REFEREE)])
    assert fast.failure == "exception: ValueError: unlucky (step 599)" and len(fast.returns) == first
    assert (refereed.returns, refereed.failure) == (fast.returns, fast.failure)


def test_colmo_optimize_scores_the_counter_alike_with_any_worker_count(tmp_path):
    """The issue's case: with one worker the 10 episodes were one call sequence (NaN at the
    10,000th call, a failure), with two they were split (a score)."""
    policy = tmp_path / "counter.py"
    policy.write_text(COUNTER)
    summaries = []
    for workers in (1, 3):
        run = run_colmo("colmo.optimize", "task=pendulum", f"policy_file={policy}", "gfo=none", "heldout.episodes=2", f"executor.workers={workers}", cwd=tmp_path)
        assert run.returncode == 0, run.stderr
        summaries.append(last_json_line(run.stdout))
    assert all(summary["failure"] is None and summary["episodes"] == 10 for summary in summaries), summaries
    assert summaries[0]["returns"] == summaries[1]["returns"] and summaries[0]["score"] == summaries[1]["score"]


def test_racing_over_more_episodes_than_a_lockstep_batch_decides_on_the_episodes_run(pendulum):
    """More episodes than the referee steps side by side: after each batch, racing decides on the
    returns of the episodes run so far, never on those of the batches still to run. (Against an
    incumbent that the candidate beats on every episode, racing never gives up; counted as
    returns of 0, the episodes not yet run made it give up.)"""
    from colmo.sandbox.referee import LOCKSTEP

    executor, evaluator = pendulum
    program = parametrize(INTEGRATOR)
    seeds = tuple(range(4 * LOCKSTEP))
    [full] = executor.evaluate([evaluator.request(program.skeleton, program.values, seeds=seeds)])
    beaten = Race((min(full.returns) - 1.0,) * len(seeds), min_episodes=2, margin=0.0)
    assert beaten.gives_up(full.returns[:LOCKSTEP] + (0.0,) * (2 * LOCKSTEP))  # what the episodes not run would have said
    for mode in (FAST, REFEREE):
        [raced] = executor.evaluate([evaluator.request(program.skeleton, program.values, seeds=seeds, mode=mode, race=beaten)])
        assert (raced.returns, raced.failure, raced.raced_out) == (full.returns, None, False), mode
