"""The run directory's files are private (issue 24 part 7): the store holds programs' failure
messages and the run's settings, so `programs.db` and SQLite's -wal and -shm files beside it
are created 0600 and a run directory colmo creates is 0700, whatever the umask lets through;
through a colmo app, every file and directory a run writes is."""

from __future__ import annotations

import os
import sqlite3
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from colmo.record import SampleRecord
from colmo.store import STORE_FILE, open_run

SETTINGS = {"task": "pendulum"}


def mode(path: Path) -> int:
    return stat.S_IMODE(path.stat().st_mode)


@pytest.fixture
def permissive_umask():
    """The most permissive umask: every bit a file or directory is created without is colmo's choice."""
    previous = os.umask(0)
    try:
        yield
    finally:
        os.umask(previous)


def write_a_sample(run_dir: Path, resume: bool, sample: int) -> None:
    store, lock = open_run(run_dir, SETTINGS, resume=resume)
    try:
        store.add(SampleRecord(sample=sample, batch=sample, status="duplicate", island=0, parent_keys=(), generator="test", raw="x"))
        store_files = sorted(path.name for path in run_dir.iterdir() if path.name.startswith(STORE_FILE))
        assert store_files == [STORE_FILE, f"{STORE_FILE}-shm", f"{STORE_FILE}-wal"]  # open, in WAL mode
        assert {name: mode(run_dir / name) for name in store_files} == dict.fromkeys(store_files, 0o600)
    finally:
        store.close()
        lock.release()


def test_a_new_run_directory_and_its_store_are_private(tmp_path, permissive_umask):
    run_dir = tmp_path / "runs" / "first"
    write_a_sample(run_dir, resume=False, sample=0)
    assert mode(run_dir) == 0o700
    assert mode(run_dir / STORE_FILE) == 0o600


def test_a_resumed_run_keeps_its_store_private(tmp_path, permissive_umask):
    run_dir = tmp_path / "run"
    write_a_sample(run_dir, resume=False, sample=0)
    write_a_sample(run_dir, resume=True, sample=1)  # -wal and -shm made anew, with the store's mode
    assert mode(run_dir) == 0o700 and mode(run_dir / STORE_FILE) == 0o600


def test_a_store_in_a_directory_the_user_made_is_private(tmp_path, permissive_umask):
    run_dir = tmp_path / "mine"
    run_dir.mkdir(mode=0o755)
    write_a_sample(run_dir, resume=False, sample=0)
    assert mode(run_dir) == 0o755  # the user's own directory keeps the mode the user gave it


def test_every_file_a_run_writes_is_private_even_in_a_directory_the_user_made(tmp_path):
    """Through a colmo app (colmo-optimize, a failing policy: seconds), under the most permissive
    umask, in a run directory the user made open to all: its log, its config copies, the result
    and the policy it writes, and the directories under it, are private."""
    run_dir = tmp_path / "mine"
    run_dir.mkdir()
    run_dir.chmod(0o777)
    policy = tmp_path / "policy.py"
    policy.write_text("def policy(obs):\n    return obs[0] / 0.0\n")
    overrides = (f"policy_file={policy}", "gfo=none", "task.episodes=1", "executor.workers=1", f"hydra.run.dir={run_dir}")
    result = subprocess.run(
        [sys.executable, "-m", "colmo.optimize", *overrides], cwd=tmp_path, capture_output=True, text=True, timeout=300,
        preexec_fn=lambda: os.umask(0),
    )  # fmt: skip
    assert result.returncode == 1, result.stderr  # the policy failed, and the run wrote its files
    written = {str(path.relative_to(run_dir)): mode(path) for path in run_dir.rglob("*")}
    assert {"colmo.log", "result.json", "tuned_policy.py", ".hydra"} <= written.keys()
    assert written == {name: 0o700 if (run_dir / name).is_dir() else 0o600 for name in written}
    assert mode(run_dir) == 0o777  # the user's own directory keeps the mode the user gave it


def test_a_store_killed_before_it_recorded_its_run_holds_nothing_to_resume(tmp_path):
    from colmo.store import STORE_FILE, holds_run, open_run

    assert not holds_run(tmp_path)  # no store
    (tmp_path / STORE_FILE).touch()
    assert not holds_run(tmp_path)  # created, nothing written
    sqlite3.connect(tmp_path / STORE_FILE).close()
    assert not holds_run(tmp_path)
    store, lock = open_run(tmp_path, {"seed": 0}, resume=False)  # a fresh run over it
    store.close()
    lock.release()
    assert holds_run(tmp_path)
