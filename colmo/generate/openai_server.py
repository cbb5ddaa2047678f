"""`llm=openai`: any OpenAI-compatible server (vllm serve, Ollama, llama.cpp, OpenAI).

openai talks to an OpenAI-compatible endpoint with the official client: chat completions
(`/v1/chat/completions`, `prompt_format=chat`) or completions of the prompt text
(`/v1/completions`, `prompt_format=completion`, stopping at the next top-level definition). It
asks for `n` choices in one request when `use_n`; a server that returns fewer (llama.cpp and
Ollama ignore `n`) is asked one completion per request from then on, in parallel. With `stream`
the answers come as server-sent chunks, each counted as a token as it arrives
(`tokens_so_far`), their usage from the stream's last chunk where the server sends it; a server
that refuses a streamed request is asked for whole answers from then on.

At most `max_concurrency` requests are in flight per server; the others wait here, before they
are sent, so a request's `timeout_s` counts from when it is sent, not while it is queued (a
one-slot llama.cpp server answers one request at a time; sent together, the last ones would
time out in its queue). Requests go round robin over the servers of `base_url` that have a free
slot, skipping a server for `max_backoff_s` after it fails.

Retries are its own (visible in the log, configurable): connection errors, timeouts, HTTP 408,
409, 429, 5xx and unusable answers are retried with exponential backoff and full jitter, up to
`max_retries` times per request; a request that runs out of retries is dropped, so a batch can
come back short. `max_consecutive_failures` failed attempts in a row, over all servers, or any
other HTTP error (a wrong model name, a bad key), raise `GeneratorError`. `cancel()` sends no
more requests and retries none; requests in flight end on their own.
"""

from __future__ import annotations

import itertools
import os
import random
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any, Optional

from colmo.config import OpenAIConfig
from colmo.errors import one_line
from colmo.generate.base import GENERATORS, Generation, GeneratorError, LanguageModelGenerator, Probe, batch_of, describe_error, logger
from colmo.prompt import COMPLETION_STOP, Prompt

# openai is imported where a client is made or its errors are caught, not here: importing it
# takes ~0.7 s of CPU, which every colmo command paid (the registries import this module),
# whatever its generator.
if TYPE_CHECKING:
    import openai

_CHECK_TIMEOUT_S = 5.0
_RETRYABLE_STATUS = frozenset({408, 409, 429})
_STREAM_REFUSED = frozenset({400, 422})  # what servers that take no `stream`/`stream_options` answer, naming it


class _UnusableAnswer(ValueError):
    """A 200 answer with no completion text in it."""


def _texts(response: Any, chat: bool) -> list[str]:
    """The non-empty completion texts of an answer; `_UnusableAnswer` if there are none (servers
    and proxies can answer 200 with HTML, an error object or empty choices)."""
    choices = getattr(response, "choices", None) or []
    if chat:
        texts = [getattr(getattr(choice, "message", None), "content", None) for choice in choices]
    else:
        texts = [getattr(choice, "text", None) for choice in choices]
    texts = [text for text in texts if isinstance(text, str) and text.strip()]
    if not texts:
        raise _UnusableAnswer(f"no completion text in the answer ({len(choices)} choices)")
    return texts


def _split(total: int, parts: int) -> list[int]:
    return [total // parts + (i < total % parts) for i in range(parts)]


class _Server:
    def __init__(self, url: str, client: openai.OpenAI):
        self.url = url
        self.client = client
        self.failed_at = -float("inf")
        self.in_flight = 0


@GENERATORS.register("openai")
class OpenAIGenerator(LanguageModelGenerator):
    """Completions from OpenAI-compatible servers, with per-server concurrency limits, our own
    retries and failover."""

    options = OpenAIConfig

    def __init__(self, cfg: OpenAIConfig, seed: int, probe: Optional[Probe] = None):
        import openai
        super().__init__(cfg, seed, probe)
        api_key = os.environ.get(cfg.api_key_env) or "EMPTY"  # local servers want no key, the client wants one
        self._servers = [
            _Server(url, openai.OpenAI(base_url=url, api_key=api_key, timeout=cfg.timeout_s, max_retries=0))
            for url in cfg.base_url
        ]
        self._turn = itertools.count()
        self._lock = threading.Condition()  # guards the servers' state; notified when a slot frees
        self._stopped = False  # cancelled or closed: nothing more is sent
        self._failures = 0  # consecutive failed attempts, all servers together
        self._use_n = cfg.use_n
        self._stream = cfg.stream
        self._tokens: Optional[int] = None  # streamed tokens of the generation in flight; None: none in flight
        self._pool = ThreadPoolExecutor(max_workers=cfg.batch_size, thread_name_prefix="colmo-openai")
        self._check_servers()

    def _check_servers(self) -> None:
        """At least one server answers (any HTTP answer counts) within `_CHECK_TIMEOUT_S`, so a
        run without one ends at once, saying how to start one; the others are logged."""
        import openai
        silent = []
        for server in self._servers:
            try:
                server.client.with_options(timeout=min(_CHECK_TIMEOUT_S, self.cfg.timeout_s)).models.list()
            except openai.APIStatusError:
                pass  # it answered
            except openai.APIError as error:
                silent.append(f"{server.url} ({describe_error(error)})")
        if len(silent) == len(self._servers):
            self.close()
            raise GeneratorError(
                f"no OpenAI-compatible server answers at {', '.join(silent)}; start one, e.g. "
                f"`vllm serve {self.cfg.model}` or `python -m llama_cpp.server --model FILE.gguf`, and pass its URL as llm.base_url"
            )
        for server in silent:
            logger.warning("openai: %s does not answer; using the other servers until it does", server)

    def check_request(self) -> None:
        """One real request, a one-token answer for `llm.model` in the run's prompt form, to each
        server until one answers it; `GeneratorError` naming what each server answered if none
        does (a server that answers anything but serves no completions: a wrong path or model
        name, HTTP 404 or 501). Busy answers (408, 409, 429, 5xx other than 501: a llama.cpp
        server still loading its model answers 503) count as serving: the search retries them.
        The start-up check (`colmo.__main__.check_inputs`) runs it before anything is created."""
        import openai
        refusals = []
        for server in self._servers:
            client = server.client.with_options(timeout=self.cfg.timeout_s)
            try:
                if self.chat:
                    client.chat.completions.create(model=self.cfg.model, messages=[{"role": "user", "content": "Say OK."}], max_tokens=1)
                else:
                    client.completions.create(model=self.cfg.model, prompt="def policy(obs):\n", max_tokens=1)
                return
            except openai.APIStatusError as error:
                if error.status_code != 501 and (error.status_code in _RETRYABLE_STATUS or error.status_code >= 500):
                    return
                refusals.append(f"{server.url} answered HTTP {error.status_code} ({one_line(error)})")
            except (openai.APIError, ValueError) as error:
                refusals.append(f"{server.url}: {describe_error(error)}")
        form = "chat completion" if self.chat else "completion"
        raise GeneratorError(f"no server serves a {form} of model {self.cfg.model!r}: {'; '.join(refusals)}")

    def generate(self, prompt: Prompt, n: int) -> list[Generation]:
        with self._lock:
            self._tokens = 0
        try:
            generations = self._complete(prompt, n, self.request_seed()) if self._use_n and n > 1 else []
            seeds = [self.request_seed() for _ in range(n - len(generations))]
            for batch in self._pool.map(lambda seed: self._complete(prompt, 1, seed), seeds):
                generations += batch
            return generations
        finally:
            with self._lock:
                self._tokens = None

    def tokens_so_far(self) -> Optional[int]:
        """Tokens streamed so far for the generation in flight, all its requests together (None
        without streaming)."""
        with self._lock:
            return self._tokens if self._stream else None

    def cancel(self) -> None:
        with self._lock:
            self._stopped = True
            self._lock.notify_all()

    def close(self) -> None:
        self.cancel()
        self._pool.shutdown(wait=False, cancel_futures=True)
        for server in self._servers:
            server.client.close()

    def _complete(self, prompt: Prompt, n: int, seed: int) -> list[Generation]:
        """One request, retried; its generations, or none once its retries are spent."""
        import openai
        cfg = self.cfg
        stream_refused = False
        for attempt in range(cfg.max_retries + 1):
            server = self._acquire()
            if server is None:
                return []
            start, streamed = time.perf_counter(), self._stream
            try:
                response = self._send(server, prompt, n, seed, streamed)
                texts = _texts(response, self.chat)
            except openai.APIStatusError as error:
                if streamed and error.status_code in _STREAM_REFUSED and "stream" in str(error).lower():
                    with self._lock:
                        if self._stream:
                            logger.warning(
                                "openai: %s refused a streamed request (HTTP %d); asking for whole answers from now on", server.url, error.status_code,
                            )
                        self._stream = False
                    stream_refused = True
                elif error.status_code not in _RETRYABLE_STATUS and error.status_code < 500:
                    message = f"{server.url} refused the request: HTTP {error.status_code}: {one_line(error)}"
                    raise GeneratorError(message) from None
                else:
                    reason = self._failed(server, error)
            except (openai.APIConnectionError, openai.APIResponseValidationError, ValueError) as error:
                # ValueError: a body that is not JSON, or `_UnusableAnswer`.
                reason = self._failed(server, error)
            else:
                return self._succeeded(server, prompt, response, texts, n, time.perf_counter() - start)
            finally:
                self._release(server)
            if stream_refused:  # asked again at once, whole, as no attempt of its own
                return self._complete(prompt, n, seed)
            if attempt < cfg.max_retries and not self._stopped:
                # Full jitter: requests that failed together do not all come back together.
                delay = random.uniform(0.0, min(cfg.max_backoff_s, cfg.backoff_s * 2**attempt))
                logger.warning(
                    "openai: %s failed (%s); retry %d/%d in %.3fs", server.url, reason, attempt + 1, cfg.max_retries, delay
                )
                time.sleep(delay)
        logger.warning("openai: dropping a request after %d attempts; the last failed with %s", cfg.max_retries + 1, reason)
        return []

    def _send(self, server: _Server, prompt: Prompt, n: int, seed: int, streamed: bool) -> Any:
        cfg = self.cfg
        sampling = dict(
            model=cfg.model, temperature=cfg.temperature_for(prompt.retry), top_p=cfg.top_p, max_tokens=cfg.max_tokens, seed=seed,
            **({"n": n} if n > 1 else {}),
        )
        if streamed:
            sampling.update(stream=True, stream_options={"include_usage": True})
        if self.chat:
            response = server.client.chat.completions.create(messages=prompt.messages, **sampling)
        else:
            response = server.client.completions.create(prompt=prompt.text, stop=list(COMPLETION_STOP), **sampling)
        return self._gathered(response) if streamed else response

    def _gathered(self, stream: Any) -> SimpleNamespace:
        """A streamed answer as a whole one (its choices' texts, its usage), each chunk that adds
        text counted in `tokens_so_far` as it arrives; without usage from the server, its
        completion tokens are those chunks."""
        texts: dict[int, list[str]] = {}
        usage = None
        for chunk in stream:
            usage = getattr(chunk, "usage", None) or usage
            for choice in getattr(chunk, "choices", None) or []:
                piece = getattr(getattr(choice, "delta", None), "content", None) if self.chat else getattr(choice, "text", None)
                if piece:
                    texts.setdefault(getattr(choice, "index", 0) or 0, []).append(piece)
                    with self._lock:
                        if self._tokens is not None:
                            self._tokens += 1
        joined = ["".join(pieces) for _, pieces in sorted(texts.items())]
        choices = [SimpleNamespace(message=SimpleNamespace(content=text), text=text) for text in joined]
        if usage is None:
            usage = SimpleNamespace(prompt_tokens=0, completion_tokens=sum(map(len, texts.values())))
        return SimpleNamespace(choices=choices, usage=usage)

    def _acquire(self) -> Optional[_Server]:
        """A slot on a server, waiting until one frees: round robin over the servers that have
        not failed in the last `max_backoff_s`; if all have, the one that failed longest ago.
        None once the generator is cancelled."""
        limit, backoff = self.cfg.max_concurrency, self.cfg.max_backoff_s
        with self._lock:
            while True:
                if self._stopped:
                    return None
                now = time.monotonic()
                healthy = [s for s in self._servers if now - s.failed_at >= backoff]
                for _ in range(len(self._servers)):
                    server = self._servers[next(self._turn) % len(self._servers)]
                    if server in healthy and server.in_flight < limit:
                        break
                else:
                    free = [s for s in self._servers if s.in_flight < limit]
                    server = min(free, key=lambda s: s.failed_at) if free and not healthy else None
                if server is not None:
                    server.in_flight += 1
                    return server
                # Wake when a slot frees, or when a failed server's back-off ends.
                ends = [s.failed_at + backoff - now for s in self._servers if s not in healthy]
                self._lock.wait(timeout=min(ends) if ends else None)

    def _release(self, server: _Server) -> None:
        with self._lock:
            server.in_flight -= 1
            self._lock.notify_all()

    def _failed(self, server: _Server, error: BaseException) -> str:
        """Record a failed attempt; its reason, or `GeneratorError` once too many failed in a row."""
        reason = describe_error(error)
        with self._lock:
            server.failed_at = time.monotonic()
            self._failures += 1
            failures = self._failures
        if failures >= self.cfg.max_consecutive_failures:
            raise GeneratorError(f"no OpenAI-compatible server answered after {failures} attempts: {reason}") from error
        return reason

    def _succeeded(
        self, server: _Server, prompt: Prompt, response: Any, texts: list[str], n: int, seconds: float
    ) -> list[Generation]:
        with self._lock:
            self._failures = 0
            server.failed_at = -float("inf")
            if n > 1 and len(response.choices) < n and self._use_n:
                self._use_n = False
                logger.warning(
                    "openai: %s returned %d choices for n=%d; asking for one completion per request from now on",
                    server.url, len(response.choices), n,
                )
        usage = getattr(response, "usage", None)
        prompt_tokens = getattr(usage, "prompt_tokens", 0) or 0
        completion_tokens = getattr(usage, "completion_tokens", 0) or 0
        logger.info(
            "openai: %s: %d completions, %d prompt + %d completion tokens, %.1fs",
            server.url, len(texts), prompt_tokens, completion_tokens, seconds,
        )
        return batch_of(
            texts, f"openai:{self.cfg.model}@{server.url}", prompt_tokens, _split(completion_tokens, len(texts)), seconds, self.form,
            self.context(prompt),
        )
