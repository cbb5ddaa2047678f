"""MLflow tracking: a real `-m` sweep read back from the SQLite store and through `mlflow server`,
jobs starting together on one fresh store, and the tracker's end states."""

import json
import multiprocessing
import os
import signal
import socket
import sqlite3
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pandas as pd
import pytest
from mlflow import MlflowClient
from mlflow.exceptions import MlflowException
from omegaconf import OmegaConf

from colmo.store import SampleRecord
from colmo.track import MlflowTracker, PROGRAM_COLUMNS, flatten, open_experiment, retry_locked

TINY = (
    "gfo=none", "search.max_samples=8", "task.episodes=2", "llm.batch_size=4",
    "executor.workers=1", "search.progress=false",
)


def _rounded(value):
    """pandas writes MLflow tables with 10 decimals: compare numbers at 1e-6."""
    if isinstance(value, float):
        return round(value, 6)
    return [_rounded(v) for v in value] if isinstance(value, list) else value


def program_rows(run_dir: Path) -> list[tuple]:
    """What the programs table must hold: every sample of the run, whatever its status (the
    starter, sample -1, is not generated and not logged), in sample order."""
    with sqlite3.connect(run_dir / "programs.db") as connection:
        connection.row_factory = sqlite3.Row
        rows = connection.execute("SELECT * FROM samples WHERE sample >= 0 ORDER BY sample").fetchall()
    loads = lambda text: json.loads(text) if text is not None else None
    return [
        tuple(_rounded(v) for v in (r["sample"], r["batch"], r["status"], r["island"], r["key"], r["code"],
                                    loads(r["params"]), r["score"], loads(r["parent_keys"]), r["failure"]))
        for r in rows
    ]


def table_rows(table: pd.DataFrame) -> list[tuple]:
    table = table.astype(object).where(table.notna(), None)  # JSON null comes back as NaN
    return [tuple(_rounded(row[c]) for c in PROGRAM_COLUMNS) for _, row in table.sort_values("sample").iterrows()]


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    """Two tiny jobs through Hydra's basic (sequential) launcher, tracked into <cwd>/mlruns.db."""
    cwd = tmp_path_factory.mktemp("sweep")
    result = subprocess.run(
        [sys.executable, "-m", "colmo", "-m", "seed=0,1", *TINY, f"hydra.sweep.dir={cwd / 'multirun'}"],
        cwd=cwd, capture_output=True, text=True, timeout=300,
    )
    assert result.returncode == 0, result.stderr
    client = MlflowClient(f"sqlite:///{cwd / 'mlruns.db'}")
    experiment = client.get_experiment_by_name("pendulum")
    runs = client.search_runs([experiment.experiment_id], order_by=["tags.seed ASC"])
    return cwd, client, experiment, runs


def test_sweep_jobs_are_runs_with_params_tags_metrics_programs_and_artifacts(sweep, monkeypatch):
    cwd, client, experiment, runs = sweep
    # MlflowClient.load_table finds runs through the global tracking URI, whatever the client's.
    monkeypatch.setenv("MLFLOW_TRACKING_URI", client.tracking_uri)
    assert experiment.artifact_location == str(cwd / "mlartifacts" / "pendulum")
    assert [run.info.run_name for run in runs] == ["pendulum-none-mutate-s0", "pendulum-none-mutate-s1"]
    for seed, run in enumerate(runs):
        run_dir = Path(run.data.tags["colmo.run_dir"])
        assert run_dir.parent == cwd / "multirun" and run.info.status == "FINISHED"
        summary = json.loads((run_dir / "summary.json").read_text())

        # params: the job's resolved config, flattened, and the task's dimensions
        config = OmegaConf.to_container(OmegaConf.load(run_dir / ".hydra" / "config.yaml"), resolve=True)
        expected = flatten(config) | {"spec.observation_size": "3", "spec.action_size": "1"}
        assert run.data.params == expected
        tags = run.data.tags
        assert (tags["task"], tags["llm"], tags["gfo"], tags["seed"]) == ("pendulum", "mutate", "none", str(seed))
        assert f"seed={seed}" in tags["overrides"].split() and "gfo=none" in tags["overrides"].split()
        assert tags["colmo.version"] and len(tags.get("mlflow.source.git.commit", "x" * 40)) == 40

        # metrics: one point per batch, at step = samples so far
        history = client.get_metric_history(run.info.run_id, "best_score")
        assert [m.step for m in history] == [4, 8]
        assert history[-1].value == summary["best_score"]
        islands = [k for k in run.data.metrics if k.startswith("best_score_island_")]
        assert len(islands) == config["database"]["num_islands"]
        for name in ("programs_evaluated", "duplicates", "failures", "evaluations_per_second", "generator_busy", "evaluator_busy"):
            assert [m.step for m in client.get_metric_history(run.info.run_id, name)] == [4, 8], name
        evaluated = client.get_metric_history(run.info.run_id, "programs_evaluated")[-1].value
        assert evaluated == summary["programs_evaluated"]

        # every sample once, in the per-batch files and in the table
        expected_rows = program_rows(run_dir)
        assert len(expected_rows) == 8
        table = client.load_table(experiment.experiment_id, "programs.json", run_ids=[run.info.run_id])
        assert table_rows(table) == expected_rows
        batches = [Path(client.download_artifacts(run.info.run_id, f.path, str(cwd / run.info.run_id)))
                   for f in client.list_artifacts(run.info.run_id, "programs")]
        assert [b.name for b in batches] == ["batch_00000.json", "batch_00001.json"]
        assert table_rows(pd.concat([pd.read_json(b, orient="split") for b in batches])) == expected_rows

        # artifacts
        names = {f.path for f in client.list_artifacts(run.info.run_id)} | {f.path for f in client.list_artifacts(run.info.run_id, "hydra")}
        assert {"best_policy.py", "summary.json", "best_so_far.png", "hydra/config.yaml", "hydra/overrides.yaml"} <= names
        best = client.download_artifacts(run.info.run_id, "best_policy.py", str(cwd / run.info.run_id))
        assert Path(best).read_text() == (run_dir / "best_policy.py").read_text()

    # load_table joins the table across runs
    both = client.load_table(experiment.experiment_id, "programs.json", run_ids=[r.info.run_id for r in runs], extra_columns=["run_id"])
    assert both.groupby("run_id").size().to_dict() == {r.info.run_id: 8 for r in runs}


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _post(url: str, body: dict) -> dict:
    request = urllib.request.Request(url, json.dumps(body).encode(), {"Content-Type": "application/json"})
    with urllib.request.urlopen(request, timeout=10) as response:
        return json.load(response)


def test_mlflow_server_lists_the_runs_over_rest(sweep):
    cwd, _, _, runs = sweep
    port = _free_port()
    base = f"http://127.0.0.1:{port}"
    # Its own session, so that stopping the group also stops uvicorn's workers.
    server = subprocess.Popen(
        [sys.executable, "-m", "mlflow", "server", "--backend-store-uri", f"sqlite:///{cwd / 'mlruns.db'}",
         "--host", "127.0.0.1", "--port", str(port), "--workers", "1"],
        cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
        env={**os.environ, "MLFLOW_SERVER_ENABLE_JOB_EXECUTION": "false"},
    )
    try:
        for _ in range(120):
            try:
                with urllib.request.urlopen(f"{base}/health", timeout=2) as response:
                    if response.status == 200:
                        break
            except OSError:
                assert server.poll() is None, "mlflow server exited"
                time.sleep(0.5)
        else:
            pytest.fail("mlflow server not ready after 60 s")
        experiments = _post(f"{base}/api/2.0/mlflow/experiments/search", {"max_results": 10})["experiments"]
        experiment_id = next(e["experiment_id"] for e in experiments if e["name"] == "pendulum")
        found = _post(f"{base}/api/2.0/mlflow/runs/search", {"experiment_ids": [experiment_id]})["runs"]
        assert sorted(r["info"]["run_name"] for r in found) == sorted(r.info.run_name for r in runs)
        for run in found:
            metrics = {m["key"]: m for m in run["data"]["metrics"]}
            assert metrics["best_score"]["step"] == 8 and run["info"]["status"] == "FINISHED"
    finally:
        os.killpg(server.pid, signal.SIGTERM)
        try:
            server.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(server.pid, signal.SIGKILL)
            server.wait()


def test_jobs_starting_together_share_one_fresh_store(tmp_path):
    jobs = [
        subprocess.Popen(
            [sys.executable, "-m", "colmo", f"seed={seed}", *TINY, f"hydra.run.dir=run{seed}"],
            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )
        for seed in (0, 1)
    ]
    for job in jobs:
        _, stderr = job.communicate(timeout=300)
        assert job.returncode == 0, stderr
    client = MlflowClient(f"sqlite:///{tmp_path / 'mlruns.db'}")
    experiments = [e.name for e in client.search_experiments()]
    assert experiments.count("pendulum") == 1
    runs = client.search_runs([client.get_experiment_by_name("pendulum").experiment_id])
    assert sorted(r.info.run_name for r in runs) == ["pendulum-none-mutate-s0", "pendulum-none-mutate-s1"]
    assert {r.info.status for r in runs} == {"FINISHED"}


def _open_after(barrier, uri: str, queue) -> None:
    barrier.wait()
    try:
        queue.put(open_experiment(uri, "together")[1])
    except Exception as error:  # reported to the test, which fails on it
        queue.put(f"{type(error).__name__}: {error}")


def test_open_experiment_is_safe_when_processes_start_at_the_same_instant(tmp_path):
    """Without the lock, MLflow's schema migrations collide here ("duplicate column name")."""
    context = multiprocessing.get_context("fork")
    barrier, queue = context.Barrier(4), context.Queue()
    uri = f"sqlite:///{tmp_path / 'mlruns.db'}"
    workers = [context.Process(target=_open_after, args=(barrier, uri, queue)) for _ in range(4)]
    for worker in workers:
        worker.start()
    results = [queue.get(timeout=120) for _ in workers]
    for worker in workers:
        worker.join(timeout=30)
    assert len(set(results)) == 1 and results[0].isdigit(), results


def _record(sample: int, score: float) -> SampleRecord:
    return SampleRecord(sample=sample, batch=sample, status="evaluated", island=sample % 2, parent_keys=["k"],
                        generator="mutate", raw="", key=f"k{sample}", code="def policy(obs):\n    return 0.0\n",
                        params=[0.5], score=score)


def test_interrupted_search_ends_killed_with_its_programs(tmp_path, monkeypatch):
    uri = f"sqlite:///{tmp_path / 'mlruns.db'}"
    monkeypatch.setenv("MLFLOW_TRACKING_URI", uri)  # for load_table, as above
    client, experiment_id = open_experiment(uri, "unit")
    run_id = client.create_run(experiment_id).info.run_id
    tracker = MlflowTracker(client, run_id, hydra_dir=None)
    for batch, score in enumerate([1.0, 3.0]):
        report = {"batch": batch, "samples": batch + 1, "best_score": score, "best_per_island": [score, 1.0],
                  "programs_evaluated": batch + 1, "duplicates": 0, "failures": 0, "generation_seconds": 0.1,
                  "evaluation_seconds": 0.2, "queue_depth": 0, "evaluations_per_second": 5.0,
                  "generator_busy": 0.1, "evaluator_busy": 0.9}
        tracker.on_batch(report, [_record(batch, score)])
    tracker.on_finish({"task": "pendulum", "run_dir": str(tmp_path), "stop_reason": "interrupted"})
    run = client.get_run(run_id)
    assert run.info.status == "KILLED"
    assert [(m.step, m.value) for m in client.get_metric_history(run_id, "best_score_island_0")] == [(1, 1.0), (2, 3.0)]
    assert client.load_table(experiment_id, "programs.json", run_ids=[run_id])["sample"].tolist() == [0, 1]
    assert {f.path for f in client.list_artifacts(run_id)} == {"programs", "programs.json", "best_so_far.png"}


def test_retry_locked_retries_only_a_locked_database():
    calls = []

    def flaky():
        calls.append(1)
        if len(calls) < 3:
            raise MlflowException("(sqlite3.OperationalError) database is locked")
        return "done"

    assert retry_locked(flaky) == "done" and len(calls) == 3

    def missing():
        calls.append(1)
        raise MlflowException("Run 'abc' not found")

    with pytest.raises(MlflowException, match="not found"):
        retry_locked(missing)
    assert len(calls) == 4


def test_flatten_gives_dot_keys_and_json_values():
    assert flatten({"gfo": {"budget": 100, "method": "cma"}, "resume": None, "llm": {"base_url": ["a", "b"]}, "env": {}}) == {
        "gfo.budget": "100", "gfo.method": "cma", "resume": "null", "llm.base_url": '["a", "b"]', "env": "{}",
    }


def test_a_process_that_dies_mid_search_leaves_its_run_failed(tmp_path):
    uri = f"sqlite:///{tmp_path / 'mlruns.db'}"
    script = (
        "from colmo.track import MlflowTracker, open_experiment\n"
        f"client, experiment_id = open_experiment({uri!r}, 'unit')\n"
        "run_id = client.create_run(experiment_id).info.run_id\n"
        "print(run_id)\n"
        "MlflowTracker(client, run_id, hydra_dir=None)\n"
        "raise RuntimeError('the search crashed')\n"
    )
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert result.returncode == 1 and "the search crashed" in result.stderr
    assert MlflowClient(uri).get_run(result.stdout.strip()).info.status == "FAILED"
