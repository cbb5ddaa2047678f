"""The model's share of the time beside the filler (`search.model_share=by_yield`): probability
matching on each generator's island bests per CPU-second, a floor under the model's share, and
the pause after a call that gives it that share."""

from __future__ import annotations

import time

import pytest

from colmo.model_share import PRIOR_CPU_S, ModelShare, cpu_seconds, island_bests_per_cpu_second, model_share, next_call_at


def entry(island_bests: int, evaluation_seconds: float, generation_seconds: float = 0.0) -> dict:
    return {"island_bests": island_bests, "evaluation_seconds": evaluation_seconds, "generation_seconds": generation_seconds}


def test_equal_yields_share_the_time_equally_and_nothing_measured_yet_is_equal():
    assert model_share({}, 1, {}, 1, floor=0.1) == pytest.approx(0.5)
    assert model_share(entry(5, 400.0), 0, entry(5, 400.0), 0, floor=0.1) == pytest.approx(0.5)


def test_the_share_is_the_models_part_of_the_two_yields():
    model, filler = entry(9, 900.0), entry(1, 900.0)  # 10 and 2 island bests (with the prior one) in 1000 CPU-seconds
    assert island_bests_per_cpu_second(model, 0) == pytest.approx(10 / (900.0 + PRIOR_CPU_S))
    assert model_share(model, 0, filler, 0, floor=0.1) == pytest.approx(10 / 12)


def test_a_model_that_yields_less_is_held_at_the_floor():
    # The mixed pendulum run of seed 0 (docs/mixed-generation.md): mutation 92 island bests in
    # 3288 CPU-seconds, the model 1 in 375 s of evaluation and 1549 s of calls on one core.
    mutation, model = entry(92, 3271.0, 17.0), entry(1, 375.0, 1549.0)
    assert model_share(model, 1, mutation, 1, floor=0.1) == 0.1
    assert model_share(model, 1, mutation, 1, floor=0.01) == pytest.approx((2 / 2024) / (2 / 2024 + 93 / 3388))


def test_a_model_on_this_machines_cores_is_charged_for_its_calls():
    model, filler = entry(3, 100.0, 400.0), entry(3, 100.0)
    assert cpu_seconds(model, 2) == 900.0 and cpu_seconds(model, 0) == 100.0
    assert model_share(model, 2, filler, 1, floor=0.01) < model_share(model, 1, filler, 1, floor=0.01) < model_share(model, 0, filler, 1, floor=0.01)


def test_the_next_call_waits_until_the_calls_so_far_are_the_models_share_of_the_time():
    assert next_call_at(100.0, 30.0, 1.0) == 130.0  # all the time: at once after a 30-s call begun at 100
    assert next_call_at(100.0, 30.0, 0.5) == pytest.approx(160.0)
    assert next_call_at(100.0, 30.0, 0.1) == pytest.approx(400.0)  # 30 s calling in every 300


class OnCores:
    """A generator as `ModelShare` sees one: the cores its calls keep busy."""

    def __init__(self, cores: int) -> None:
        self.n = cores

    def cores(self) -> int:
        return self.n


def test_by_yield_the_model_pauses_after_a_call_and_always_it_never_does():
    by_generator = {"model": entry(0, 100.0, 300.0), "mutate": entry(40, 900.0, 10.0)}
    always = ModelShare("always", 0.1)
    always.called(OnCores(1), "model", 60.0, OnCores(1), by_generator)
    assert not always.paused()
    pacing = ModelShare("by_yield", 0.1)
    pacing.filler_label = "mutate"
    before = time.perf_counter()
    pacing.called(OnCores(1), "model", 60.0, OnCores(1), by_generator)
    assert pacing.paused()
    # Yields 1/500 against 41/1010: held at the floor, the model waits nine times its call.
    assert pacing.pauses_until - before == pytest.approx(540.0, abs=1.0)
    without_filler = ModelShare("by_yield", 0.1)
    without_filler.called(OnCores(1), "model", 60.0, None, by_generator)
    assert not without_filler.paused()


class Clock:
    """A clock a test moves."""

    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


@pytest.mark.parametrize("floor", [0.1, 0.25])
def test_calls_of_any_length_take_the_models_share_of_the_time(floor):
    # A model held at its floor: calls of 150, 98, 220, 60 and 500 s (the 1.5B model's, with
    # its duplicates asked again) take `floor` of the time up to each next call, whatever each lasted.
    by_generator = {"model": entry(0, 100.0, 300.0), "mutate": entry(40, 900.0, 10.0)}
    clock = Clock()
    pacing = ModelShare("by_yield", floor, clock)
    pacing.filler_label = "mutate"
    began, calling = clock.now, 0.0
    for seconds in (150.0, 98.0, 220.0, 60.0, 500.0):
        clock.now += seconds
        calling += seconds
        pacing.called(OnCores(1), "model", seconds, OnCores(1), by_generator)
        assert pacing.paused()
        clock.now = pacing.pauses_until
        assert not pacing.paused()
        assert calling / (clock.now - began) == pytest.approx(floor)


def test_a_share_that_falls_makes_the_model_pay_for_its_earlier_calls():
    clock = Clock()
    pacing = ModelShare("by_yield", 0.1, clock)
    pacing.filler_label = "mutate"
    clock.now += 100.0
    pacing.called(OnCores(1), "model", 100.0, OnCores(1), {})  # nothing measured: half the time
    assert pacing.pauses_until == pytest.approx(clock.now + 100.0)
    clock.now = pacing.pauses_until + 10.0
    poor = {"model": entry(0, 100.0, 300.0), "mutate": entry(40, 900.0, 10.0)}
    pacing.called(OnCores(1), "model", 10.0, OnCores(1), poor)  # now at the floor: 110 s of calling in 1100
    assert pacing.pauses_until == pytest.approx(1000.0 + 1100.0)
