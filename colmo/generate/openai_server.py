"""`llm=openai`: any OpenAI-compatible chat-completions server.

openai talks to any OpenAI-compatible chat-completions endpoint (vllm serve, Ollama, llama.cpp,
OpenAI) with the official client. It asks for `n` choices in one request when `use_n`; a
server that returns fewer is asked one completion per request from then on, in parallel.
Retries are its own (visible in the log, configurable): connection errors, timeouts, HTTP 408,
409, 429, 5xx and unusable answers are retried with exponential backoff and full jitter, up to
`max_retries` times per request; a request that runs out of retries is dropped, so a batch can
come back short. Requests go round robin over `base_url`, skipping a server for
`max_backoff_s` after it fails. `max_consecutive_failures` failed attempts in a row, over all
servers, or any other HTTP error (a wrong model name, a bad key), raise `GeneratorError`.
"""

from __future__ import annotations

import itertools
import os
import random
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import openai

from colmo.config import OpenAIConfig, one_line
from colmo.generate.base import Generation, Generator, GeneratorError, batch_of, describe_error, logger
from colmo.prompt import Prompt

_RETRYABLE_STATUS = frozenset({408, 409, 429})


class _UnusableAnswer(ValueError):
    """A 200 answer with no completion text in it."""


def _texts(response: Any) -> list[str]:
    """The non-empty completion texts of an answer; `_UnusableAnswer` if there are none (servers
    and proxies can answer 200 with HTML, an error object or empty choices)."""
    choices = getattr(response, "choices", None) or []
    texts = [getattr(getattr(choice, "message", None), "content", None) for choice in choices]
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


class OpenAIGenerator(Generator):
    """Chat completions from OpenAI-compatible servers, with our own retries and failover."""

    def __init__(self, cfg: OpenAIConfig, seed: int):
        self.cfg = cfg
        api_key = os.environ.get(cfg.api_key_env) or "EMPTY"  # local servers want no key, the client wants one
        self._servers = [
            _Server(url, openai.OpenAI(base_url=url, api_key=api_key, timeout=cfg.timeout_s, max_retries=0))
            for url in cfg.base_url
        ]
        self._turn = itertools.count()
        self._lock = threading.Lock()
        self._failures = 0  # consecutive failed attempts, all servers together
        self._use_n = cfg.use_n
        self._seeds = random.Random(seed)
        self._pool = ThreadPoolExecutor(max_workers=cfg.batch_size, thread_name_prefix="colmo-openai")

    def generate(self, prompt: Prompt, n: int) -> list[Generation]:
        generations = self._complete(prompt.messages, n, self._seeds.randrange(2**31)) if self._use_n and n > 1 else []
        seeds = [self._seeds.randrange(2**31) for _ in range(n - len(generations))]
        for batch in self._pool.map(lambda seed: self._complete(prompt.messages, 1, seed), seeds):
            generations += batch
        return generations

    def close(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)
        for server in self._servers:
            server.client.close()

    def _complete(self, messages: list[dict[str, str]], n: int, seed: int) -> list[Generation]:
        """One request, retried; its generations, or none once its retries are spent."""
        cfg = self.cfg
        for attempt in range(cfg.max_retries + 1):
            server = self._pick_server()
            start = time.perf_counter()
            try:
                response = server.client.chat.completions.create(
                    model=cfg.model, messages=messages, temperature=cfg.temperature, top_p=cfg.top_p,
                    max_tokens=cfg.max_tokens, seed=seed, **({"n": n} if n > 1 else {}),
                )
                texts = _texts(response)
            except openai.APIStatusError as error:
                if error.status_code not in _RETRYABLE_STATUS and error.status_code < 500:
                    message = f"{server.url} refused the request: HTTP {error.status_code}: {one_line(error)}"
                    raise GeneratorError(message) from None
                reason = self._failed(server, error)
            except (openai.APIConnectionError, openai.APIResponseValidationError, ValueError) as error:
                # ValueError: a body that is not JSON, or `_UnusableAnswer`.
                reason = self._failed(server, error)
            else:
                return self._succeeded(server, response, texts, n, time.perf_counter() - start)
            if attempt < cfg.max_retries:
                # Full jitter: requests that failed together do not all come back together.
                delay = random.uniform(0.0, min(cfg.max_backoff_s, cfg.backoff_s * 2**attempt))
                logger.warning(
                    "openai: %s failed (%s); retry %d/%d in %.3fs", server.url, reason, attempt + 1, cfg.max_retries, delay
                )
                time.sleep(delay)
        logger.warning("openai: dropping a request after %d attempts; the last failed with %s", cfg.max_retries + 1, reason)
        return []

    def _pick_server(self) -> _Server:
        """Round robin over the servers that have not failed in the last `max_backoff_s`; if all
        have, the one that failed longest ago."""
        with self._lock:
            now = time.monotonic()
            for _ in range(len(self._servers)):
                server = self._servers[next(self._turn) % len(self._servers)]
                if now - server.failed_at >= self.cfg.max_backoff_s:
                    return server
            return min(self._servers, key=lambda s: s.failed_at)

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

    def _succeeded(self, server: _Server, response: Any, texts: list[str], n: int, seconds: float) -> list[Generation]:
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
        name = f"openai:{self.cfg.model}@{server.url}"
        return batch_of(texts, name, prompt_tokens, _split(completion_tokens, len(texts)), seconds)
