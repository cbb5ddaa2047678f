"""One search, two generators (`search.fill=mutate`): while a slow model's call is in flight,
colmo's embedded mutation keeps idle workers busy in the same database, so the model is shown
what mutation found; every sample records which generator made it, and the summary splits
the results by generator."""

from __future__ import annotations

import logging
import re
import sqlite3
import threading
import time

from conftest import compose, refused

from colmo.__main__ import main as colmo
from colmo.generate import Generation, Generator
from colmo.search import Search

TINY = ("gfo.budget=4", "task.episodes=2", "tracker=none", "executor.workers=2", "search.progress=false", "heldout.episodes=2",
        "finish.render=false", "finish.simplify=false")
ANSWERS = [f"import numpy as np\n\ndef policy(obs):\n    return {k}.0 * obs[2] - np.sin(obs[{k % 2}])\n" for k in range(1, 50)]


class SlowModel(Generator):
    """A language model as a search meets one: a second per call; records the prompts it was given."""

    def __init__(self) -> None:
        super().__init__(cfg=None, seed=0)
        self.prompts, self.calls, self.cancelled = [], 0, threading.Event()

    def generate(self, prompt, n):
        self.prompts.append(prompt)
        self.cancelled.wait(1.0)
        self.calls += 1
        return [Generation(ANSWERS[(self.calls + i) % len(ANSWERS)], "slow-model:test", completion_tokens=20, seconds=1.0) for i in range(n)]

    def cancel(self) -> None:
        self.cancelled.set()


def test_mutation_fills_the_workers_while_the_model_thinks_and_the_model_is_shown_its_programs(tmp_path):
    cfg = compose(
        "search", "search.fill=mutate", "search.model_share=always", "search.max_samples=40", "llm.batch_size=1", "search.queue_size=1",
        "database.num_islands=1", *TINY,
    )
    model = SlowModel()
    summary = Search(cfg, tmp_path / "run", generator=model).run()
    with sqlite3.connect(tmp_path / "run" / "programs.db") as connection:
        rows = connection.execute("SELECT generator, status, key, model_calls FROM samples WHERE sample >= 0").fetchall()
    made_by = {generator.split(":")[0] for generator, *_ in rows}
    assert made_by == {"mutate", "slow-model"}, made_by
    split = summary.by_generator
    assert set(split) == {"mutate", "slow-model"}
    assert sum(entry["samples"] for entry in split.values()) == summary.samples == sum(row[3] for row in rows)
    assert split["mutate"]["programs_evaluated"] >= 1 and split["mutate"]["samples"] > split["slow-model"]["samples"]
    mutated = {key for generator, status, key, _ in rows if generator == "mutate" and status == "evaluated"}
    shown = [prompt for prompt in model.prompts if mutated & set(prompt.parent_keys)]
    assert shown, "no prompt of the model showed a program mutation made"


def test_fill_names_a_generator_colmo_can_fill_with(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, line = refused(colmo, "search.fill=llamacpp")
    assert code == 2 and "search.fill must be null or mutate, got 'llamacpp'" in line


class UnhelpfulModel(SlowModel):
    """A slow model that never writes a program, on one core; records when each call began and when
    each call it answered ended."""

    def __init__(self) -> None:
        super().__init__()
        self.began, self.ended = [], []

    def cores(self) -> int:
        return 1

    def generate(self, prompt, n):
        self.began.append(time.perf_counter())
        if not self.cancelled.wait(0.5):  # a call the search abandons (its last sample came meanwhile) is neither answered nor paced
            self.ended.append(time.perf_counter())
        return [Generation("I cannot help with that.", "unhelpful-model:test", completion_tokens=5, seconds=0.5) for _ in range(n)]


def test_by_yield_the_default_a_model_that_sets_no_island_best_pauses_while_mutation_has_the_workers(tmp_path, caplog):
    cfg = compose(
        "search", "search.fill=mutate", "search.min_model_share=0.2", "search.max_samples=40",
        "search.duplicate_retries=0",
        "llm.batch_size=1", "search.queue_size=1", "database.num_islands=1", *TINY,
    )
    model = UnhelpfulModel()
    with caplog.at_level(logging.INFO, logger="colmo.search"):
        summary = Search(cfg, tmp_path / "run", generator=model).run()
    said = [re.search(r"model share ([\d.]+) .*its next call in ([\d.]+) s", message) for message in caplog.messages]
    shares = [(float(found[1]), float(found[2])) for found in said if found]
    assert len(shares) == len(model.ended) >= 2
    assert all(0.2 <= share <= 1 for share, _ in shares)
    # Each call begins no sooner than the pause said after the one before it.
    for (_, pause), ended, began in zip(shares, model.ended, model.began[1:]):
        assert began - ended >= pause - 0.05
    split = summary.by_generator
    assert split["mutate"]["island_bests"] >= 1 and split["unhelpful-model"]["island_bests"] == 0
    assert split["unhelpful-model"]["generation_seconds"] >= 0.5 * split["unhelpful-model"]["samples"]
    assert split["mutate"]["evaluation_seconds"] > 0
    # Once mutation has set an island best, the model's yield is below mutation's: it calls for less than half the time.
    assert min(share for share, _ in shares) < 0.5


def test_model_share_names_a_pacing_and_a_share_in_range(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, line = refused(colmo, "search.fill=mutate", "search.model_share=sometimes")
    assert code == 2 and "search.model_share must be one of always, by_yield, got 'sometimes'" in line
    code, line = refused(colmo, "search.fill=mutate", "search.model_share=by_yield", "search.min_model_share=0")
    assert code == 2 and "search.min_model_share must be in (0, 1], got 0" in line
