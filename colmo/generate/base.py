"""The generator interface: a `Generator` turns one `Prompt` into `n` raw texts (`Generation`s,
`n` = `llm.batch_size`); pulling the policy out of a model's answer is the search loop's job
(`colmo.extract`)."""

from __future__ import annotations

import abc
import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING, Sequence

from colmo.config import one_line

if TYPE_CHECKING:
    from colmo.prompt import Prompt

logger = logging.getLogger("colmo.generate")


@dataclass(frozen=True)
class Generation:
    text: str  # raw output: code from mutate, a model's whole answer otherwise
    generator: str  # "mutate", "openai:<model>@<url>", "vllm:<model>"
    prompt_tokens: int = 0
    completion_tokens: int = 0
    seconds: float = 0.0


class GeneratorError(RuntimeError):
    """The generator cannot go on (no server answers, a request is refused, a library is
    missing); the message is one line."""


class Generator(abc.ABC):
    @abc.abstractmethod
    def generate(self, prompt: Prompt, n: int) -> list[Generation]:
        """Up to `n` candidate programs for `prompt`."""

    def close(self) -> None:
        """Release connections, threads or GPU memory."""


def batch_of(
    texts: Sequence[str], generator: str, prompt_tokens: int, completion_tokens: Sequence[int], seconds: float
) -> list[Generation]:
    """The generations of one request. Its prompt is counted on the first only and its time is
    split evenly, so that sums over generations are the request's totals."""
    return [
        Generation(text, generator, prompt_tokens if i == 0 else 0, completion, seconds / len(texts))
        for i, (text, completion) in enumerate(zip(texts, completion_tokens))
    ]


def describe_error(error: BaseException) -> str:
    cause = f" ({one_line(error.__cause__)})" if error.__cause__ else ""
    return f"{type(error).__name__}: {one_line(error)}{cause}"
