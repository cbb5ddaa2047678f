"""A sandbox worker killed from outside (SIGKILL) costs no evaluation: the request is retried
on a fresh worker, and the search around it goes on with every program present once."""

import os
import signal
import threading
import time

from conftest import EXAMPLES, compose
from colmo.program import parametrize
from colmo.sandbox import EvalRequest, WorkerPool
from colmo.search import Search
from colmo.spec import load_spec
from colmo.store import ProgramStore


def paper_request(episodes: int) -> EvalRequest:
    spec = load_spec("pendulum.py")
    program = parametrize((EXAMPLES / "paper_pendulum.py").read_text())
    return EvalRequest(str(spec.path), (), tuple(range(episodes)), program.skeleton, program.values, spec.allowed_imports)


def kill_busy_worker(pool: WorkerPool, index: int = 0, after: float = 0.3) -> int:
    time.sleep(after)
    pid = pool.workers[index].process.pid
    os.kill(pid, signal.SIGKILL)
    return pid


def test_a_killed_worker_costs_no_evaluation():
    request = paper_request(episodes=40)
    with WorkerPool(1, timeout_s=60, memory_mb=1024) as pool:
        expected = pool.evaluate([request])[0]
        future = pool.submit(request)
        killed = kill_busy_worker(pool)
        result = future.result()
        assert pool.workers[0].process.pid != killed  # a fresh worker took over
    assert result == expected and result.failure is None


def test_a_request_that_keeps_losing_its_worker_fails_with_the_reason():
    request = paper_request(episodes=40)
    with WorkerPool(1, timeout_s=60, memory_mb=1024) as pool:
        pool.evaluate([paper_request(episodes=1)])  # a worker is up
        future = pool.submit(request)
        kill_busy_worker(pool)
        while pool.workers[0] is None or pool.workers[0].process.pid is None:
            time.sleep(0.01)
        kill_busy_worker(pool, after=0.5)
        result = future.result()
    assert result.failure.startswith("crash: the worker was killed (SIGKILL)")


def test_search_survives_workers_killed_at_random_moments(tmp_path):
    cfg = compose(
        "search", "search.max_samples=16", "gfo.budget=6", "task.episodes=3", "tracker=none",
        "executor.workers=2", "search.progress=false",
    )
    search = Search(cfg, tmp_path)
    killed = []

    def killer():
        for delay in (1.0, 1.5, 2.0):
            time.sleep(delay)
            busy = [w for w in search.pool.workers if w is not None and w.process.poll() is None]
            if busy:
                os.kill(busy[0].process.pid, signal.SIGKILL)
                killed.append(busy[0].process.pid)

    thread = threading.Thread(target=killer)
    thread.start()
    summary = search.run()
    thread.join()
    assert killed, "no worker was running to kill"
    store = ProgramStore(tmp_path / "programs.db")
    records = [r for r in store.records() if r.sample >= 0]
    store.close()
    assert [r.sample for r in records] == list(range(16)) and summary["samples"] == 16
    assert not [r.failure for r in records if r.failure and "killed" in r.failure]
