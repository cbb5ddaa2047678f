"""`search.steady_state`: instead of `llm.batch_size` children a prompt and `search.queue_size`
batches in flight, each idle worker gets one child, from a prompt drawn when it frees
(asynchronous steady-state evolution, as `search.fill` draws), and the programs still enter the
database in order."""

from __future__ import annotations

from collections import Counter

from conftest import compose

from colmo.record import PENDING
from colmo.search import Search
from colmo.store import STORE_FILE, ProgramStore

TINY = ("task=pendulum", "llm=mutate", "gfo.budget=4", "task.episodes=2", "tracker=none", "search.progress=false", "heldout.episodes=2",
        "finish.render=false", "finish.simplify=false")


def searched(run_dir, *overrides: str):
    """The summary and the stored samples (the starter left out) of a search."""
    summary = Search(compose("search", *TINY, *overrides), run_dir).run()
    store = ProgramStore(run_dir / STORE_FILE)
    try:
        return summary, [record for record in store.records() if record.sample >= 0]
    finally:
        store.close()


def test_each_idle_worker_gets_a_child_of_its_own(tmp_path):
    summary, records = searched(tmp_path / "run", "search.steady_state=true", "executor.workers=2", "search.max_samples=16")
    assert summary.stop_reason == "max_samples" and summary.samples == 16 == sum(record.model_calls for record in records)
    assert not [record for record in records if record.status == PENDING]
    per_batch = Counter(record.batch for record in records)
    assert max(per_batch.values()) <= 2 and len(per_batch) >= 8, per_batch
    # Without it, each prompt gives llm.batch_size children.
    _, queued = searched(tmp_path / "queued", "executor.workers=2", "search.max_samples=16")
    assert set(Counter(record.batch for record in queued).values()) == {4}


def test_with_one_worker_a_steady_state_run_is_a_function_of_its_seed(tmp_path):
    # One worker: each child is drawn once the one before it is in, whatever the timing.
    runs = [searched(tmp_path / name, "search.steady_state=true", "executor.workers=1", "search.max_samples=8")[1] for name in ("a", "b")]
    assert [(r.sample, r.batch, r.code, r.score) for r in runs[0]] == [(r.sample, r.batch, r.code, r.score) for r in runs[1]]
    assert set(Counter(record.batch for record in runs[0]).values()) == {1}


def test_a_steady_queue_keeps_programs_in_flight_beyond_the_workers(tmp_path):
    summary, records = searched(tmp_path / "run", "search.steady_state=true", "search.steady_queue=1", "executor.workers=1", "search.max_samples=8")
    assert summary.stop_reason == "max_samples" and summary.samples == 8 == sum(record.model_calls for record in records)
    assert not [record for record in records if record.status == PENDING]
    # One worker and one program queued: two children drawn at the start (without the queue, one), never more than two in flight.
    sizes = Counter(record.batch for record in records)
    assert sizes[min(sizes)] == 2 and max(sizes.values()) <= 2, sizes


def test_a_program_that_takes_every_worker_has_them_to_itself(tmp_path):
    # gfo.workers=2 on 2 workers: one program slot, so one child at a time, however many workers are idle.
    summary, records = searched(tmp_path / "run", "search.steady_state=true", "executor.workers=2", "gfo.workers=2", "search.max_samples=6")
    assert summary.stop_reason == "max_samples"
    assert set(Counter(record.batch for record in records).values()) == {1}
