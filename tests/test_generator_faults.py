"""A search whose OpenAI-compatible servers fail on purpose: it retries with backoff, keeps
evaluating what it has, then stops cleanly with its state saved for `resume=`."""

import json
import logging
import re
import socket

from conftest import FakeOpenAIServer, compose

from colmo.search import Search
from colmo.store import ProgramStore


def test_failing_servers_are_retried_then_the_search_stops_cleanly(tmp_path, caplog):
    server = FakeOpenAIServer(stall_s=3.0)
    refusing = socket.socket()
    refusing.bind(("127.0.0.1", 0))  # bound, never listening: connections are refused
    dead_url = f"http://127.0.0.1:{refusing.getsockname()[1]}/v1"
    # The first request answers; then every request stalls, fails with 500, or returns garbage.
    server.script = ["ok"] + ["500", "garbage", "stall", "500", "html", "empty"] * 10
    try:
        cfg = compose(
            "search", "llm=openai", f"llm.base_url=[{server.url},{dead_url}]", "llm.model=test-model",
            "llm.batch_size=2", "llm.max_retries=2", "llm.backoff_s=0.01", "llm.max_backoff_s=0.05",
            "llm.timeout_s=1", "llm.max_consecutive_failures=8", "search.max_samples=50",
            "gfo.budget=3", "task.episodes=1", "tracker=none", "executor.workers=1", "search.progress=false", "finish.render=false", "finish.simplify=false",
        )
        with caplog.at_level(logging.WARNING, logger="colmo.generate"):
            summary = Search(cfg, tmp_path).run()
    finally:
        server.close()
        refusing.close()

    # Requests run in parallel, so the count that trips the limit may pass it by one or two.
    assert re.match(r"generator failed: no OpenAI-compatible server answered after (8|9|10) attempts", summary.stop_reason)
    retries = [r.getMessage() for r in caplog.records if "retry" in r.getMessage()]
    assert len(retries) >= 4
    reasons = " ".join(retries) + summary.stop_reason
    assert "InternalServerError" in reasons and "APIConnectionError" in reasons  # 500s and the refusing server
    # garbage (streamed, a body that is no event stream holds no chunk) or a stall
    assert "no completion text" in reasons or "APITimeoutError" in reasons
    # What was generated before the failures was evaluated and kept.
    assert summary.samples == 2
    store = ProgramStore(tmp_path / "programs.db")
    assert len([r for r in store.records() if r.sample >= 0]) == 2
    store.close()
    assert json.loads((tmp_path / "summary.json").read_text())["samples"] == 2
