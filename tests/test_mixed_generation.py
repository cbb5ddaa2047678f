"""One search, two generators (`search.fill=mutate`): while a slow model's call is in flight,
colmo's embedded mutation keeps idle workers busy in the same database, so the model is shown
what mutation found; every sample records which generator made it, and the summary splits
the results by generator."""

from __future__ import annotations

import sqlite3
import threading

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
    cfg = compose("search", "search.fill=mutate", "search.max_samples=40", "llm.batch_size=1", "search.queue_size=1", "database.num_islands=1", *TINY)
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
