"""executor=ray on a real Ray instance on this machine: the same search as executor=local, and
actors killed mid-work cost no request (retried, or recorded as failed), never a lost one."""

import importlib.util
import json
import logging
import os
import signal
import sqlite3
import sys
import threading
from pathlib import Path

import pytest
from conftest import EXAMPLES, children_of, compose, last_json_line, run_colmo, same_outcome, wait_for

from colmo.config import RayExecutorConfig
from colmo.errors import ConfigError
from colmo.evaluation import EvalRequest
from colmo.executor import LocalExecutor, make_executor
from colmo.program import parametrize
from colmo.rollout import episode_seeds
from colmo.search import Search
from colmo.specs import load_spec

requires_ray = pytest.mark.skipif(importlib.util.find_spec("ray") is None, reason="Ray is not installed: pip install 'colmo[ray]'")

TINY = ("search.max_samples=8", "gfo.budget=4", "task.episodes=2", "tracker=none", "seed=3", "executor.workers=2", "search.progress=false", "heldout.episodes=2", "finish.render=false", "finish.simplify=false")


@pytest.fixture(scope="module")
def ray_instance():
    """One local Ray instance for the module; executors find it running and leave it running."""
    import ray

    ray.init(address="local", num_cpus=2, include_dashboard=False, logging_level=logging.ERROR, log_to_driver=False)
    yield ray
    ray.shutdown()


def store_rows(run_dir: Path) -> list[tuple]:
    with sqlite3.connect(run_dir / "programs.db") as connection:
        return connection.execute("SELECT sample, status, key, score, returns FROM samples ORDER BY sample").fetchall()


def pendulum_requests(count: int, episodes: int) -> list[EvalRequest]:
    """`count` distinct evaluations of the paper's pendulum policy (constants scaled)."""
    spec = load_spec("pendulum.py")
    program = parametrize((EXAMPLES / "paper_pendulum.py").read_text())
    seeds = tuple(episode_seeds(0, episodes))
    return [
        EvalRequest(str(spec.path), (), seeds, program.skeleton, tuple(v * (0.8 + 0.05 * i) for v in program.values), spec.allowed_imports)
        for i in range(count)
    ]


def evaluating(actor: int) -> bool:
    """Whether an actor's sandbox worker is running an evaluation (has an evaluation process)."""
    return any(children_of(worker) for worker in children_of(actor))


def evaluate_while_killing(executor, requests: list[EvalRequest]) -> tuple[list, int]:
    """Evaluate `requests` and SIGKILL an actor's process while it evaluates one of them."""
    results: list = []
    batch = threading.Thread(target=lambda: results.extend(executor.evaluate(requests)))
    batch.start()
    victim = wait_for(lambda: next((pid for pid in executor.worker_pids() if evaluating(pid)), None), what="an actor at work")
    os.kill(victim, signal.SIGKILL)
    batch.join(timeout=300)
    assert not batch.is_alive(), "the batch never completed"
    return results, victim


def test_missing_ray_is_a_one_line_config_error(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # makes `import ray` fail
    with pytest.raises(ConfigError, match=r"^executor=ray needs Ray: pip install 'colmo\[ray\]'$"):
        make_executor(RayExecutorConfig())


@requires_ray
def test_a_bad_address_is_a_one_line_error(tmp_path):
    result = run_colmo("colmo.optimize", f"policy_file={EXAMPLES / 'paper_pendulum.py'}", "executor=ray", "executor.address=nonsense", cwd=tmp_path)
    assert result.returncode == 2
    assert result.stderr.strip().splitlines()[-1] == "colmo: error: executor=ray: cannot reach Ray at executor.address=nonsense: Invalid address format: nonsense"
    assert "Traceback" not in result.stderr


@pytest.fixture(scope="module")
def local_search(tmp_path_factory):
    """The summary and stored samples of the `TINY` search with executor=local: what every
    executor=ray search of this module must reproduce."""
    run_dir = tmp_path_factory.mktemp("local") / "run"
    summary = Search(compose("search", *TINY, "executor=local"), run_dir).run()
    return summary, store_rows(run_dir)


@requires_ray
def test_ray_search_equals_local_search(tmp_path, ray_instance, local_search):
    local, local_rows = local_search
    ray = Search(compose("search", *TINY, "executor=ray"), tmp_path / "ray").run()
    assert ray.samples == local.samples == 8
    assert ray.best_score == local.best_score
    assert ray.best_code == local.best_code
    ray_rows = store_rows(tmp_path / "ray")
    assert [row[0] for row in ray_rows] == list(range(-1, 8))
    assert ray_rows == local_rows
    assert sum(row[1] == "evaluated" for row in ray_rows) >= 2  # scores were compared, not just failures


@requires_ray
def test_killed_actor_requests_are_retried_on_a_replacement(ray_instance, caplog):
    requests = pendulum_requests(8, episodes=20)
    with LocalExecutor(2) as local:
        expected = local.evaluate(requests)
    executor = make_executor(RayExecutorConfig(workers=2, max_retries=2))
    try:
        with caplog.at_level(logging.WARNING, logger="colmo.executor"):
            results, victim = evaluate_while_killing(executor, requests)
        assert all(map(same_outcome, results, expected))  # every request answered once, in order, as if nothing happened
        assert all(result.failure is None for result in results)
        assert any("retrying its request (retry 1 of 2)" in message for message in caplog.messages)
        assert all(map(same_outcome, executor.evaluate(requests[:2]), expected[:2]))  # the replacement works
        wait_for(lambda: len(executor.worker_pids()) == 2, what="a replacement actor")  # it starts in the background
        assert victim not in executor.worker_pids()
    finally:
        executor.close()


@requires_ray
def test_without_retries_the_lost_request_is_recorded_as_failed(ray_instance):
    requests = pendulum_requests(8, episodes=20)
    executor = make_executor(RayExecutorConfig(workers=2, max_retries=0))
    try:
        results, _ = evaluate_while_killing(executor, requests)
    finally:
        executor.close()
    assert len(results) == len(requests)
    failures = [result.failure for result in results if result.failure]
    assert len(failures) == 1, failures
    assert failures[0].startswith("lost worker: ") and failures[0].endswith(" after 0 retries")


@requires_ray
def test_search_completes_when_an_actor_is_killed(tmp_path, ray_instance, local_search, caplog):
    search = Search(compose("search", *TINY, "executor=ray"), tmp_path / "ray")
    victim = search.executor.worker_pids()[1]
    running = threading.Thread(target=search.run)
    running.start()
    wait_for(lambda: (tmp_path / "ray" / "programs.db").is_file() and store_rows(tmp_path / "ray"), what="the starter's evaluation")
    with caplog.at_level(logging.WARNING, logger="colmo.executor"):
        os.kill(victim, signal.SIGKILL)  # the starter is in: the search is now evaluating generated programs
        running.join(timeout=300)
    assert not running.is_alive()
    summary = json.loads((tmp_path / "ray" / "summary.json").read_text())
    assert summary["samples"] == 8 and summary["stop_reason"] == "max_samples"
    assert any("retrying its request" in message for message in caplog.messages)  # its next request, or the one it held
    assert store_rows(tmp_path / "ray") == local_search[1]  # retried, so nothing changed


@requires_ray
def test_optimize_cli_starts_and_stops_its_own_ray(tmp_path):
    result = run_colmo(
        "colmo.optimize", f"policy_file={EXAMPLES / 'pendulum_mistuned.py'}", "executor=ray", "executor.workers=2",
        "gfo.budget=10", "gfo.workers=2", "task.episodes=3", cwd=tmp_path, timeout=600,  # Ray starts in 20-40 s, slower under load
    )
    assert result.returncode == 0, result.stderr
    summary = last_json_line(result.stdout)
    assert summary["evaluations"] >= 10 and summary["failure"] is None
    assert "Traceback" not in result.stderr
