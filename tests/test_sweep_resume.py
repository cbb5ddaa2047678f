"""A `-m` sweep killed mid-way and run again with the same command (its `hydra.sweep.dir`) keeps
every job that finished and resumes the others from their stores: only what was left is done."""

import json
import os
import signal
import subprocess
import sys

from conftest import wait_for

from colmo.store import SUMMARY_FILE, holds_run

SWEEP = ("-m", "seed=0,1", "llm=mutate", "search.max_samples=40", "gfo.budget=2", "task.episodes=1", "heldout.episodes=2",
         "finish.render=false", "finish.simplify=false", "executor.workers=1", "search.progress=false", "tracker=none",
         "hydra.sweep.dir=sweep")


def test_a_killed_sweep_run_again_keeps_its_finished_jobs_and_resumes_the_others(tmp_path):
    command = [sys.executable, "-m", "colmo", *SWEEP]
    first = subprocess.Popen(command, cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        # Killed (with its workers) as soon as the second job's store records its run: the first has finished.
        wait_for(lambda: any(map(holds_run, (tmp_path / "sweep").glob("1_*"))) or first.poll() is not None, timeout=600, interval=0.05,
                 what="the second job's store")
    finally:
        os.killpg(first.pid, signal.SIGKILL)
        first.wait()
    [finished] = (tmp_path / "sweep").glob(f"0_*/{SUMMARY_FILE}")
    assert not list((tmp_path / "sweep").glob(f"1_*/{SUMMARY_FILE}")), "the second job ended before it was killed"
    kept = finished.read_text()
    stamp = finished.stat().st_mtime_ns

    again = subprocess.run(command, cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr[-3000:]
    assert "this job finished earlier in" in again.stdout and "kept" in again.stdout
    assert finished.read_text() == kept and finished.stat().st_mtime_ns == stamp  # not run again
    assert "this job resumes its earlier run" in again.stderr
    [resumed] = (tmp_path / "sweep").glob(f"1_*/{SUMMARY_FILE}")
    summary = json.loads(resumed.read_text())
    assert summary["samples"] == 40 and summary["stop_reason"] == "max_samples" and summary["programs_evaluated"] > 0
    assert "sweep sweep: 2 jobs" in again.stdout  # the end-of-sweep table, over both jobs
