"""MLflow tracking: a real 2-job `-m` sweep read back from the SQLite store (one parent run, two
children, unique names, metric columns, a classic ML experiment, the programs table) and through
`mlflow server`, the report made from it, a tracked `colmo-optimize`, and the tracker's end
states and table writes on a store of its own."""

import dataclasses
import importlib.metadata
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

from colmo.record import BatchReport, SampleRecord, Summary
from colmo.track import (
    CLASSIC_ML,
    EXPERIMENT_KIND_TAG,
    PROGRAM_COLUMNS,
    VIEW_TAG,
    MlflowTracker,
    TrackedRun,
    browse_hint,
    flatten,
    open_experiment,
    retry_locked,
)

# Small, with the whole finish (simplification, video and plot) that a run logs at its end.
TINY = (
    "search.max_samples=4", "llm.batch_size=2", "gfo.budget=2", "task.episodes=1", "heldout.episodes=2",
    "executor.workers=1", "search.progress=false",
)
# The run list's columns a person compares runs by.
KEY_METRICS = ("best_score", "best_heldout_score", "samples", "programs_evaluated", "valid_program_rate", "evaluations_per_second", "steps", "seconds")


def shown_digits(value: float) -> bool:
    """A metric as MLflow's run list shows it: at most 4 significant digits, or an integer."""
    return value == int(value) or float(f"{value:.4g}") == value


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
    loads = lambda text: json.loads(text) if text is not None else None  # noqa: E731
    fields = {"parents": "parent_keys"}
    return [
        tuple(_rounded(loads(r[fields.get(c, c)]) if c in ("params", "parents") else r[fields.get(c, c)]) for c in PROGRAM_COLUMNS)
        for r in rows
    ]


def table_rows(table: pd.DataFrame) -> list[tuple]:
    table = table.astype(object).where(table.notna(), None)  # JSON null comes back as NaN
    return [tuple(_rounded(row[c]) for c in PROGRAM_COLUMNS) for _, row in table.sort_values("sample").iterrows()]


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    """Two tiny jobs (no GFO and (1+1)-ES) through Hydra's basic launcher, tracked into <cwd>/mlruns.db."""
    cwd = tmp_path_factory.mktemp("sweep")
    result = subprocess.run(
        [sys.executable, "-m", "colmo", "-m", "gfo=none,oneplusone", "seed=0", *TINY, f"hydra.sweep.dir={cwd / 'multirun'}"],
        cwd=cwd, capture_output=True, text=True, timeout=600,
    )
    assert result.returncode == 0, result.stderr
    client = MlflowClient(f"sqlite:///{cwd / 'mlruns.db'}")
    experiment = client.get_experiment_by_name("pendulum")
    runs = client.search_runs([experiment.experiment_id], order_by=["attributes.start_time ASC"])
    return cwd, client, experiment, runs


def test_a_sweep_is_one_parent_run_with_a_child_per_job(sweep):
    cwd, client, experiment, runs = sweep
    assert experiment.tags[EXPERIMENT_KIND_TAG] == CLASSIC_ML  # MLflow 3.0-3.4's UI opens it in the classic ML view
    view = json.loads(experiment.tags[VIEW_TAG])  # the run list's columns in MLflow's UI (browse_hint)
    assert {f"metrics.`{m}`" for m in ("best_score", "best_heldout_score", "samples", "seconds", "runs")} <= set(view["selectedColumns"])
    # Seed, generator and the scores first; each job a row of its GFO method's open group, best first
    # (nested under the sweep's parent, the jobs hid in its collapsed row).
    assert view["columnOrder"][:4] == ["params.`seed`", "params.`llm.name`", "metrics.`best_score`", "metrics.`best_heldout_score`"]
    assert (view["orderByKey"], view["orderByAsc"]) == ("metrics.`best_score`", False)
    assert view["groupBy"]["groupByKeys"] == [{"mode": "param", "groupByData": "gfo.method"}]
    assert {"param.gfo.method.none", "param.gfo.method.oneplusone", "param.gfo.method.bo"} <= {k for k, v in view["groupsExpanded"].items() if v}
    assert experiment.tags["mlflow.experiment.primaryMetric.name"] == "best_score"  # the chart view opens on it
    assert experiment.tags["mlflow.experiment.primaryMetric.greaterIsBetter"] == "True"
    parents = [run for run in runs if "mlflow.parentRunId" not in run.data.tags]
    children = [run for run in runs if "mlflow.parentRunId" in run.data.tags]
    assert len(parents) == 1 and len(children) == 2
    parent = parents[0]
    assert {child.data.tags["mlflow.parentRunId"] for child in children} == {parent.info.run_id}
    assert parent.info.run_name.startswith("pendulum-sweep-") and parent.info.status == "FINISHED"
    assert parent.data.tags["colmo.sweep_dir"] == str(cwd / "multirun")
    assert "gfo=none,oneplusone" in parent.data.tags["overrides"].split()
    assert parent.data.metrics["runs"] == 2
    assert parent.data.metrics["best_score"] == max(child.data.metrics["best_score"] for child in children)
    assert next(iter(parent.data.metrics)) == "best_score"

    names = [child.info.run_name for child in children]
    assert len(set(names)) == 2
    for name, gfo, job in zip(sorted(names), ("none", "oneplusone"), (0, 1)):
        prefix, clock, number = name.rsplit("-", 2)
        assert prefix == f"pendulum-{gfo}-mutate-s0" and len(clock) == 6 and clock.isdigit() and number == f"j{job}"


def test_sweep_jobs_log_params_tags_metric_columns_programs_and_artifacts(sweep, monkeypatch):
    cwd, client, experiment, runs = sweep
    # MlflowClient.load_table finds runs through the global tracking URI, whatever the client's.
    monkeypatch.setenv("MLFLOW_TRACKING_URI", client.tracking_uri)
    assert experiment.artifact_location == str(cwd / "mlartifacts" / "pendulum")
    children = [run for run in runs if "mlflow.parentRunId" in run.data.tags]
    for run in children:
        run_dir = Path(run.data.tags["colmo.run_dir"])
        assert run_dir.parent == cwd / "multirun" and run.info.status == "FINISHED"
        summary = json.loads((run_dir / "summary.json").read_text())

        # params: the job's resolved config, flattened, and the task's dimensions
        config = OmegaConf.to_container(OmegaConf.load(run_dir / ".hydra" / "config.yaml"), resolve=True)
        assert run.data.params == flatten(config) | {"spec.observation_size": "3", "spec.action_size": "1"}
        tags = run.data.tags
        assert (tags["task"], tags["llm"], tags["seed"], tags["colmo.command"]) == ("pendulum", "mutate", "0", "search")
        assert f"gfo={tags['gfo']}" in tags["overrides"].split()
        assert tags["colmo.version"] and len(tags.get("mlflow.source.git.commit", "x" * 40)) == 40
        assert tags["colmo.lib.mujoco"] == summary["provenance"]["libraries"]["mujoco"] == importlib.metadata.version("mujoco")

        # metrics: the key ones as run-list columns (their latest values), best score first (what
        # MLflow's compare page plots first), rounded as they are shown ...
        metrics = run.data.metrics
        assert set(KEY_METRICS) <= set(metrics), set(KEY_METRICS) - set(metrics)
        assert next(iter(metrics)) == "best_score"
        for name in ("best_score", "best_heldout_score", "samples", "programs_evaluated", "evaluations", "steps"):
            assert metrics[name] == pytest.approx(summary[name], rel=5e-4), name
        assert all(shown_digits(value) for value in metrics.values()), metrics
        for name in ("seconds", "evaluations_per_second", "valid_program_rate"):
            assert all(shown_digits(m.value) for m in client.get_metric_history(run.info.run_id, name)), name
        # ... and one point per batch, at step = samples so far
        for name in ("best_score", "evaluations", "seconds", "programs_evaluated", "best_score_island_0"):
            assert [m.step for m in client.get_metric_history(run.info.run_id, name)] == [2, 4], name
        islands = [k for k in metrics if k.startswith("best_score_island_")]
        assert len(islands) == config["database"]["num_islands"]

        # every sample once, in one table with the code in full, registered once
        expected = program_rows(run_dir)
        assert len(expected) == 4
        table = client.load_table(experiment.experiment_id, "programs.json", run_ids=[run.info.run_id])
        assert table_rows(table) == expected
        assert json.loads(tags["mlflow.loggedArtifacts"]) == [{"path": "programs.json", "type": "table"}]
        heldout = {entry["sample"]: entry["heldout_score"] for entry in summary["heldout"]}
        for _, row in table.iterrows():
            if row["sample"] in heldout and heldout[row["sample"]] is not None:
                assert row["heldout_score"] == pytest.approx(heldout[row["sample"]])

        # artifacts: every file the run made that the README lists
        names = {f.path for folder in (None, "hydra", "best_policy") for f in client.list_artifacts(run.info.run_id, folder)}
        assert {"best_policy.py", "summary.json", "best_so_far.png", "programs.json", "programs.html", "hydra/config.yaml", "hydra/overrides.yaml"} <= names
        assert (run_dir / "simplified_policy.py").is_file() and "simplified_policy.py" in names
        # the best policy's readability report, as the summary has it
        readable = summary["readability"]
        assert metrics["readability_lines"] == readable["lines"] >= 1 and metrics["readability_misleading_names"] == readable["misleading_names"]
        assert metrics["readability_simplified_lines"] == readable["simplified_lines"]
        media = summary["media"]
        assert {"plot", "video"} <= set(media), media  # the best policy on a held-out episode, made by every job
        assert {f"best_policy/{Path(media['plot']).name}", f"best_policy/{Path(media['video']).name}"} <= names

        # where to look: the `mlflow ui` command for this store and the address it serves the view at
        log = (run_dir / "colmo.log").read_text()
        ui = f"/#/experiments/{experiment.experiment_id}/runs?workflowType=machine_learning&viewStateShareKey=colmo"
        assert f"browse: mlflow ui --backend-store-uri sqlite:///{cwd / 'mlruns.db'} --port 5000, then http://127.0.0.1:5000{ui}" in log
        assert not any(name.startswith("programs/") for name in names)  # no per-batch files
        best = client.download_artifacts(run.info.run_id, "best_policy.py", str(cwd / run.info.run_id))
        assert Path(best).read_text() == (run_dir / "best_policy.py").read_text()

    # load_table joins the table across runs
    both = client.load_table(experiment.experiment_id, "programs.json", run_ids=[r.info.run_id for r in children], extra_columns=["run_id"])
    assert both.groupby("run_id").size().to_dict() == {r.info.run_id: 4 for r in children}


def test_the_report_reads_the_sweep(sweep):
    cwd, _, _, runs = sweep
    result = subprocess.run(
        [sys.executable, "-m", "colmo.report", "experiment=pendulum", "axis=evaluations", "out=report"],
        cwd=cwd, capture_output=True, text=True, timeout=300,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "report/report.md" and not result.stderr.strip()  # no download progress bars
    markdown = (cwd / "report" / "report.md").read_text()
    assert "2 search runs read from MLflow" in markdown and "2 count, 0 left out" in markdown
    assert "| pendulum | 3 | 1 | oneplusone, budget 2 |" in markdown


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _post(url: str, body: dict) -> dict:
    request = urllib.request.Request(url, json.dumps(body).encode(), {"Content-Type": "application/json"})
    with urllib.request.urlopen(request, timeout=10) as response:
        return json.load(response)


def test_mlflow_server_lists_the_runs_nested_over_rest(sweep):
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
        deadline = time.monotonic() + 120
        while True:
            try:
                with urllib.request.urlopen(f"{base}/health", timeout=2) as response:
                    if response.status == 200:
                        break
            except OSError:
                assert server.poll() is None, "mlflow server exited"
                assert time.monotonic() < deadline, "mlflow server not ready after 120 s"
                time.sleep(0.5)
        experiments = _post(f"{base}/api/2.0/mlflow/experiments/search", {"max_results": 10})["experiments"]
        experiment = next(e for e in experiments if e["name"] == "pendulum")
        assert {"key": EXPERIMENT_KIND_TAG, "value": CLASSIC_ML} in experiment["tags"]
        found = _post(f"{base}/api/2.0/mlflow/runs/search", {"experiment_ids": [experiment["experiment_id"]]})["runs"]
        assert sorted(r["info"]["run_name"] for r in found) == sorted(r.info.run_name for r in runs)
        for run in found:
            assert run["info"]["status"] == "FINISHED"
            assert run["data"]["metrics"][0]["key"] == "best_score"  # what the compare page plots first
    finally:
        os.killpg(server.pid, signal.SIGTERM)
        try:
            server.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(server.pid, signal.SIGKILL)
            server.wait()


def test_colmo_optimize_logs_one_run(sweep, examples):
    cwd, client, _, _ = sweep  # its store, in an experiment of its own
    result = subprocess.run(
        [sys.executable, "-m", "colmo.optimize", f"policy_file={examples / 'pendulum_mistuned.py'}", "tracker=mlflow",
         "tracker.experiment=optimize", "gfo.budget=3", "task.episodes=1", "heldout.episodes=2", "executor.workers=1",
         "hydra.run.dir=optimized"],
        cwd=cwd, capture_output=True, text=True, timeout=300,
    )
    assert result.returncode == 0, result.stderr
    assert "MLflow run" in result.stderr
    experiment = client.get_experiment_by_name("optimize")
    assert experiment.tags[EXPERIMENT_KIND_TAG] == CLASSIC_ML
    (run,) = client.search_runs([experiment.experiment_id])
    summary = json.loads((cwd / "optimized" / "result.json").read_text())
    assert run.info.status == "FINISHED" and run.data.tags["colmo.command"] == "optimize"
    assert run.info.run_name.startswith("pendulum-optimize-oneplusone-pendulum_mistuned-s0-")
    assert run.data.metrics["score"] == pytest.approx(summary["score"]) and run.data.metrics["evaluations"] == summary["evaluations"]
    assert run.data.params["gfo.budget"] == "3"
    assert {f.path for f in client.list_artifacts(run.info.run_id)} >= {"tuned_policy.py", "result.json", "hydra"}


# -- the tracker on a store of its own -------------------------------------------------------------


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
    assert MlflowClient(uri).get_experiment(results[0]).tags[EXPERIMENT_KIND_TAG] == CLASSIC_ML


def test_an_experiment_made_before_gets_the_classic_kind_and_colmos_view(store):
    uri = store
    old_view = json.dumps({"selectedColumns": ["metrics.`best_score`"], "orderByKey": "metrics.`best_score`", "orderByAsc": False})
    experiment_id = MlflowClient(uri).create_experiment(
        "old", tags={VIEW_TAG: old_view, "mlflow.experiment.primaryMetric.name": "best_heldout_score"},  # an older colmo's view; a person's choice
    )
    assert open_experiment(uri, "old")[1] == experiment_id
    tags = MlflowClient(uri).get_experiment(experiment_id).tags
    assert tags[EXPERIMENT_KIND_TAG] == CLASSIC_ML
    assert json.loads(tags[VIEW_TAG])["groupBy"]["groupByKeys"][0]["groupByData"] == "gfo.method"
    assert tags["mlflow.experiment.primaryMetric.name"] == "best_heldout_score"


def test_the_ui_address_follows_the_tracking_uri():
    ui = "/#/experiments/7/runs?workflowType=machine_learning&viewStateShareKey=colmo"
    assert browse_hint("http://mlflow.lab:8080/", "7") == f"http://mlflow.lab:8080{ui}"
    assert browse_hint("https://example.org/mlflow", "7") == f"https://example.org/mlflow{ui}"
    assert browse_hint("postgresql://db/mlflow", "7") == f"mlflow ui --backend-store-uri postgresql://db/mlflow --port 5000, then http://127.0.0.1:5000{ui}"


def _record(sample: int, score: float) -> SampleRecord:
    return SampleRecord(sample=sample, batch=sample, status="evaluated", island=sample % 2, parent_keys=("k",),
                        generator="mutate", raw="", key=f"k{sample}", code="def policy(obs):\n    return 0.0\n",
                        params=(0.5,), score=score)


def _report(batch: int, score: float) -> BatchReport:
    counts = dict(programs_evaluated=batch + 1, duplicates_skipped=0, failures=0, unusable_outputs=0, interrupted=0,
                  evaluations=3 * (batch + 1), steps=100 * (batch + 1))
    rates = dict(valid_program_rate=1.0, duplicate_rate=0.0, tokens_per_second=0.0, evaluations_per_second=5.0,
                 generator_busy=0.1, evaluator_busy=0.9, seconds=float(batch + 1), worker_seconds=1.8 * (batch + 1), steps_per_worker_second=55.6, load=2.0, generation_seconds=0.1, evaluation_seconds=0.2)
    return BatchReport(batch=batch, samples=batch + 1, best_score=score, best_per_island=(score, 1.0), queue_depth=0, **counts, **rates)


def _summary(run_dir: Path, stop_reason: str) -> Summary:
    values = dict(
        task="pendulum", best_score=3.0, best_heldout_score=2.5, best_key="k1", best_code=None, samples=2, programs_evaluated=2,
        evaluations=6, steps=200, seconds=2.0, best_so_far=((0, 1.0), (2, 3.0)), stop_reason=stop_reason, run_dir=str(run_dir),
        heldout=({"sample": 1, "key": "k1", "score": 3.0, "heldout_score": 2.5, "heldout_failure": None},),
    )
    # The other totals as zeros: the tracker logs them with each batch, not from the summary.
    required = [f for f in dataclasses.fields(Summary) if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING]
    return Summary(**{f.name: values.get(f.name, 0) for f in required}, **{k: v for k, v in values.items() if k not in {f.name for f in required}})


@pytest.fixture(scope="module")
def store(tmp_path_factory) -> str:
    """One MLflow store for the tests below (creating MLflow's schema takes seconds)."""
    uri = f"sqlite:///{tmp_path_factory.mktemp('store') / 'mlruns.db'}"
    open_experiment(uri, "unit")
    return uri


def _tracked(uri: str) -> TrackedRun:
    client, experiment_id = open_experiment(uri, "unit")
    return TrackedRun(client, experiment_id, client.create_run(experiment_id).info.run_id, "unit", None, None, None)


def test_an_interrupted_search_ends_killed_with_its_programs_table_rewritten_in_place(store, tmp_path, monkeypatch):
    uri = store
    monkeypatch.setenv("MLFLOW_TRACKING_URI", uri)  # for load_table, as above
    run = _tracked(uri)
    tracker = MlflowTracker(run, table_every_s=0.0)  # rewrite the table after every batch
    for batch, score in enumerate([1.0, 3.0]):
        tracker.on_batch(_report(batch, score), [_record(batch, score)])
        table = run.client.load_table(run.experiment_id, "programs.json", run_ids=[run.run_id])
        assert table["sample"].tolist() == list(range(batch + 1))  # the whole table so far, once
    tracker.on_finish(_summary(tmp_path, "interrupted"))
    client = run.client
    finished = client.get_run(run.run_id)
    assert finished.info.status == "KILLED"
    assert [(m.step, m.value) for m in client.get_metric_history(run.run_id, "best_score_island_0")] == [(1, 1.0), (2, 3.0)]
    assert finished.data.metrics["best_heldout_score"] == 2.5 and finished.data.metrics["samples"] == 2 and finished.data.metrics["seconds"] == 2.0
    table = client.load_table(run.experiment_id, "programs.json", run_ids=[run.run_id])
    assert table["sample"].tolist() == [0, 1] and table["heldout_score"].tolist()[1] == 2.5
    assert table["code"][0] == "def policy(obs):\n    return 0.0\n"  # in full, newlines and all
    assert json.loads(finished.data.tags["mlflow.loggedArtifacts"]) == [{"path": "programs.json", "type": "table"}]
    assert {f.path for f in client.list_artifacts(run.run_id)} == {"programs.json", "programs.html", "best_so_far.png"}
    page = Path(client.download_artifacts(run.run_id, "programs.html", str(tmp_path)))
    text = page.read_text()
    assert text.index("<td>1</td><td>3.00</td><td>2.50</td>") < text.index("<td>0</td><td>1.00</td>")  # best first
    assert "<pre>def policy(obs):\n    return 0.0\n</pre>" in text


def test_the_table_is_rewritten_at_most_every_table_every_s(store, tmp_path, monkeypatch):
    uri = store
    monkeypatch.setenv("MLFLOW_TRACKING_URI", uri)
    run = _tracked(uri)
    tracker = MlflowTracker(run, table_every_s=3600.0)
    for batch in range(3):
        tracker.on_batch(_report(batch, 1.0), [_record(batch, 1.0)])
    # Written at the first batch only (then not for an hour); the end writes every row.
    assert run.client.load_table(run.experiment_id, "programs.json", run_ids=[run.run_id])["sample"].tolist() == [0]
    tracker.on_finish(_summary(tmp_path, "max_samples"))
    assert run.client.get_run(run.run_id).info.status == "FINISHED"
    assert run.client.load_table(run.experiment_id, "programs.json", run_ids=[run.run_id])["sample"].tolist() == [0, 1, 2]


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


def test_a_process_that_dies_mid_search_leaves_its_run_failed(store):
    uri = store
    script = (
        "from colmo.track import MlflowTracker, TrackedRun, open_experiment\n"
        f"client, experiment_id = open_experiment({uri!r}, 'unit')\n"
        "run_id = client.create_run(experiment_id).info.run_id\n"
        "print(run_id)\n"
        "MlflowTracker(TrackedRun(client, experiment_id, run_id, 'unit', None, None, None))\n"
        "raise RuntimeError('the search crashed')\n"
    )
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert result.returncode == 1 and "the search crashed" in result.stderr
    assert MlflowClient(uri).get_run(result.stdout.strip()).info.status == "FAILED"


def test_a_resumed_search_goes_on_in_its_mlflow_run(tmp_path, monkeypatch):
    """A search stopped at 2 samples and resumed to 4, from another directory, is one MLflow run:
    its table holds every sample, its metrics go on at later steps, the resuming overrides are a tag."""
    base = [sys.executable, "-m", "colmo", *TINY, "finish.render=false", "finish.simplify=false"]
    first = subprocess.run([*base, "search.max_samples=2", f"hydra.run.dir={tmp_path / 'run'}"], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert first.returncode == 0, first.stderr[-3000:]
    elsewhere = tmp_path / "elsewhere"  # resumed from another directory: the run goes on in the store it began in
    elsewhere.mkdir()
    again = subprocess.run(
        [*base, "search.max_samples=4", f"resume={tmp_path / 'run'}", f"hydra.run.dir={elsewhere / 'again'}"], cwd=elsewhere, capture_output=True, text=True, timeout=600,
    )
    assert again.returncode == 0, again.stderr[-3000:]
    assert "(goes on: the search resumes)" in again.stderr and not (elsewhere / "mlruns.db").exists()
    uri = f"sqlite:///{tmp_path / 'mlruns.db'}"
    monkeypatch.setenv("MLFLOW_TRACKING_URI", uri)  # for load_table
    client = MlflowClient(uri)
    [run] = client.search_runs([client.get_experiment_by_name("pendulum").experiment_id])
    assert run.info.status == "FINISHED"
    assert "search.max_samples=4" in run.data.tags["colmo.resumed"] and run.data.tags["colmo.run_dir"] == str((tmp_path / "run").resolve())
    assert [m.step for m in client.get_metric_history(run.info.run_id, "samples")] == [2, 4]
    table = client.load_table(run.info.experiment_id, "programs.json", run_ids=[run.info.run_id])
    assert table_rows(table) == program_rows(tmp_path / "run")
    assert [row[0] for row in program_rows(tmp_path / "run")] == [0, 1, 2, 3]


def test_a_continued_tracker_keeps_the_rows_and_curves_logged_before(store, tmp_path, monkeypatch):
    monkeypatch.setenv("MLFLOW_TRACKING_URI", store)
    run = _tracked(store)
    before = MlflowTracker(run, table_every_s=0.0)
    for batch, score in enumerate([1.0, 3.0]):
        before.on_batch(_report(batch, score), [_record(batch, score)])
    before.on_finish(_summary(tmp_path, "interrupted"))
    after = MlflowTracker(dataclasses.replace(run, continued=True), table_every_s=3600.0)
    assert (after.steps, after.best, after.seconds, after.per_island) == ([1, 2], [1.0, 3.0], [1.0, 2.0], [[1.0, 1.0], [3.0, 1.0]])
    after.on_batch(_report(2, 4.0), [_record(2, 4.0)])
    after.on_finish(_summary(tmp_path, "max_samples"))
    assert run.client.load_table(run.experiment_id, "programs.json", run_ids=[run.run_id])["sample"].tolist() == [0, 1, 2]
    assert run.client.get_run(run.run_id).info.status == "FINISHED"


def test_a_search_of_two_generators_logs_each_ones_samples_best_and_island_bests(store, tmp_path, monkeypatch):
    monkeypatch.setenv("MLFLOW_TRACKING_URI", store)
    run = _tracked(store)
    tracker = MlflowTracker(run, table_every_s=0.0)
    tracker.on_batch(_report(0, 1.0), [_record(0, 1.0)])
    split = {
        "mutate": {"samples": 40, "programs_evaluated": 38, "best_score": 3.0, "island_bests": 9, "generation_seconds": 1.0, "evaluation_seconds": 80.0},
        "llamacpp": {"samples": 4, "programs_evaluated": 2, "best_score": 2.0, "island_bests": 1, "generation_seconds": 90.0, "evaluation_seconds": 9.0},
    }
    tracker.on_finish(dataclasses.replace(_summary(tmp_path, "max_seconds"), by_generator=split))
    metrics = run.client.get_run(run.run_id).data.metrics
    assert {name: metrics[name] for name in metrics if name.endswith(("_mutate", "_llamacpp"))} == {
        "samples_mutate": 40, "programs_evaluated_mutate": 38, "best_score_mutate": 3.0, "island_bests_mutate": 9,
        "samples_llamacpp": 4, "programs_evaluated_llamacpp": 2, "best_score_llamacpp": 2.0, "island_bests_llamacpp": 1,
    }
