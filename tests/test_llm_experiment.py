"""`scripts/llm_experiment.py`: which runs it starts, skips and resumes, and its report from the
run directories (no search runs here: the directories are written as a search leaves them)."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parent.parent / "scripts" / "llm_experiment.py"
_spec = importlib.util.spec_from_file_location("llm_experiment", SCRIPT)
llm_experiment = sys.modules["llm_experiment"] = importlib.util.module_from_spec(_spec)  # dataclasses look their module up
_spec.loader.exec_module(llm_experiment)


def write_run(run_dir: Path, seed: int, best: float, stop_reason: str = "max_samples", calls: int = 48, evaluated: int = 30) -> None:
    (run_dir / ".hydra").mkdir(parents=True)
    (run_dir / ".hydra" / "config.yaml").write_text(f"seed: {seed}\ntask:\n  name: pendulum\n  target_score: 400.0\n")
    (run_dir / "programs.db").write_bytes(b"")
    summary = dict(
        samples=calls, programs_evaluated=evaluated, duplicate_rate=0.25, valid_program_rate=0.9, failures=2, unusable_outputs=1,
        best_score=best, best_heldout_score=None if seed == 2 else best - 10, best_so_far=[[0, 1.0], [12, best - 50], [40, best]],
        stop_reason=stop_reason, seconds=600.0,
    )
    (run_dir / "summary.json").write_text(json.dumps(summary))


def test_finished_runs_are_skipped_stopped_ones_resumed_new_ones_started(tmp_path, monkeypatch):
    write_run(tmp_path / "gfo-none" / "s0", 0, 100.0)
    write_run(tmp_path / "gfo-none" / "s1", 1, 100.0, stop_reason="interrupted")
    commands = []
    monkeypatch.setattr(llm_experiment.subprocess, "call", lambda command: commands.append(command) or 0)
    assert llm_experiment.run_all(tmp_path, ["gfo=none"], [0, 1, 2], ["task=pendulum"]) == 0
    assert [command[3:] for command in commands] == [
        ["task=pendulum", "gfo=none", "seed=1", f"hydra.run.dir={tmp_path / 'gfo-none' / 's1'}", f"resume={tmp_path / 'gfo-none' / 's1'}"],
        ["task=pendulum", "gfo=none", "seed=2", f"hydra.run.dir={tmp_path / 'gfo-none' / 's2'}"],
    ]


def test_runs_go_seed_by_seed_so_a_cut_short_experiment_leaves_pairs(tmp_path, monkeypatch):
    commands = []
    monkeypatch.setattr(llm_experiment.subprocess, "call", lambda command: commands.append(command) or 0)
    assert llm_experiment.run_all(tmp_path, ["gfo=none", "gfo=oneplusone"], [0, 1], []) == 0
    assert [(command[3], command[4]) for command in commands] == [
        ("gfo=none", "seed=0"), ("gfo=oneplusone", "seed=0"), ("gfo=none", "seed=1"), ("gfo=oneplusone", "seed=1"),
    ]


def test_a_failing_run_stops_the_experiment_with_its_status(tmp_path, monkeypatch):
    commands = []
    monkeypatch.setattr(llm_experiment.subprocess, "call", lambda command: commands.append(command) or 2)
    assert llm_experiment.run_all(tmp_path, ["gfo=none", "gfo=oneplusone gfo.budget=20"], [0, 1], []) == 2
    assert len(commands) == 1
    assert llm_experiment.variant_dir("gfo=oneplusone gfo.budget=20") == "gfo-oneplusone_gfo.budget-20"  # Hydra takes it in a path


def test_the_report_counts_model_calls_per_seed_and_compares_two_variants(tmp_path):
    for seed, best in enumerate([50.0, 60.0, 70.0]):
        write_run(tmp_path / "gfo-none" / f"s{seed}", seed, best)
    for seed, best in enumerate([190.0, 200.0, 210.0]):
        write_run(tmp_path / "gfo-oneplusone" / f"s{seed}", seed, best)
    write_run(tmp_path / "gfo-oneplusone" / "s3", 3, 999.0, stop_reason="interrupted")  # not finished: not counted
    markdown = llm_experiment.write_report(tmp_path, tmp_path / "report.md", "report").read_text()
    assert "| gfo-none | 0 | 48 | 30 | 12 | 3 | 62.5 | 50.0 | 40.0 | — | 600 |" in markdown
    assert "| gfo-oneplusone | 3 | 48 ± 0 | 30.0 ± 0.0 | 62.5 ± 0.0 | 25.0 ± 0.0% | 90.0 ± 0.0% | 200.0 ± 10.0 | 185.0 ± 7.1 (2/3 seeds) |" in markdown
    assert "gfo gfo-oneplusone" not in markdown and "gfo-oneplusone − gfo-none: +140.0" in markdown and "excludes 0" in markdown
    assert "gfo-oneplusone/s3`: stopped (interrupted)" in markdown
    assert (tmp_path / "best_so_far.png").stat().st_size > 0


def test_the_figure_shows_best_so_far_against_seconds_of_generation_where_stores_say_them(tmp_path):
    from colmo.generate import Generation
    from colmo.record import Sample, SampleRecord
    from colmo.store import STORE_FILE, ProgramStore

    for variant, best in [("gfo-none", 50.0), ("gfo-oneplusone", 200.0)]:
        run_dir = tmp_path / variant / "s0"
        write_run(run_dir, 0, best)
        (run_dir / "programs.db").unlink()
        store = ProgramStore(run_dir / STORE_FILE)
        # 48 calls: the first answer took 3 calls (two duplicates thrown away) and 30 s, each other 10 s.
        store.add(*(
            SampleRecord.of(Sample(index, index, 0, (), Generation("answer", "test", seconds=30.0 if index == 0 else 10.0, calls=3 if index == 0 else 1)), "evaluated")
            for index in range(46)
        ))
        store.close()
    [run] = llm_experiment.read_runs(tmp_path)[0]["gfo-none"]
    assert run.curve == ([0.0, 12.0, 40.0, 48.0], [1.0, 0.0, 50.0, 50.0])
    assert run.seconds_curve == ([0.0, 120.0, 400.0, 480.0], [1.0, 0.0, 50.0, 50.0])  # call 12 ends answer 10: 30 + 9 x 10 s
    llm_experiment.write_report(tmp_path, tmp_path / "report.md", "report")
    from matplotlib.image import imread

    assert imread(tmp_path / "best_so_far.png").shape[1] > 1.5 * 4.8 * 130  # two panels side by side


def test_the_bootstrap_interval_of_equal_groups_includes_zero():
    difference, low, high = llm_experiment.bootstrap_difference([1.0, 5.0, 9.0], [1.0, 5.0, 9.0])
    assert difference == 0.0 and low < 0 < high
    assert llm_experiment.bootstrap_difference([1.0, 2.0], [11.0, 12.0]) == pytest.approx((10.0, 9.0, 11.0))


def write_store(run_dir: Path, settled: list[tuple[str, int]], pending: int = 0) -> None:
    """A run's store: the starter, then samples settled as (status, model calls), then `pending` ones."""
    from colmo.generate import Generation
    from colmo.record import PENDING, Sample, SampleRecord
    from colmo.store import STORE_FILE, ProgramStore

    run_dir.mkdir(parents=True)
    store = ProgramStore(run_dir / STORE_FILE)
    rows = [("evaluated", 1), *settled, *[(PENDING, 1)] * pending]
    store.add(*(
        SampleRecord.of(Sample(index - 1, index, 0, (), Generation("answer", "test", calls=calls)), status)
        for index, (status, calls) in enumerate(rows)
    ))
    store.close()


def test_the_model_call_yield_is_read_from_every_runs_store_over_its_first_calls(tmp_path):
    # 3 calls for the first answer (two duplicates thrown away), then 45 single calls of which 30
    # are evaluated: 31 evaluated of the first 48 calls; 2 more calls settled, 1 evaluated; one pending.
    write_store(tmp_path / "gfo-oneplusone" / "s0", [("evaluated", 3), *[("evaluated", 1)] * 30, *[("duplicate", 1)] * 10, *[("failed", 1)] * 5,
                                                     ("evaluated", 1), ("unusable", 1)], pending=1)
    write_store(tmp_path / "gfo-oneplusone" / "s1", [("evaluated", 1)] * 20)  # still running: fewer than 48 calls so far
    first = llm_experiment.call_yield(tmp_path / "gfo-oneplusone" / "s0", 48)
    assert (first.calls, first.evaluated, first.first_evaluated) == (50, 32, 31)
    # Of the first 48 calls: 46 answers, 30 evaluated at their first call; 2 calls generated the first again, and it was evaluated.
    assert (first.first_answers, first.regenerations) == ((46, 30), (2, 1))
    short = llm_experiment.call_yield(tmp_path / "gfo-oneplusone" / "s1", 48)
    assert (short.calls, short.first_evaluated) == (20, None)
    markdown = llm_experiment.write_report(tmp_path, tmp_path / "report.md", "report").read_text()  # no run finished: the yield alone
    assert "| gfo-oneplusone | 0 | 50 | 32 | 64.0 | 31 | 64.6 | 30 of 46 | 2, 1 |" in markdown
    assert "| gfo-oneplusone | 1 | 20 | 20 | 100.0 | — | — | — | — |" in markdown
    assert "gfo-oneplusone: 64.6 per 100 of the first 48 calls over 1 seeds (s0 64.6)" in markdown


def test_one_finished_seed_a_variant_gives_a_difference_but_no_interval(tmp_path):
    write_run(tmp_path / "gfo-none" / "s0", 0, 50.0)
    write_run(tmp_path / "gfo-oneplusone" / "s0", 0, 250.0)
    markdown = llm_experiment.write_report(tmp_path, tmp_path / "report.md", "report").read_text()
    assert "gfo-oneplusone − gfo-none: +200.0; no interval" in markdown and "bootstrap interval" not in markdown



def test_a_resumed_run_whose_store_lacks_the_whole_time_says_its_seconds_are_the_last_process(tmp_path):
    """Before colmo recorded a run's time in its store, a resumed run's summary counted only its
    last process: the report says so instead of showing that as the run's time."""
    from colmo.record import Elapsed
    from colmo.store import STORE_FILE, ProgramStore

    resumed_log = "[2026-12-03 11:29:59,064][colmo.search][INFO] resumed /runs/gfo-none/s1: 77 samples, best 196.50, 0 to evaluate again\n"
    for seed, log, recorded in [(0, "", False), (1, resumed_log, False), (2, resumed_log, True)]:
        run_dir = tmp_path / "gfo-none" / f"s{seed}"
        write_run(run_dir, seed, 100.0)
        (run_dir / "programs.db").unlink()
        store = ProgramStore(run_dir / STORE_FILE)
        if recorded:
            store.set_elapsed(Elapsed(seconds=600.0))
        store.close()
        (run_dir / "colmo.log").write_text(log)
    markdown = llm_experiment.write_report(tmp_path, tmp_path / "report.md", "report").read_text()
    assert "| gfo-none | 0 | 48 | 30 | 12 | 3 | 62.5 | 100.0 | 90.0 | — | 600 |" in markdown  # one process
    assert "| 600 (the last of 2 processes) |" in markdown  # seed 1: resumed, its store predates the record
    assert "| gfo-none | 2 | 48 | 30 | 12 | 3 | 62.5 | 100.0 | — | — | 600 |" in markdown  # resumed, the whole time recorded
