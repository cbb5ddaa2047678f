"""The model's share of the time beside the filler (`search.model_share=by_yield`): probability
matching on each generator's island bests per CPU-second, a floor under the model's share, and
the pause after a call that gives it that share."""

from __future__ import annotations

import time

import pytest

from colmo.model_share import PRIOR_CPU_S, ModelShare, cpu_seconds, island_bests_per_cpu_second, model_share, pause_after


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


def test_the_pause_after_a_call_gives_the_model_its_share_of_the_time():
    assert pause_after(30.0, 1.0) == 0.0
    assert pause_after(30.0, 0.5) == pytest.approx(30.0)
    assert pause_after(30.0, 0.1) == pytest.approx(270.0)  # 30 s calling in every 300


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
    assert pacing.pauses_until - before >= pause_after(60.0, 0.1) == pytest.approx(540.0)
    without_filler = ModelShare("by_yield", 0.1)
    without_filler.called(OnCores(1), "model", 60.0, None, by_generator)
    assert not without_filler.paused()
