"""The programs database: island and cluster sampling, resets, dedup by structure, determinism."""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import replace

import pytest

from colmo.config import DatabaseConfig
from colmo.database import ProgramDatabase, StoredProgram
from colmo.program import measure

STARTER = StoredProgram("starter", "def policy(obs):\n    return 0.0\n", 0.0, 0, -1)


def code(lines: int) -> str:
    """A policy of `lines` lines as `measure` counts them."""
    return "def policy(obs):\n" + "    a = 1.0\n" * (lines - 2) + "    return a\n"


def program(key: str, score: float, island: int = 0, lines: int = 2, sample: int = 0) -> StoredProgram:
    return StoredProgram(key, code(lines), score, island, sample)


def database(seed: int = 0, **options) -> ProgramDatabase:
    return ProgramDatabase(DatabaseConfig(**{"num_islands": 1, "reset_every": 0, **options}), STARTER, seed)


def frequencies(draws: list[str]) -> dict[str, float]:
    return {key: count / len(draws) for key, count in Counter(draws).items()}


def test_code_helper_has_the_requested_length():
    assert [measure(code(n)).lines for n in (2, 5, 12)] == [2, 5, 12]


def test_every_island_starts_with_the_starter():
    db = database(num_islands=3)
    assert [db.programs(i) for i in range(3)] == [[replace(STARTER, island=i)] for i in range(3)]
    assert db.best_per_island == [0.0, 0.0, 0.0]
    assert db.island_sizes == [1, 1, 1] and db.n_programs == 3
    assert db.best == STARTER
    assert db.is_known("starter")
    selection = db.select()
    assert selection.programs == [replace(STARTER, island=selection.island)]


def test_selection_has_distinct_programs_in_ascending_score():
    db = database(functions_per_prompt=2, cluster_temperature_init=100.0)
    for key, score in (("a", 3.0), ("b", 1.0), ("c", 2.0)):
        db.register(program(key, score))
    pairs = set()
    for _ in range(300):
        selection = db.select()
        scores = [p.score for p in selection.programs]
        assert selection.island == 0 and len(scores) == 2 and scores[0] < scores[1]
        pairs.add(tuple(p.key for p in selection.programs))
    # A high temperature makes every pair of the four clusters show up.
    assert pairs == {("starter", "b"), ("starter", "c"), ("starter", "a"), ("b", "c"), ("b", "a"), ("c", "a")}


def test_selection_shows_fewer_programs_when_the_island_has_fewer_clusters():
    db = database(functions_per_prompt=3)
    assert [p.key for p in db.select().programs] == ["starter"]
    db.register(program("a", 1.0))
    db.register(program("b", 1.0))  # same score: same cluster, so still two clusters
    selection = db.select()
    assert len(selection.programs) == 2 and selection.programs[0].key == "starter"


def test_a_program_too_big_to_show_counts_but_is_never_shown():
    """A hostile or bloated program that scores best would fill every prompt past the model's
    context (a llama.cpp run then ends: 'prompt longer than the context')."""
    db = database(functions_per_prompt=2, max_shown_nodes=50, cluster_temperature_init=100.0)
    db.register(program("big", 900.0, lines=40))  # its own cluster, the best score
    db.register(program("small", 1.0))
    db.register(program("big-twin", 1.0, lines=40))  # shares small's cluster: small is shown for it
    assert db.best.key == "big"
    shown = {p.key for _ in range(200) for p in db.select().programs}
    assert shown == {"starter", "small"}
    alone = ProgramDatabase(DatabaseConfig(num_islands=1, reset_every=0, max_shown_nodes=1), STARTER, 0)  # nothing fits
    assert [p.key for p in alone.select().programs] == ["starter"]  # the island's smallest


def test_higher_scoring_clusters_are_sampled_more_often():
    db = database(functions_per_prompt=1, cluster_temperature_init=1.0, cluster_temperature_period=10**9)
    db.register(program("one", 1.0))
    db.register(program("two", 2.0))
    observed = frequencies([db.select().programs[0].key for _ in range(2000)])
    weights = {"starter": 1.0, "one": math.e, "two": math.e**2}  # softmax(score / 1.0)
    for key, weight in weights.items():
        assert observed[key] == pytest.approx(weight / sum(weights.values()), abs=0.03)


def test_cluster_temperature_divides_the_scores():
    db = database(functions_per_prompt=1, cluster_temperature_init=0.5, cluster_temperature_period=10**9)
    db.register(program("one", 1.0))
    observed = frequencies([db.select().programs[0].key for _ in range(2000)])
    assert observed["one"] == pytest.approx(1 / (1 + math.exp(-2.0)), abs=0.02)  # 0.881


def test_cluster_temperature_schedule():
    db = database(cluster_temperature_init=2.0, cluster_temperature_period=4)
    temperatures = [db.cluster_temperature(0)]  # one program: the starter
    for i in range(5):
        db.register(program(f"p{i}", float(i)))
        temperatures.append(db.cluster_temperature(0))
    assert temperatures == [1.5, 1.0, 0.5, 2.0, 1.5, 1.0]


def test_default_schedule_is_greedy_towards_the_best_cluster():
    db = database(functions_per_prompt=1)  # temperature 0.1: a score gap of 1 is a factor e^10
    db.register(program("better", 1.0))
    observed = [db.select().programs[0].key for _ in range(500)]
    assert observed.count("better") >= 495


@pytest.mark.parametrize("length_temperature", [1.0, 0.25])
def test_shorter_programs_are_preferred_within_a_cluster(length_temperature):
    db = database(functions_per_prompt=1, length_temperature=length_temperature)
    db.register(program("long", 10.0, lines=12))
    db.register(program("short", 10.0, lines=2))
    observed = frequencies([db.select().programs[0].key for _ in range(2000)])
    normalized_long = (12 - 2) / (12 + 1e-6)  # FunSearch: (length - min) / max
    expected_short = 1 / (1 + math.exp(-normalized_long / length_temperature))
    assert expected_short == pytest.approx({1.0: 0.697, 0.25: 0.966}[length_temperature], abs=1e-3)
    assert observed["short"] == pytest.approx(expected_short, abs=0.03)
    assert set(observed) == {"short", "long"}


def test_islands_evolve_independently():
    db = database(num_islands=3, functions_per_prompt=2)
    db.register(program("a", 5.0, island=1))
    db.register(program("a", 5.0, island=2))  # one structure may live on several islands
    db.register(program("b", 7.0, island=2))
    assert [[p.key for p in db.programs(i)] for i in range(3)] == [["starter"], ["starter", "a"], ["starter", "a", "b"]]
    assert db.best_per_island == [0.0, 5.0, 7.0]
    assert db.best.key == "b"
    shown = {0: set(), 1: set(), 2: set()}
    for _ in range(300):
        selection = db.select()
        assert all(p.island == selection.island for p in selection.programs)
        shown[selection.island].update(p.key for p in selection.programs)
    assert shown == {0: {"starter"}, 1: {"starter", "a"}, 2: {"a", "b"}}


def test_dedup_by_structure_key():
    db = database(num_islands=2)
    assert not db.is_known("x")
    db.mark_seen("x")  # e.g. a program that failed: known, but never stored
    assert db.is_known("x") and db.n_programs == 2
    db.register(program("y", 1.0, island=1))
    assert db.is_known("y") and not db.is_known("z")
    with pytest.raises(AssertionError, match="already on island 1"):
        db.register(program("y", 2.0, island=1))
    with pytest.raises(AssertionError, match="failed program"):
        db.register(program("z", float("nan")))
    assert db.n_programs == 3 and [db.is_known(key) for key in ("starter", "x", "y", "z")] == [True, True, True, False]


def test_best_is_the_first_program_to_reach_the_top_score():
    db = database(num_islands=2)
    db.register(program("a", 3.0, island=1, sample=1))
    db.register(program("b", 3.0, island=0, sample=2))
    db.register(program("c", 2.0, island=0, sample=3))
    assert db.best.key == "a" and db.best_per_island == [3.0, 3.0]
    assert db.n_programs == 5 and db.island_sizes == [3, 2] and all(db.is_known(key) for key in ("starter", "a", "b", "c"))


def four_islands(seed: int = 0) -> ProgramDatabase:
    """Islands with best scores 5, 1, 3, 0: islands 1 and 3 are the weaker half."""
    db = database(seed, num_islands=4, reset_every=10)
    db.register(program("five", 5.0, island=0))
    db.register(program("one", 1.0, island=1))
    db.register(program("three", 3.0, island=2))
    db.register(program("two", 2.0, island=2))
    return db


def test_reset_empties_the_weaker_half_and_reseeds_from_survivors_best():
    db = four_islands()
    survivors = [db.programs(0), db.programs(2)]
    assert db.on_sample(9) == []
    assert db.on_sample(10) == [1, 3]
    assert [db.programs(0), db.programs(2)] == survivors
    for island in (1, 3):
        (founder,) = db.programs(island)
        assert founder.key in ("five", "three")
        assert founder == replace(program(founder.key, founder.score), island=island)
    assert db.best_per_island[0] == 5.0 and db.best_per_island[2] == 3.0
    assert db.is_known("one")  # an emptied island's structures are still never evaluated again
    assert db.cluster_temperature(1) == db.cluster_temperature(3) == pytest.approx(0.1 * (1 - 1 / 30000))


def test_reset_happens_once_per_period():
    db = four_islands()
    assert db.on_sample(12) == [1, 3]
    assert db.on_sample(19) == []
    assert len(db.on_sample(20)) == 2
    assert len(db.on_sample(45)) == 2  # crossed 30 and 40: one reset
    assert db.on_sample(49) == []


def test_reset_founders_are_drawn_from_all_survivors():
    founders = set()
    for seed in range(20):
        db = four_islands(seed)
        db.on_sample(10)
        founders.update(db.programs(island)[0].key for island in (1, 3))
    assert founders == {"five", "three"}


def test_reset_breaks_ties_randomly():
    reset_sets = set()
    for seed in range(20):
        db = database(seed, num_islands=4, reset_every=10)  # every island holds only the starter
        reset = db.on_sample(10)
        assert len(reset) == 2 and reset == sorted(reset)
        reset_sets.add(tuple(reset))
    assert len(reset_sets) > 3


def test_reset_every_zero_never_resets():
    db = database(num_islands=4, reset_every=0)
    db.register(program("a", 1.0, island=0))
    assert [db.on_sample(n) for n in (1, 400, 10**6)] == [[], [], []]
    assert db.island_sizes == [2, 1, 1, 1]


def test_a_single_island_is_never_reset():
    db = database(num_islands=1, reset_every=1)
    db.register(program("a", 1.0))
    assert db.on_sample(5) == [] and db.island_sizes == [2]


def run(db: ProgramDatabase, draw_prompts: bool) -> tuple[list, list]:
    """Registrations, resets and (optionally) prompt draws interleaved like a search; returns
    the selections and the reset islands."""
    selections, resets = [], []
    for batch in range(12):
        if draw_prompts:
            selections.append(db.select())
        for i in range(3):
            sample = 3 * batch + i
            db.register(program(f"k{sample}", float(sample % 4), island=(sample * 5) % 6, sample=sample))
        resets.append(db.on_sample(3 * batch + 3))
    return selections, resets


def snapshot(db: ProgramDatabase) -> list:
    return [db.programs(i) for i in range(6)] + [db.best, db.island_sizes, db.best_per_island]


def test_same_seed_same_calls_same_selections_and_state():
    config = {"num_islands": 6, "reset_every": 6, "functions_per_prompt": 2}
    first, second, other = (database(seed, **config) for seed in (3, 3, 4))
    assert run(first, True) == run(second, True) != run(other, True)
    assert snapshot(first) == snapshot(second)


def test_replaying_registrations_without_prompts_rebuilds_the_same_state():
    config = {"num_islands": 6, "reset_every": 6, "functions_per_prompt": 2}
    live, replayed = database(7, **config), database(7, **config)
    _, live_resets = run(live, draw_prompts=True)
    _, replayed_resets = run(replayed, draw_prompts=False)
    assert live_resets == replayed_resets
    assert sum(map(len, live_resets)) == 18  # 6 resets of 3 islands
    assert snapshot(live) == snapshot(replayed)
