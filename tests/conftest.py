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


_STARTED: list[subprocess.Popen] = []


def start_colmo(module: str, *overrides: str, cwd: Path, **popen) -> subprocess.Popen:
    """Start `python -m <module> <overrides>` in `cwd` (text pipes); a process a test leaves
    running is killed when the test ends, failed or not."""
    process = subprocess.Popen(
        [sys.executable, "-m", module, *overrides], cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **popen
    )
    _STARTED.append(process)
    return process


@pytest.fixture(autouse=True)
def no_process_left_behind():
    yield
    while _STARTED:
        process = _STARTED.pop()
        if process.poll() is None:
            process.kill()
            process.communicate()


def run_colmo(module: str, *overrides: str, cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess:
    """Run `python -m <module> <overrides>` as a user would, in `cwd`."""
    return subprocess.run(
        [sys.executable, "-m", module, *overrides], cwd=cwd, capture_output=True, text=True, timeout=timeout
    )


def limit_for_load(seconds: float) -> int:
    """A search's time limit for a test, longer on a machine loaded past twice its cores: start-up
    slows with the load, and a limit it eats ends the run "no sample searched" (right for the run,
    not what the test checks)."""
    oversubscribed = os.getloadavg()[0] / (2 * (os.cpu_count() or 1))
    return round(seconds * max(1.0, oversubscribed))


def refused(app, *argv: str) -> tuple[int, str]:
    """The exit code and the one line with which `app` (a colmo command: `colmo.__main__.main`,
    `colmo.optimize.__main__.main`, ...) refuses the command line `argv` before Hydra starts,
    checked in this process (`colmo.cli.App.check_command_line`: no interpreter and imports to
    start); the test fails if the command line would run. Relative paths are the working
    directory's, as for a user."""
    from colmo.cli import refusal

    try:
        app.check_command_line(list(argv))
    except Exception as error:  # what the app would print and exit with
        return refusal(error)
    pytest.fail(f"`{' '.join(argv)}` passes the checks: it would run")


def unavailable(reason: str, in_ci: str) -> None:
    """Skip a test whose prerequisite is missing; under CI (`CI=true`) fail instead, saying why
    the test must run there (`in_ci`)."""
    if os.environ.get("CI") == "true":
        pytest.fail(f"{reason} (CI=true: {in_ci})")
    pytest.skip(reason)


def last_json_line(stdout: str) -> dict:
    return json.loads(stdout.strip().splitlines()[-1])


@pytest.fixture
def examples() -> Path:
    return EXAMPLES


def compose(config_name: str, *overrides: str):
    """A config composed from colmo's bundled configs, as validated dataclasses."""
    from colmo.cli import compose as compose_config

    return compose_config(config_name, list(overrides))


class FakeOpenAIServer:
    """An OpenAI-compatible chat-completions server on 127.0.0.1 whose next answers can be
    scripted: "500", "429", "400", "404", "501", "garbage" (not JSON), "html" (not a completion), "empty",
    "stall" (answers only after `stall_s`, past any sensible client timeout). A request with
    `stream` is answered in server-sent chunks of a few characters, `chunk_delay` apart, unless
    `streams` is false: then it is refused with HTTP 400 naming `stream_options`, as by a server
    that takes no streaming options."""

    def __init__(self, honour_n: bool = True, delay: float = 0.0, stall_s: float = 3.0, streams: bool = True, chunk_delay: float = 0.0):
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
                if body.get("stream") and not streams and behaviour == "ok":
                    self.reply(400, {"error": {"message": "Unrecognized request argument supplied: stream_options", "type": "invalid_request_error"}})
                elif behaviour in ("500", "429", "400", "404", "501"):
                    self.reply(int(behaviour), {"error": {"message": f"scripted {behaviour}", "type": "error"}})
                elif behaviour == "garbage":
                    self.reply(200, b"{not json", content_type="application/json")
                elif behaviour == "html":
                    self.reply(200, b"<html>proxy error</html>", content_type="text/html")
                else:
                    chat = self.path.endswith("/chat/completions")
                    # /v1/completions: the body of a policy, as a code model continuing the prompt text writes it
                    answer = completion(body, n, "" if behaviour == "empty" else None) if chat else text_completion(body, n)
                    if body.get("stream"):
                        self.stream(answer, chat, bool(body.get("stream_options", {}).get("include_usage")))
                    else:
                        self.reply(200, answer)

            def stream(self, answer, chat, include_usage):
                self.send_response(200)
                self.send_header("Content-Type", "text/event-stream")
                self.end_headers()  # no length: the stream ends when the connection closes (HTTP/1.0)
                for chunk in stream_chunks(answer, chat, include_usage):
                    self.wfile.write(f"data: {json.dumps(chunk)}\n\n".encode())
                    self.wfile.flush()
                    time.sleep(chunk_delay)
                self.wfile.write(b"data: [DONE]\n\n")

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


def text_completion(body: dict, n: int) -> dict:
    choices = [{"index": i, "text": f"    return {i}.0 * obs[0]\n", "finish_reason": "stop", "logprobs": None} for i in range(n)]
    return {
        "id": "cmpl-test", "object": "text_completion", "created": int(time.time()), "model": body["model"],
        "choices": choices, "usage": {"prompt_tokens": 30, "completion_tokens": 4 * n, "total_tokens": 30 + 4 * n},
    }


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


def stream_chunks(answer: dict, chat: bool, include_usage: bool) -> list[dict]:
    """A whole answer as the chunks of a stream: each choice's text 8 characters a chunk, then
    the usage (if asked for)."""
    kind = "chat.completion.chunk" if chat else "text_completion"
    chunks = []
    for choice in answer["choices"]:
        text = choice["message"]["content"] if chat else choice["text"]
        for start in range(0, len(text), 8):
            piece = text[start : start + 8]
            delta = {"index": choice["index"], "delta": {"content": piece}, "finish_reason": None} if chat else {
                "index": choice["index"], "text": piece, "finish_reason": None, "logprobs": None,
            }
            chunks.append({"id": answer["id"], "object": kind, "created": answer["created"], "model": answer["model"], "choices": [delta]})
    if include_usage:
        chunks.append({"id": answer["id"], "object": kind, "created": answer["created"], "model": answer["model"], "choices": [], "usage": answer["usage"]})
    return chunks


def wait_for(condition, timeout: float = 300.0, interval: float = 0.01, what: str = "a condition"):
    """Poll `condition()` until it returns something true; fail after `timeout` seconds (generous:
    CI shares 2 cores)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(interval)
    raise AssertionError(f"timed out after {timeout:g} s waiting for {what}")


def children_of(pid: int) -> list[int]:
    """The child processes of `pid` (a sandbox worker's evaluation processes)."""
    children = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            children += [int(child) for child in (task / "children").read_text().split()]
        except OSError:
            pass
    return children


def same_outcome(a, b) -> bool:
    """Two evaluations with the same returns, failure and steps (their timings differ)."""
    return (a.returns, a.failure, a.steps, a.raced_out) == (b.returns, b.failure, b.steps, b.raced_out)
