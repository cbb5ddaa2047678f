"""The settled samples' ledger: each sample, once its outcome is in and in sample order, counted
(`Counters`: by status and by generator, island bests included), registered in the island database
if it was evaluated, and a new overall best noted (`best_so_far`, what the report plots); a
resumed run's ledger is rebuilt by replaying its store in the same order. Islands reset only at a
batch's end (`end_batch`), so a run and its resumed continuation reset them alike."""

from __future__ import annotations

import dataclasses
from typing import Iterable

from colmo.database import ProgramDatabase, StoredProgram
from colmo.record import EVALUATED, INTERRUPTED, TO_EVALUATE_AGAIN, Counters, SampleRecord


@dataclasses.dataclass
class Replayed:
    """What a replay of an earlier run's store leaves to the search: the samples it left pending or
    interrupted, to evaluate first, and the numbers its next sample and batch take."""

    to_evaluate: list[SampleRecord]
    next_sample: int = 0
    next_batch: int = 0


class Ledger:
    """The counters, the database and the best-so-far curve, kept in step by `settle`."""

    def __init__(self, database: ProgramDatabase, counters: Counters):
        self.database = database
        self.counters = counters
        self.best_so_far: list[tuple[int, float]] = [(0, database.best.score)]

    def settle(self, record: SampleRecord) -> None:
        """Count one settled sample and register it in the database, in sample order."""
        database = self.database
        island_best = record.status == EVALUATED and record.score is not None and record.score > database.best_per_island[record.island]
        self.counters.count(record, island_best)
        if record.status == EVALUATED:
            before = database.best.score
            database.register(StoredProgram(record.key, record.code, record.score, record.island, record.sample, record.nodes, record.coverage))
            if database.best.score > before:
                self.best_so_far.append((self.counters.samples, database.best.score))
        elif record.key and record.status != INTERRUPTED:
            database.mark_seen(record.key)

    def end_batch(self) -> list[int]:
        """A batch's samples are all settled: the islands due for a reset are reset (their indices)."""
        return self.database.on_sample(self.counters.samples)

    def replay(self, records: Iterable[SampleRecord], starter_key: str) -> Replayed:
        """Settle an earlier run's stored samples (the starter's excepted) as that run did."""
        replayed, batch, registered = Replayed([]), None, {starter_key}
        for record in records:
            if batch is not None and record.batch != batch:
                self.end_batch()
            batch = record.batch
            if record.status in TO_EVALUATE_AGAIN:
                replayed.to_evaluate.append(record)
            elif record.status == EVALUATED and record.key in registered:
                self.counters.count(record)  # one structure under today's keys, evaluated twice by an older colmo: the first stays
            else:
                self.settle(record)
            if record.status == EVALUATED:
                registered.add(record.key)
            replayed.next_sample, replayed.next_batch = record.sample + 1, record.batch + 1
        if batch is not None:
            self.end_batch()
        return replayed
