"""Faults a run meets, each ending cleanly: what was evaluated stays evaluated, the summary
agrees with the store, no sample number is skipped or counted twice, and user errors end in
one line naming the path.

Ctrl-C and SIGTERM (once: the programs in flight finish with their best constants so far;
twice: they are stored as interrupted and evaluated on resume), a SIGKILL while a batch is
tuned (its generated samples stay pending and are evaluated on resume), a full disk (simulated
with a file-size limit), a second search into a locked run directory, a resume with other scoring
settings, empty and corrupt stores, and directories that cannot be written.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import resource
import signal
import sqlite3
import subprocess
import time
from pathlib import Path

import pytest
from conftest import children_of, compose, refused, run_colmo, start_colmo, wait_for

from colmo.__main__ import main as colmo
from colmo.program import STRUCTURE_KEY_VERSION, structure_key
from colmo.record import Summary
from colmo.search import Search

TINY = ("task.episodes=2", "tracker=none", "executor.workers=2", "search.progress=false", "heldout.episodes=2", "finish.render=false", "finish.simplify=false")
# Programs that tune long enough to be caught in flight: two batches of 4 are tuned together,
# 320 evaluations (20 s on 2 loaded cores); the starter's tuning before them, 40.
SLOW = ("gfo.budget=40", "llm.batch_size=4")


def rows(run_dir: Path, columns: str = "sample, status, cut_short") -> list[tuple]:
    """The store's samples (read-only, while a search may be writing)."""
    path = run_dir / "programs.db"
    if not path.is_file():
        return []
    try:
        with sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=30) as connection:
            return connection.execute(f"SELECT {columns} FROM samples WHERE sample >= 0 ORDER BY sample").fetchall()
    except sqlite3.OperationalError:  # the schema is not there yet
        return []


def start(cwd: Path, *overrides: str, **popen) -> subprocess.Popen:
    return start_colmo("colmo", *overrides, cwd=cwd, **popen)


def resume(run_dir: Path, *overrides: str) -> Summary:
    """Resume the run in `run_dir` in this process (tests/test_search.py resumes through `colmo`)."""
    return Search(compose("search", *overrides, f"resume={run_dir}"), run_dir).run()


def run_dir_of(cwd: Path) -> Path:
    return wait_for(lambda: next(iter(cwd.glob("outputs/pendulum/*")), None), what="the run directory")


def pending_samples(run_dir: Path) -> set[int]:
    return {sample for sample, status, _ in rows(run_dir) if status == "pending"}


def being_tuned(run_dir: Path) -> bool:
    """A generated batch is being tuned: its samples stay pending (a duplicate or a program that
    fails at once would settle within moments)."""
    before = pending_samples(run_dir)
    time.sleep(0.2)
    return bool(before & pending_samples(run_dir))


def descendants_of(pid: int) -> list[int]:
    children = children_of(pid)
    return children + [grandchild for child in children for grandchild in descendants_of(child)]


def frozen_in_tuning(pid: int, run_dir: Path) -> bool:
    """Stop (SIGSTOP) the search's workers and their evaluations; true if samples are then pending
    (in flight, or queued behind them), otherwise let the workers go on and false."""
    workers = descendants_of(pid)
    for worker in workers:
        with contextlib.suppress(ProcessLookupError):
            os.kill(worker, signal.SIGSTOP)
    if pending_samples(run_dir):
        return True
    for worker in workers:
        with contextlib.suppress(ProcessLookupError):
            os.kill(worker, signal.SIGCONT)
    time.sleep(0.2)
    return False


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_stop_signal_finishes_the_programs_in_flight_and_loses_nothing(tmp_path, signum):
    process = start(tmp_path, "search.max_samples=1000", *TINY, *SLOW)
    run_dir = run_dir_of(tmp_path)
    wait_for(lambda: being_tuned(run_dir), timeout=600, what="programs in tuning")
    process.send_signal(signum)
    _, stderr = process.communicate(timeout=300)
    assert process.returncode == 130, stderr
    assert "resume with: colmo " in stderr and f"resume={run_dir}" in stderr and "Traceback" not in stderr
    stored = rows(run_dir)
    summary = json.loads((run_dir / "summary.json").read_text())
    assert summary["stop_reason"] == "interrupted"
    assert [sample for sample, *_ in stored] == list(range(summary["samples"]))  # every number once, none skipped
    assert summary["samples"] >= 1 and all(status in ("evaluated", "failed", "duplicate", "unusable") for _, status, _ in stored)
    assert any(cut_short for *_, cut_short in stored)  # tuning stopped at the next candidate, its best kept
    assert (run_dir / "best_policy.py").is_file()
    policy = f"task=pendulum seed=0 policy_file={run_dir / 'best_policy.py'}"
    assert f"or score, simplify and film its best so far: colmo-evaluate {policy}; colmo-simplify {policy}; colmo-render {policy}" in stderr


def test_a_second_signal_stores_the_programs_in_flight_as_interrupted_and_resume_evaluates_them(tmp_path, monkeypatch):
    process = start(tmp_path, "search.max_samples=8", *TINY, *SLOW)
    run_dir = run_dir_of(tmp_path)
    # The first signal lets the programs in flight finish at their next candidate, within moments:
    # their workers are frozen so that they are still in flight when the second signal comes.
    wait_for(lambda: frozen_in_tuning(process.pid, run_dir), timeout=600, what="programs in tuning, their workers frozen")
    process.send_signal(signal.SIGINT)
    # Signals of one kind do not queue: the second is sent once the first has been handled.
    for line in process.stderr:
        if "stopping:" in line:
            break
    process.send_signal(signal.SIGINT)
    process.communicate(timeout=300)
    assert process.returncode == 130
    interrupted = [sample for sample, status, _ in rows(run_dir) if status == "interrupted"]
    assert interrupted, rows(run_dir)
    summary = json.loads((run_dir / "summary.json").read_text())
    assert summary["interrupted"] == len(interrupted) and summary["samples"] == len(rows(run_dir))

    monkeypatch.chdir(tmp_path)
    code, line = refused(colmo, "search.max_samples=8", *TINY, "gfo.budget=4", f"resume={run_dir}")
    assert code == 2 and "gfo.budget=40; this command has gfo.budget=4" in line  # other scoring settings: refused
    assert resume(run_dir, "search.max_samples=8", *TINY, *SLOW).stop_reason == "max_samples"
    after = rows(run_dir)
    assert [sample for sample, *_ in after] == list(range(8))
    assert all(status != "interrupted" for _, status, _ in after)


def _limit_file_size(size: int):
    def apply() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails (EFBIG) instead of killing

    return apply


def test_a_full_disk_ends_the_search_cleanly_with_the_store_intact(tmp_path):
    overrides = ("search.max_samples=400", "gfo=none", *TINY, "hydra/job_logging=stdout")
    process = start(tmp_path, *overrides, preexec_fn=_limit_file_size(96 * 1024))
    stdout, stderr = process.communicate(timeout=600)
    run_dir = next(tmp_path.glob("outputs/pendulum/*"))
    assert process.returncode == 1, stderr
    assert "Traceback" not in stdout + stderr and "resume with: colmo " in stderr
    assert f"stopped: store failed: cannot write to {run_dir / 'programs.db'}" in stdout
    with sqlite3.connect(run_dir / "programs.db") as connection:
        assert connection.execute("PRAGMA integrity_check").fetchone() == ("ok",)
    stored = rows(run_dir)
    # Whichever write failed (a batch's pending rows, or an outcome that landed before an
    # earlier sample's), the store's sample numbers have no gap: samples in flight stay pending.
    assert stored and [sample for sample, *_ in stored] == list(range(len(stored)))
    assert resume(run_dir, *overrides[:-1], "search.max_samples=" + str(len(stored) + 4)).stop_reason == "max_samples"
    after = rows(run_dir)
    assert [sample for sample, *_ in after] == list(range(len(stored) + 4))
    assert all(status != "pending" for _, status, _ in after)


def test_a_killed_search_keeps_what_was_generated_and_resume_evaluates_it(tmp_path, caplog):
    """SIGKILL while a batch is being tuned: its samples are in the store as `pending`, with the
    generator's output; the resumed run evaluates those outputs under their own numbers instead
    of generating new ones. Nor does the kill leave a worker's temporary directory behind."""
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    process = start(tmp_path, "search.max_samples=8", *TINY, *SLOW, start_new_session=True, env={**os.environ, "TMPDIR": str(temporary)})
    run_dir = run_dir_of(tmp_path)
    wait_for(lambda: being_tuned(run_dir), timeout=600, what="programs in tuning")
    os.killpg(process.pid, signal.SIGKILL)  # the coordinator and its sandbox workers
    process.communicate(timeout=60)
    assert not any(temporary.glob("colmo-sandbox-*"))
    pending = {sample: raw for sample, status, raw in rows(run_dir, "sample, status, raw") if status == "pending"}
    assert pending
    with caplog.at_level(logging.INFO, logger="colmo.search"):
        assert resume(run_dir, "search.max_samples=8", *TINY, *SLOW).stop_reason == "max_samples"
    after = {sample: (status, raw) for sample, status, raw in rows(run_dir, "sample, status, raw")}
    assert sorted(after) == list(range(8))
    assert all(after[sample][0] != "pending" and after[sample][1] == raw for sample, raw in pending.items())
    assert any(f"{len(pending)} to evaluate again" in message for message in caplog.messages)


def recorded_elapsed(run_dir: Path) -> dict[str, float]:
    with sqlite3.connect(f"file:{run_dir / 'programs.db'}?mode=ro", uri=True) as connection:
        (value,) = connection.execute("SELECT value FROM run WHERE name = 'elapsed'").fetchone()
    return json.loads(value)


def test_a_resumed_run_counts_the_time_of_its_earlier_processes(tmp_path):
    """A run's seconds (summary.json, and the rates and per-second plots made from them) are the
    whole run's: its store records the time taken after every batch and at the end, and a
    resumed run adds its own process's time to it."""
    overrides = ("gfo=none", *TINY)
    run_dir = tmp_path / "run"
    first = Search(compose("search", "search.max_samples=4", *overrides), run_dir).run()
    assert first.seconds <= recorded_elapsed(run_dir)["seconds"] <= first.seconds + 5
    started = time.perf_counter()
    second = resume(run_dir, "search.max_samples=8", *overrides)
    resume_wall = time.perf_counter() - started
    assert second.samples == 8
    # This process's own time is under its wall clock; the earlier process's comes on top.
    assert first.seconds < second.seconds <= first.seconds + resume_wall
    assert second.seconds > resume_wall
    assert recorded_elapsed(run_dir)["seconds"] >= second.seconds
    assert second.evaluations_per_second == pytest.approx(second.evaluations / second.seconds)


def has_run_settings(run_dir: Path) -> bool:
    """The search holds the run directory's lock and has recorded its settings (a resume's input
    check passes): from the moment it opens its store, before any evaluation."""
    try:
        with sqlite3.connect(f"file:{run_dir / 'programs.db'}?mode=ro", uri=True, timeout=30) as connection:
            return bool(connection.execute("SELECT name FROM run").fetchall())
    except sqlite3.OperationalError:  # no store yet, or not its schema
        return False


def test_a_second_search_into_a_run_directory_in_use_is_one_line(tmp_path):
    first = start(tmp_path, "search.max_samples=1000", *TINY)
    run_dir = run_dir_of(tmp_path)
    try:
        wait_for(lambda: has_run_settings(run_dir), timeout=600, what="the first search to open its store")
        result = run_colmo("colmo", "search.max_samples=1000", *TINY, f"resume={run_dir}", cwd=tmp_path)
    finally:
        first.send_signal(signal.SIGINT)
        first.communicate(timeout=300)
    assert result.returncode == 2
    assert result.stderr.strip().splitlines()[-1] == f"colmo: error: the run directory {run_dir} is in use by another colmo search (pid {first.pid})"


@pytest.mark.parametrize("content, message", [
    (b"", "{path} is empty: not a colmo program store"),
    (b"garbage " * 100, "{path} is not a colmo program store (file is not a database)"),
])
def test_empty_or_corrupt_stores_are_one_line_naming_the_file(tmp_path, monkeypatch, content, message):
    run_dir = tmp_path / "run"
    run_dir.mkdir()
    (run_dir / "programs.db").write_bytes(content)
    monkeypatch.chdir(tmp_path)
    assert refused(colmo, *TINY, f"resume={run_dir}") == (2, "colmo: error: " + message.format(path=run_dir / "programs.db"))


def test_a_run_directory_that_cannot_be_written_is_one_line(tmp_path, monkeypatch):
    """Root ignores directory permissions, so the parent is made unwritable for everyone: it is
    a file."""
    blocker = tmp_path / "not_a_directory"
    blocker.write_text("")
    monkeypatch.chdir(tmp_path)
    code, line = refused(colmo, *TINY, f"hydra.run.dir={blocker}/run")
    assert code == 2 and line.startswith(f"colmo: error: cannot create the output directory {blocker}/run: {blocker} is not a directory")


def test_a_store_an_older_colmo_wrote_is_resumed_under_todays_structure_keys(tmp_path, caplog):
    """A store whose keys are of another definition (an older colmo's, recorded without a key
    version) has them computed again when resumed, so that its structures are not met as new ones,
    and programs that are one structure under today's keys (here: two samples that share their
    code, and one that is the starter's) are registered once, without failing the resume."""
    overrides = ("search.max_samples=8", "gfo.budget=4", *TINY)
    run_dir = tmp_path / "run"
    Search(compose("search", *overrides), run_dir).run()
    with sqlite3.connect(run_dir / "programs.db") as connection:
        evaluated = connection.execute("SELECT sample, skeleton, initial_params, island FROM samples WHERE status = 'evaluated' ORDER BY sample").fetchall()
        starter, first, second, third = evaluated[:4]
        connection.execute("UPDATE samples SET key = 'old-' || sample WHERE skeleton IS NOT NULL")
        connection.execute("UPDATE samples SET skeleton = ?, initial_params = ?, island = ? WHERE sample = ?", (*first[1:], second[0]))
        connection.execute("UPDATE samples SET skeleton = ?, initial_params = ? WHERE sample = ?", (*starter[1:3], third[0]))
        connection.execute("DELETE FROM run WHERE name = 'structure_key_version'")
    with caplog.at_level(logging.INFO, logger="colmo.search"):
        assert resume(run_dir, *overrides[1:], "search.max_samples=10").samples == 10
    assert any("the keys of" in message and "computed again" in message for message in caplog.messages)
    with sqlite3.connect(run_dir / "programs.db") as connection:
        keys = dict(connection.execute("SELECT sample, key FROM samples WHERE skeleton IS NOT NULL").fetchall())
        skeletons = dict(connection.execute("SELECT sample, skeleton FROM samples WHERE skeleton IS NOT NULL").fetchall())
        (version,) = connection.execute("SELECT value FROM run WHERE name = 'structure_key_version'").fetchone()
    assert json.loads(version) == STRUCTURE_KEY_VERSION
    assert all(keys[sample] == structure_key(skeleton) for sample, skeleton in skeletons.items())
    assert keys[second[0]] == keys[first[0]] and keys[third[0]] == keys[starter[0]]
