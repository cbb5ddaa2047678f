"""Sweeps through Hydra plugins: every job of a real `colmo -m` sweep finishes through the joblib
and submitit launchers, jobs starting together share one fresh MLflow store under one parent
run, and Optuna's sweeper (hydra/sweeper=optuna) runs trials that search."""

import importlib.util
import json

import pytest
from conftest import run_colmo
from mlflow import MlflowClient

TINY = ("search.max_samples=2", "gfo.budget=2", "task.episodes=1", "heldout.episodes=2", "finish.render=false", "finish.simplify=false",
        "executor.workers=1", "search.progress=false")


def installed(plugin: str, extra: str) -> pytest.MarkDecorator:
    missing = importlib.util.find_spec(f"hydra_plugins.{plugin}") is None
    return pytest.mark.skipif(missing, reason=f"{plugin} is not installed: pip install 'colmo[{extra}]'")


def sweep(tmp_path, *overrides: str) -> list[dict]:
    """Run a sweep with `overrides` into tmp_path/sweep; the summaries of its jobs, by job number."""
    result = run_colmo("colmo", "-m", *overrides, *TINY, "hydra.sweep.dir=sweep", cwd=tmp_path, timeout=600)
    assert result.returncode == 0, result.stderr
    summaries = sorted((tmp_path / "sweep").glob("*/summary.json"), key=lambda path: int(path.parent.name.split("_")[0]))
    return [json.loads(path.read_text()) for path in summaries]


def tracked(tmp_path) -> tuple[MlflowClient, list, list]:
    """The sweep's MLflow runs in <tmp_path>/mlruns.db: parents and children."""
    client = MlflowClient(f"sqlite:///{tmp_path / 'mlruns.db'}")
    runs = client.search_runs([client.get_experiment_by_name("pendulum").experiment_id])
    parents = [run for run in runs if "mlflow.parentRunId" not in run.data.tags]
    return client, parents, [run for run in runs if run not in parents]


@installed("hydra_joblib_launcher", "launchers")
def test_joblib_jobs_starting_together_share_one_fresh_store_and_one_parent_run(tmp_path):
    summaries = sweep(tmp_path, "hydra/launcher=joblib", "hydra.launcher.n_jobs=2", "seed=0,1")
    assert [s["samples"] for s in summaries] == [2, 2]
    assert all(s["stop_reason"] == "max_samples" for s in summaries)
    client, parents, children = tracked(tmp_path)
    assert [e.name for e in client.search_experiments()].count("pendulum") == 1
    assert len(parents) == 1 and len(children) == 2
    assert {child.data.tags["mlflow.parentRunId"] for child in children} == {parents[0].info.run_id}
    assert len({child.info.run_name for child in children}) == 2
    assert {run.info.status for run in parents + children} == {"FINISHED"}


@installed("hydra_submitit_launcher", "launchers")
def test_submitit_sweep_runs_both_jobs(tmp_path):
    # submitit_local runs the jobs as local processes through the same plugin as SLURM does.
    summaries = sweep(tmp_path, "hydra/launcher=submitit_local", "hydra.launcher.timeout_min=10", "seed=0,1", "tracker=none")
    assert [s["samples"] for s in summaries] == [2, 2]


@installed("hydra_optuna_sweeper", "sweep")
def test_optuna_sweeper_runs_trials_that_search(tmp_path):
    """Three trials of TPE over the GFO budget and the number of islands: each a search, its
    best score the objective, all children of one MLflow parent run."""
    summaries = sweep(
        tmp_path, "hydra/sweeper=optuna", "hydra.sweeper.optuna_config.n_trials=3",
        "gfo.budget=tag(int, interval(2, 4))", "database.num_islands=choice(1, 2)",
    )
    assert len(summaries) == 3 and all(s["samples"] == 2 for s in summaries)
    _, parents, children = tracked(tmp_path)
    assert len(parents) == 1 and len(children) == 3
    for child in children:
        assert child.data.params["gfo.budget"] in ("2", "3", "4")  # integers from the interval
        assert child.data.params["database.num_islands"] in ("1", "2")
    assert parents[0].data.metrics["best_score"] == pytest.approx(max(s["best_score"] for s in summaries), rel=5e-4)  # logged at 4 significant digits
