"""Sweeps through Hydra launcher plugins: every job of a real `python -m colmo -m` sweep finishes."""

import importlib.util
import json

import pytest

from conftest import run_colmo

TINY = ("search.max_samples=2", "gfo.budget=2", "task.episodes=1", "tracker=none", "executor.workers=1", "search.progress=false")


def installed(plugin: str) -> pytest.MarkDecorator:
    missing = importlib.util.find_spec(f"hydra_plugins.{plugin}") is None
    return pytest.mark.skipif(missing, reason=f"{plugin.replace('_', '-')} is not installed: pip install 'colmo[launchers]'")


def sweep(tmp_path, launcher: str, *overrides: str) -> list[dict]:
    """Run a two-job sweep (seed=0,1) through `launcher`; the summaries of its jobs, by seed."""
    result = run_colmo("colmo", "-m", f"hydra/launcher={launcher}", *overrides, "seed=0,1", *TINY, "hydra.sweep.dir=sweep", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    summaries = sorted((tmp_path / "sweep").glob("*/summary.json"))
    assert len(summaries) == 2, result.stderr
    return [json.loads(path.read_text()) for path in summaries]


@installed("hydra_joblib_launcher")
def test_joblib_sweep_runs_every_job(tmp_path):
    summaries = sweep(tmp_path, "joblib", "hydra.launcher.n_jobs=2")
    assert [s["samples"] for s in summaries] == [2, 2]
    assert all(s["stop_reason"] == "max_samples" for s in summaries)


@installed("hydra_submitit_launcher")
def test_submitit_sweep_runs_both_jobs(tmp_path):
    # submitit_local runs the jobs as local processes through the same plugin as SLURM does.
    summaries = sweep(tmp_path, "submitit_local", "hydra.launcher.timeout_min=10")
    assert [s["samples"] for s in summaries] == [2, 2]
