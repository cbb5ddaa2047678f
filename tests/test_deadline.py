"""`search.max_seconds` is a wall-clock limit: the search ends within seconds of it whatever the
task, with a summary that says so, and the programs whose tuning the deadline cut short are
stored with their best constants so far (`cut_short`), not thrown away."""

from __future__ import annotations

import contextlib
import json
import sqlite3
import time

import pytest
from conftest import run_colmo

from colmo.store import STORE_FILE, SUMMARY_FILE


def search(tmp_path, task: str, *overrides: str, timeout: float) -> tuple[float, dict, list[dict]]:
    """Run `python -m colmo task=<task> ...` in `tmp_path` (killed after `timeout` seconds): its
    wall-clock seconds, its summary, and its stored samples."""
    start = time.monotonic()
    result = run_colmo("colmo", f"task={task}", "tracker=none", *overrides, cwd=tmp_path, timeout=timeout)
    wall = time.monotonic() - start
    assert result.returncode == 0, result.stderr[-3000:]
    run_dir = next(tmp_path.glob(f"outputs/{task}/*/"))
    summary = json.loads((run_dir / SUMMARY_FILE).read_text())
    with contextlib.closing(sqlite3.connect(run_dir / STORE_FILE)) as store:
        store.row_factory = sqlite3.Row
        samples = [dict(row) for row in store.execute("SELECT sample, status, score, cut_short FROM samples ORDER BY sample")]
    return wall, summary, samples


def test_a_time_limit_stops_tuning_in_flight_and_keeps_its_programs(tmp_path):
    # Each program would take hours to tune with this budget: only the deadline ends the run.
    _, summary, samples = search(
        tmp_path, "pendulum", "gfo.budget=100000", "search.max_seconds=8", "executor.workers=2", "evaluation.episodes=5", "evaluation.top=1",
        timeout=120,
    )
    assert summary["stop_reason"] == "max_seconds"
    cut_short = [s for s in samples if s["cut_short"]]
    assert cut_short, samples
    assert all(s["status"] == "evaluated" and s["score"] is not None for s in cut_short)
    assert summary["best_score"] is not None


@pytest.mark.slow
def test_the_quadruped_search_ends_within_80_s_of_a_60_s_limit(tmp_path):
    wall, summary, _ = search(tmp_path, "quadruped", "search.max_seconds=60", timeout=600)
    assert summary["stop_reason"] == "max_seconds"
    assert wall < 80, f"the run took {wall:.0f} s"
