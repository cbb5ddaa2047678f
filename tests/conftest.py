"""Shared test set-up: the offline Menagerie tree, and helpers to run colmo's command lines."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
EXAMPLES = REPO / "examples"
_MENAGERIE = REPO.parent / "shared" / "menagerie"
if "MENAGERIE_ROOT" not in os.environ and _MENAGERIE.is_dir():
    os.environ["MENAGERIE_ROOT"] = str(_MENAGERIE)


def run_colmo(module: str, *overrides: str, cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess:
    """Run `python -m <module> <overrides>` as a user would, in `cwd`."""
    return subprocess.run(
        [sys.executable, "-m", module, *overrides], cwd=cwd, capture_output=True, text=True, timeout=timeout
    )


def last_json_line(stdout: str) -> dict:
    return json.loads(stdout.strip().splitlines()[-1])


@pytest.fixture
def examples() -> Path:
    return EXAMPLES


def compose(config_name: str, *overrides: str):
    """A config composed from colmo's bundled configs, as validated dataclasses."""
    from hydra import compose as hydra_compose
    from hydra import initialize_config_module

    from colmo.config import CONFIG_MODULE, register_schemas, to_objects

    register_schemas()
    with initialize_config_module(config_module=CONFIG_MODULE, version_base="1.3"):
        return to_objects(hydra_compose(config_name=config_name, overrides=list(overrides)))


class FakeOpenAIServer:
    """An OpenAI-compatible chat-completions server on 127.0.0.1 whose next answers can be
    scripted: "500", "429", "400", "garbage" (not JSON), "html" (not a completion), "empty",
    "stall" (answers only after `stall_s`, past any sensible client timeout)."""

    def __init__(self, honour_n: bool = True, delay: float = 0.0, stall_s: float = 3.0):
        self.requests: list[dict] = []
        self.script: list[str] = []
        self.max_active = 0
        self._active = 0
        self._lock = threading.Lock()
        owner = self

        class Handler(BaseHTTPRequestHandler):
            def log_message(self, *args):
                pass

            def do_POST(self):
                body = json.loads(self.rfile.read(int(self.headers["Content-Length"])))
                with owner._lock:
                    owner.requests.append({"path": self.path, "authorization": self.headers.get("Authorization"), "body": body})
                    behaviour = owner.script.pop(0) if owner.script else "ok"
                    owner._active += 1
                    owner.max_active = max(owner.max_active, owner._active)
                time.sleep(stall_s if behaviour == "stall" else delay)
                with owner._lock:
                    owner._active -= 1
                n = body.get("n", 1) if honour_n else 1
                if behaviour in ("500", "429", "400"):
                    self.reply(int(behaviour), {"error": {"message": f"scripted {behaviour}", "type": "error"}})
                elif behaviour == "garbage":
                    self.reply(200, b"{not json", content_type="application/json")
                elif behaviour == "html":
                    self.reply(200, b"<html>proxy error</html>", content_type="text/html")
                else:
                    content = "" if behaviour == "empty" else None
                    self.reply(200, completion(body, n, content))

            def reply(self, status, payload, content_type="application/json"):
                data = payload if isinstance(payload, bytes) else json.dumps(payload).encode()
                self.send_response(status)
                self.send_header("Content-Type", content_type)
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data)

        self._server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self._thread = threading.Thread(target=self._server.serve_forever, kwargs={"poll_interval": 0.01}, daemon=True)
        self._thread.start()
        self.url = f"http://127.0.0.1:{self._server.server_address[1]}/v1"

    def close(self) -> None:
        self._server.shutdown()
        self._server.server_close()


def completion(body: dict, n: int, content: str | None) -> dict:
    answers = [f"```python\ndef policy(obs):\n    return {i}.0 * obs[0]\n```" if content is None else content for i in range(n)]
    choices = [
        {"index": i, "message": {"role": "assistant", "content": answer}, "finish_reason": "stop"}
        for i, answer in enumerate(answers)
    ]
    return {
        "id": "chatcmpl-test", "object": "chat.completion", "created": int(time.time()), "model": body["model"],
        "choices": choices, "usage": {"prompt_tokens": 10, "completion_tokens": 5 * n, "total_tokens": 10 + 5 * n},
    }
