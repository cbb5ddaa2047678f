"""What a search records (`colmo.record`): a sample's record and back, and the one `Totals`
that the counters make for every report."""

from __future__ import annotations

import dataclasses

import pytest

from colmo.generate import Generation, PromptForm
from colmo.load import LoadMeter
from colmo.record import DUPLICATE, EVALUATED, FAILED, INTERRUPTED, PENDING, UNUSABLE, Counters, Elapsed, Sample, SampleRecord


def sample(index: int, calls: int = 1) -> Sample:
    generation = Generation("def policy(obs):\n    return 0.0\n", "mutate", 10, 20 * calls, 0.5 * calls, calls)
    return Sample(index, index // 2, 1, ("parent",), generation)


def test_a_pending_record_gives_back_the_sample_it_was_made_from():
    assert SampleRecord.of(sample(3, calls=2), PENDING).as_sample() == sample(3, calls=2)


def test_a_pending_chat_answer_keeps_the_code_its_prompt_showed():
    # A resumed run reads it again, and it may call what its prompt showed.
    shown = "def policy_v0(obs):\n    return 0.0"
    made = dataclasses.replace(sample(4), generation=dataclasses.replace(sample(4).generation, form=PromptForm.CHAT, context=shown))
    assert SampleRecord.of(made, PENDING).as_sample() == made


def test_a_pending_completion_keeps_the_prompt_it_continues():
    prompt = "def policy_v0(obs):\n    return 0.0\n\n\ndef policy_v1(obs):\n"
    made = dataclasses.replace(sample(5), generation=dataclasses.replace(sample(5).generation, text="    return 1.0\n", form=PromptForm.COMPLETION, context=prompt))
    record = SampleRecord.of(made, PENDING)
    assert (record.prompt_prefix, record.prompt_shown) == (prompt, "")
    assert record.as_sample() == made


def test_code_on_its_own_has_no_prompt_context():
    with pytest.raises(ValueError, match="no prompt context"):
        Generation("def policy(obs):\n    return 0.0\n", "mutate", context="def policy_v0(obs): ...")


def test_totals_count_model_calls_records_by_status_and_rates():
    counters = Counters()
    # Six answers kept, eight model calls: one evaluated program was the third answer of its
    # prompt (two duplicates thrown away before it), and one sample is a duplicate itself.
    statuses = [(EVALUATED, 3), (EVALUATED, 1), (FAILED, 1), (UNUSABLE, 1), (DUPLICATE, 1), (INTERRUPTED, 1)]
    for index, (status, calls) in enumerate(statuses):
        counters.count(SampleRecord.of(sample(index, calls), status))
    totals = counters.totals(Elapsed(seconds=10.0, generator_seconds=4.0, evaluator_seconds=15.0), workers=2)
    assert (totals.samples, totals.programs_evaluated, totals.failures, totals.unusable_outputs) == (8, 2, 1, 1)
    assert (totals.duplicates_skipped, totals.interrupted) == (1, 1)
    assert totals.valid_program_rate == pytest.approx(2 / 4)  # duplicates and interrupted samples aside
    assert totals.duplicate_rate == pytest.approx(3 / 8)  # two regenerated, one recorded
    assert totals.tokens_per_second == pytest.approx(20 / 0.5)
    assert (totals.generator_busy, totals.evaluator_busy, totals.seconds) == (pytest.approx(0.4), pytest.approx(0.75), 10.0)


def test_totals_before_anything_happened_are_zeros():
    totals = Counters().totals(Elapsed(), workers=2)
    assert totals.samples == 0 and totals.valid_program_rate == totals.evaluator_busy == totals.evaluations_per_second == 0.0


def test_the_load_is_the_mean_load_average_over_the_run_resumed_processes_included():
    readings = iter([(2.0, 9.0, 9.0), (4.0, 9.0, 9.0), (7.0, 1.5, 7.0), (7.0, 7.0, 0.5)])
    meter = LoadMeter(read=lambda: next(readings))
    assert meter.load_seconds(10.0) == 20.0 and meter.load_seconds(10.0) == 20.0  # no time passed: no reading
    assert meter.load_seconds(20.0) == 60.0  # the 1-minute average: 2.0 over the first ten seconds, 4.0 over the next ten
    # readings minutes apart stand for their gap with the 5-minute average, then the 15-minute one
    assert meter.load_seconds(320.0) == 60.0 + 1.5 * 300 and meter.load_seconds(1320.0) == 510.0 + 0.5 * 1000
    this_process = Elapsed(seconds=20.0, load_seconds=60.0)
    assert Counters().totals(this_process, workers=2).load == pytest.approx(3.0)
    earlier = Elapsed(seconds=40.0, load_seconds=40.0)  # an earlier process of a resumed run, at load 1.0
    assert Counters().totals(earlier.plus(this_process), workers=2).load == pytest.approx(100 / 60)
