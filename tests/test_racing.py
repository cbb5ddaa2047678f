"""Racing in the GFO (`gfo.racing`, `colmo.racing.Race`): the rule on constructed returns, its
place in tuning (a raced-out candidate never becomes the best), and racing on and off in real
tuning runs through sandboxed workers, `colmo-optimize` included."""

from __future__ import annotations

import dataclasses
import statistics

import pytest
from conftest import EXAMPLES, compose, last_json_line, run_colmo

from colmo.evaluation import Evaluation
from colmo.optimize.tune import CandidateEvaluator, optimize_program, tune
from colmo.racing import Race

# An incumbent's returns on 10 episodes, as a task would give them: they vary by episode.
INCUMBENT = (100.0, 90.0, 110.0, 95.0, 105.0, 100.0, 98.0, 102.0, 97.0, 103.0)


def race(min_episodes: int = 2, margin: float = 0.002, incumbent: tuple[float, ...] = INCUMBENT) -> Race:
    return Race(incumbent, min_episodes, margin)


def shifted(by: float, k: int) -> list[float]:
    return [r + by for r in INCUMBENT[:k]]


# -- the rule ------------------------------------------------------------------------------------


def test_a_candidate_consistently_worse_on_the_same_episodes_gives_up_after_two():
    # 20 and 19 below the incumbent on the same seeds: the returns vary by 20 across episodes,
    # their paired differences by 1.
    assert race().gives_up([80.0, 71.0])


def test_a_candidate_that_is_better_or_noisy_runs_on():
    assert not race().gives_up(shifted(+5.0, 2))
    assert not race().gives_up(shifted(+0.5, 9))
    assert not race().gives_up([70.0, 115.0])  # -30 then +25: the test cannot tell yet


def test_evidence_accumulates_over_the_episodes():
    differences = [-12.0, 4.0, -10.0, -6.0, -9.0, -7.0]
    returns = [i + d for i, d in zip(INCUMBENT, differences)]
    decisions = [race().gives_up(returns[:k]) for k in range(1, len(returns) + 1)]
    assert decisions == [False, False, False, True, True, True]


def test_a_tie_stops_only_with_a_margin():
    assert race(margin=0.002).gives_up(list(INCUMBENT[:2]))
    assert not race(margin=0.0).gives_up(list(INCUMBENT[:2]))
    # Trailing by 0.1 % on every episode: within a 0.2 % margin it is a tie, without one it loses.
    slightly = [r * 0.999 for r in INCUMBENT[:3]]
    assert race(margin=0.0).gives_up(slightly) and race(margin=0.002).gives_up(slightly)
    assert not race(margin=0.002).gives_up([r * 1.003 for r in INCUMBENT[:3]])


def test_one_episode_never_decides():
    assert not Race(INCUMBENT, 1, 0.002).gives_up([0.0])
    assert Race(INCUMBENT, 1, 0.002).gives_up([0.0, 0.0])


def test_min_episodes_are_always_run():
    terrible = [0.0] * 10
    assert [race(min_episodes=4).gives_up(terrible[:k]) for k in range(1, 6)] == [False, False, False, True, True]


def test_never_on_the_last_episode():
    terrible = [0.0] * 10
    assert race().gives_up(terrible[:9])
    assert not race().gives_up(terrible)  # all episodes run: a full evaluation, not a raced-out one
    assert not race(min_episodes=10).gives_up(terrible[:9])


def test_racing_waits_while_the_incumbent_fails_some_episodes():
    # It catches the ball in some episodes only: a candidate that does worse on the first ones
    # may still catch it where the incumbent does not.
    uneven = (900.0, 850.0, 0.0, 880.0, 0.0, 910.0, 870.0, 0.0, 890.0, 860.0)
    assert race(incumbent=uneven).uneven and not race().uneven
    assert not any(race(incumbent=uneven).gives_up([0.0] * k) for k in range(1, 10))
    # Once it does well everywhere, racing resumes.
    even = tuple(r or 600.0 for r in uneven)
    assert not race(incumbent=even).uneven and race(incumbent=even).gives_up([0.0, 0.0])


def test_the_estimate_pairs_the_episodes_run_with_the_incumbents():
    # The first two episodes are easy: their mean flatters any candidate; the paired estimate does not.
    incumbent = (950.0, 950.0, 700.0, 700.0, 700.0, 700.0, 700.0, 700.0, 700.0, 700.0)
    candidate = [900.0, 900.0]
    assert race(incumbent=incumbent).gives_up(candidate)
    assert statistics.mean(candidate) > statistics.mean(incumbent)
    assert race(incumbent=incumbent).estimate(candidate) == pytest.approx(statistics.mean(incumbent) - 50.0)
    assert race(incumbent=incumbent).estimate([650.0, 690.0], episodes=[2, 5]) == pytest.approx(750.0 - 30.0)


# -- in tuning, with a scripted evaluator (no program runs) -------------------------------------


class ScriptedEvaluator:
    """Evaluations without any program: the program's own constants score 10 on every episode
    (the referee's score); every other candidate is raced out after two episodes that score 50
    (a mean over the episodes run above the incumbent's)."""

    def __init__(self):
        self.races: list[Race] = []

    def referee(self, params):
        return Evaluation((10.0,) * 10, steps=10_000)

    def fast(self, params_list, race=None):
        self.races.append(race)
        return [Evaluation((50.0, 50.0), steps=2_000, raced_out=True) for _ in params_list]


def test_a_raced_out_candidate_never_becomes_the_best():
    gfo = compose("optimize", "gfo=oneplusone", "gfo.budget=6", "policy_file=unused.py").gfo
    scripted = ScriptedEvaluator()
    tuning = tune(scripted, [1.0, 2.0], gfo, seed=0)
    assert tuning.params == (1.0, 2.0) and tuning.evaluation.returns == (10.0,) * 10
    assert tuning.evaluations == 6 and tuning.raced_out == 5 and tuning.steps == 10_000 + 5 * 2_000
    assert all(race.incumbent == (10.0,) * 10 for race in scripted.races)  # every candidate raced against the best


# -- real tuning runs ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def pendulum():
    """Two sandbox workers, the pendulum's calibrated evaluator on 5 episodes and the mistuned
    example program."""
    from colmo.executor import LocalExecutor
    from colmo.heldout import task_evaluator
    from colmo.intake import read_policy_file

    cfg = compose("optimize", "task=pendulum", "task.episodes=5", "gfo=oneplusone", "policy_file=unused.py")
    with LocalExecutor(2) as executor:
        spec, evaluator = task_evaluator(cfg.task, cfg.executor, executor, seed=0)
        program = read_policy_file(str(EXAMPLES / "pendulum_mistuned.py"), spec.allowed_imports)
        yield executor, evaluator, program, cfg.gfo


def tuned(pendulum, racing: bool, budget: int = 40, chunks: int = 1):
    executor, evaluator, program, gfo = pendulum
    evaluate = CandidateEvaluator(executor, evaluator, program.skeleton, chunks)
    return optimize_program(program, evaluate, dataclasses.replace(gfo, racing=racing, budget=budget), seed=0)


def test_racing_simulates_fewer_steps_and_reports_scores_over_all_episodes(pendulum):
    off, on = tuned(pendulum, racing=False), tuned(pendulum, racing=True)
    episodes = len(pendulum[1].seeds)
    assert off.raced_out == 0 and off.steps == off.evaluations * episodes * 1000
    assert on.raced_out > 0 and on.steps < off.steps and on.evaluations == off.evaluations
    for result in (off, on):  # the referee's score, over every episode, of the code shown
        assert result.failure is None and len(result.evaluation.returns) == episodes and not result.evaluation.raced_out
        assert result.score > result.initial.score + 50


def test_spreading_episodes_over_workers_gives_the_same_result(pendulum):
    one, two = tuned(pendulum, racing=False, budget=15), tuned(pendulum, racing=False, budget=15, chunks=2)
    assert (one.params, one.evaluation.returns, one.steps, one.evaluations) == (two.params, two.evaluation.returns, two.steps, two.evaluations)


def test_an_evaluation_spread_over_workers_reports_their_time(pendulum):
    executor, evaluator, program, _ = pendulum
    whole = CandidateEvaluator(executor, evaluator, program.skeleton).referee(program.values)
    spread = CandidateEvaluator(executor, evaluator, program.skeleton, 2).referee(program.values)
    assert spread.returns == whole.returns and spread.steps == whole.steps
    assert spread.seconds > 0  # the two parts' time (it was dropped: 0)


@pytest.mark.slow
def test_colmo_optimize_reports_the_steps_simulated(tmp_path):
    """tests/test_optimize_cli.py checks the same figures on its oneplusone (racing) and bo (no racing) runs."""
    common = (f"policy_file={EXAMPLES / 'pendulum_mistuned.py'}", "gfo.budget=10", "task.episodes=3", "heldout.episodes=3", "executor.workers=2")
    off = run_colmo("colmo.optimize", *common, "gfo.racing=false", cwd=tmp_path)
    on = run_colmo("colmo.optimize", *common, cwd=tmp_path)  # racing: on by default for the (1+1)-ES
    assert off.returncode == 0 and on.returncode == 0, off.stderr + on.stderr
    off, on = last_json_line(off.stdout), last_json_line(on.stdout)
    assert off["steps"] == off["evaluations"] * 3 * 1000 and off["raced_out"] == 0
    assert isinstance(on["steps"], int) and 0 < on["steps"] <= on["evaluations"] * 3 * 1000
    assert len(on["returns"]) == 3  # the reported score is over all episodes
