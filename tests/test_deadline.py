"""`search.max_seconds` is a wall-clock limit of the whole run: it ends within 5 s of it from the
process's start, with the held-out score, simplified policy, video and plot it promises, says
before the first batch how long it will take, and the programs whose tuning the deadline cut
short are stored with their best constants so far (`cut_short`), rounded to 4 significant
digits like every other program's, not thrown away."""

from __future__ import annotations

import ast
import contextlib
import json
import re
import sqlite3
import time
from dataclasses import dataclass
from pathlib import Path

import pytest
from conftest import run_colmo

from colmo.render import PLOT_FILE, VIDEO_FILE
from colmo.store import BEST_POLICY_FILE, SIMPLIFIED_POLICY_FILE, STORE_FILE, SUMMARY_FILE


@dataclass
class Run:
    wall: float  # seconds from the process's start to its end
    summary: dict
    samples: list[dict]  # the stored samples
    run_dir: Path
    stderr: str


def search(tmp_path, task: str, *overrides: str, timeout: float) -> Run:
    """Run `python -m colmo task=<task> ...` in `tmp_path` (killed after `timeout` seconds)."""
    start = time.monotonic()
    result = run_colmo("colmo", f"task={task}", "tracker=none", *overrides, cwd=tmp_path, timeout=timeout)
    wall = time.monotonic() - start
    assert result.returncode == 0, result.stderr[-3000:]
    run_dir = next(tmp_path.glob(f"outputs/{task}/*/"))
    summary = json.loads((run_dir / SUMMARY_FILE).read_text())
    with contextlib.closing(sqlite3.connect(run_dir / STORE_FILE)) as store:
        store.row_factory = sqlite3.Row
        samples = [dict(row) for row in store.execute("SELECT sample, status, score, cut_short, code FROM samples ORDER BY sample")]
    return Run(wall, summary, samples, run_dir, result.stderr)


def constants(code: str) -> list[float]:
    return [node.value for node in ast.walk(ast.parse(code)) if isinstance(node, ast.Constant) and isinstance(node.value, float)]


def test_a_time_limit_stops_tuning_in_flight_and_keeps_its_programs(tmp_path):
    # Each program would take hours to tune with this budget: only the deadline ends the run.
    run = search(
        tmp_path, "pendulum", "gfo.budget=100000", "search.max_seconds=30", "executor.workers=2", "evaluation.episodes=5", "evaluation.top=1",
        timeout=120,
    )
    assert run.summary["stop_reason"] == "max_seconds"
    cut_short = [s for s in run.samples if s["cut_short"]]
    assert cut_short, run.samples
    assert all(s["status"] == "evaluated" and s["score"] is not None for s in cut_short)
    assert run.summary["best_score"] is not None
    # Readable like any other program: every constant at 4 significant digits at most.
    for sample in cut_short:
        assert all(float(f"{value:.4g}") == value for value in constants(sample["code"])), sample["code"]


def test_a_short_run_ends_within_5_s_of_its_limit_with_everything_it_promises(tmp_path):
    limit = 60  # under load, the start of the process and the starter's calibration take half of it
    run = search(tmp_path, "pendulum", f"search.max_seconds={limit}", "gfo.budget=10", "executor.workers=2", timeout=600)
    assert run.wall <= limit + 5, f"the run took {run.wall:.1f} s"
    assert re.search(r"estimated duration: search \S+ .* limit that binds: max_seconds=60", run.stderr), run.stderr[-3000:]
    for name in (BEST_POLICY_FILE, SIMPLIFIED_POLICY_FILE, PLOT_FILE, VIDEO_FILE):
        assert (run.run_dir / name).is_file(), (name, run.stderr[-3000:])
    assert run.summary["best_heldout_score"] is not None
    assert run.summary["media"]["video"] == VIDEO_FILE


@pytest.mark.slow
def test_the_quadruped_run_ends_within_5_s_of_a_60_s_limit(tmp_path):
    run = search(tmp_path, "quadruped", "search.max_seconds=60", timeout=600)
    assert run.summary["stop_reason"] == "max_seconds"
    assert run.wall <= 65, f"the run took {run.wall:.1f} s"
