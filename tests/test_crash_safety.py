"""A sandbox worker killed from outside (SIGKILL) costs no evaluation: the request is retried
on a fresh worker, and the search around it goes on with every program present once."""

import concurrent.futures
import dataclasses
import os
import signal
import threading

from conftest import EXAMPLES, children_of, compose, same_outcome, wait_for

from colmo.evaluation import EvalRequest
from colmo.executor import LocalExecutor
from colmo.program import parametrize
from colmo.search import Search
from colmo.specs import load_spec
from colmo.store import ProgramStore


def paper_request(episodes: int) -> EvalRequest:
    spec = load_spec("pendulum.py")
    program = parametrize((EXAMPLES / "paper_pendulum.py").read_text())
    return EvalRequest(str(spec.path), (), tuple(range(episodes)), program.skeleton, program.values, spec.allowed_imports, timeout_s=120)


def kill_worker_mid_evaluation(executor: LocalExecutor) -> int:
    """Kill the worker once it has started an evaluation (it has forked an evaluation process)."""
    pid = wait_for(lambda: next((p for p in executor.worker_pids() if children_of(p)), None), what="an evaluation in progress")
    os.kill(pid, signal.SIGKILL)
    return pid


def test_a_killed_worker_costs_no_evaluation():
    request = paper_request(episodes=40)
    with LocalExecutor(1, memory_mb=1024) as executor, concurrent.futures.ThreadPoolExecutor(1) as threads:
        expected = executor.evaluate([request])[0]
        future = threads.submit(executor.evaluate, [request])
        killed = kill_worker_mid_evaluation(executor)
        [result] = future.result()
        assert executor.worker_pids() and killed not in executor.worker_pids()  # a fresh worker took over
    assert same_outcome(result, expected) and result.failure is None


def test_a_request_that_keeps_losing_its_worker_fails_with_the_reason():
    request = dataclasses.replace(paper_request(episodes=40), label="sample 7")
    with LocalExecutor(1, memory_mb=1024, max_retries=1) as executor, concurrent.futures.ThreadPoolExecutor(1) as threads:
        executor.evaluate([paper_request(episodes=1)])  # a worker is up
        future = threads.submit(executor.evaluate, [request])
        first = kill_worker_mid_evaluation(executor)
        wait_for(lambda: [p for p in executor.worker_pids() if p != first and children_of(p)], what="the retry")
        kill_worker_mid_evaluation(executor)
        [result] = future.result()
    assert result.failure.startswith("lost worker: the worker was killed (SIGKILL)") and result.failure.endswith("after 1 retries")
    assert "; it held sample 7, " in result.failure  # which program held the lost worker


def test_search_survives_workers_killed_at_random_moments(tmp_path):
    kills = 3  # and as many retries, so that even one request killed every time is not lost
    cfg = compose(
        "search", "search.max_samples=16", "gfo.budget=6", "task.episodes=3", "tracker=none", f"executor.max_retries={kills}",
        "executor.workers=2", "search.progress=false", "heldout.episodes=3", "finish.render=false", "finish.simplify=false",
    )
    search = Search(cfg, tmp_path)
    killed = []
    finished = threading.Event()

    def killer():
        # Polls for a worker in mid-evaluation (however long a loaded machine takes to get
        # there), kills it, and lets the search go on a while before the next kill.
        while len(killed) < kills and not finished.is_set():
            busy = [pid for pid in search.executor.worker_pids() if children_of(pid)]
            if busy:
                os.kill(busy[0], signal.SIGKILL)
                killed.append(busy[0])
                finished.wait(1.0)
            else:
                finished.wait(0.01)

    thread = threading.Thread(target=killer)
    thread.start()
    try:
        summary = search.run()
    finally:
        finished.set()
        thread.join()
    assert killed, "no worker was running to kill"
    store = ProgramStore(tmp_path / "programs.db")
    records = [r for r in store.records() if r.sample >= 0]
    store.close()
    # 16 model calls; a duplicate generated again is one sample of several calls.
    assert [r.sample for r in records] == list(range(len(records))) and summary.samples == sum(r.model_calls for r in records) == 16
    assert not [r.failure for r in records if r.failure and ("killed" in r.failure or "lost" in r.failure)]
