"""The ledger of settled samples: counted, registered and noted as a new best in sample order, island
bests marked against the island's programs before them; a replay of a store rebuilds the same
ledger and returns what was left to evaluate and the next sample and batch numbers."""

from __future__ import annotations

from colmo.config import DatabaseConfig
from colmo.database import ProgramDatabase, StoredProgram
from colmo.ledger import Ledger
from colmo.record import DUPLICATE, EVALUATED, FAILED, INTERRUPTED, PENDING, Counters, SampleRecord

STARTER = StoredProgram("starter", "def policy(obs):\n    return 0.0\n", 10.0, 0, -1)


def ledger(islands: int = 2) -> Ledger:
    database = ProgramDatabase(DatabaseConfig(num_islands=islands, reset_every=0), STARTER, 0)
    return Ledger(database, Counters())


def record(sample: int, status: str, score: float | None = None, island: int = 0, batch: int = 0, key: str | None = None, generator: str = "mutate") -> SampleRecord:
    code = f"def policy(obs):\n    return {sample}.0\n"
    return SampleRecord(
        sample, batch, status, island, (), generator, code, key=key or f"k{sample}", code=code if status == EVALUATED else None, score=score,
    )


def test_settled_samples_are_counted_registered_and_new_bests_noted():
    books = ledger()
    for settled in (
        record(0, EVALUATED, 12.0, island=0),  # above the starter on island 0: an island best and a new best
        record(1, EVALUATED, 11.0, island=1, generator="llamacpp:model.gguf"),  # island 1's best, not the overall best
        record(2, EVALUATED, 11.5, island=0),  # below island 0's best
        record(3, FAILED, island=1, key="broken"),
        record(4, DUPLICATE, island=0, key="k0"),
        record(5, EVALUATED, 20.0, island=1, generator="llamacpp:model.gguf"),
    ):
        books.settle(settled)
    assert books.best_so_far == [(0, 10.0), (1, 12.0), (6, 20.0)]  # (samples settled, best) at each new best
    assert books.database.best.key == "k5" and books.database.best_per_island == [12.0, 20.0]
    assert books.database.is_known("broken")  # a failed structure is not generated again
    by_generator = books.counters.by_generator
    assert by_generator["mutate"]["island_bests"] == 1 and by_generator["mutate"]["samples"] == 4
    assert by_generator["llamacpp"]["island_bests"] == 2 and by_generator["llamacpp"]["best_score"] == 20.0
    assert books.counters.by_status == {EVALUATED: 4, FAILED: 1, DUPLICATE: 1}


def test_an_interrupted_sample_is_counted_but_not_marked_seen():
    books = ledger()
    books.settle(record(0, INTERRUPTED, key="cut"))
    assert books.counters.by_status[INTERRUPTED] == 1 and not books.database.is_known("cut")


def test_a_replay_rebuilds_the_ledger_and_returns_what_is_left_to_evaluate():
    stored = [
        record(0, EVALUATED, 12.0, batch=0),
        record(1, EVALUATED, 13.0, island=1, batch=0),
        record(2, INTERRUPTED, batch=1, key="again"),
        record(3, EVALUATED, 14.0, batch=1, key="k0"),  # the structure of sample 0 again (an older colmo's keys): counted only
        record(4, PENDING, batch=2, key="waiting"),
    ]
    live = ledger()
    for settled in stored:
        if settled.status not in (INTERRUPTED, PENDING) and settled.sample != 3:
            live.settle(settled)

    books = ledger()
    replayed = books.replay(stored, STARTER.key)
    assert [r.sample for r in replayed.to_evaluate] == [2, 4]
    assert (replayed.next_sample, replayed.next_batch) == (5, 3)
    assert books.database.best.key == "k1" and books.database.best_per_island == live.database.best_per_island
    assert books.best_so_far == live.best_so_far
    assert books.counters.samples == 3 and books.counters.by_status[EVALUATED] == 3  # sample 3 counted, not registered


def test_islands_reset_at_the_end_of_a_batch_as_in_the_run_a_replay_rebuilds():
    def books() -> Ledger:
        database = ProgramDatabase(DatabaseConfig(num_islands=2, reset_every=2), STARTER, 0)
        return Ledger(database, Counters())

    stored = [record(0, EVALUATED, 12.0, island=0, batch=0), record(1, EVALUATED, 30.0, island=1, batch=0), record(2, EVALUATED, 13.0, island=0, batch=1)]
    live = books()
    live.settle(stored[0])
    live.settle(stored[1])
    assert live.end_batch() == [0]  # two samples: the weaker island starts again from the best program
    live.settle(stored[2])
    live.end_batch()
    replayed = books()
    replayed.replay(stored, STARTER.key)
    assert replayed.database.best_per_island == live.database.best_per_island
    assert replayed.best_so_far == live.best_so_far
