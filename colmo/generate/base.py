"""The generator interface: a `Generator` turns one `Prompt` into `n` raw texts (`Generation`s,
`n` = `llm.batch_size`); pulling the policy out of a model's answer is the search loop's job
(`colmo.extract`).

A `Generation` is where a generator's text enters colmo: a character that is not text (a lone
surrogate, which the OpenAI client returns for a server's JSON `"\ud800"`) becomes U+FFFD there,
so that the text can be stored, logged and shown, and intake refuses it as unusable
(`colmo.intake.read_program`); it used to end the whole search with a `UnicodeEncodeError`."""

from __future__ import annotations

import abc
import dataclasses
import enum
import logging
import random
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable, ClassVar, Optional, Sequence

from colmo.config import GeneratorConfig
from colmo.errors import one_line
from colmo.registry import Library, Registry

if TYPE_CHECKING:
    from colmo.prompt import Prompt

logger = logging.getLogger("colmo.generate")


class PromptForm(str, enum.Enum):
    """What an answer is to its prompt, and so how intake reads it (`colmo.intake.read_program`)."""

    CODE = "code"  # a program on its own (`mutate`, a spec's starter)
    CHAT = "chat"  # an answer to the prompt's messages: it may call the code the prompt showed
    COMPLETION = "completion"  # the prompt's text continued: read as one with it


@dataclass(frozen=True)
class Generation:
    text: str  # raw output: code from mutate, a model's whole answer otherwise
    generator: str  # "mutate", "openai:<model>@<url>", "vllm:<model>"
    prompt_tokens: int = 0
    completion_tokens: int = 0
    seconds: float = 0.0
    # Model calls this answer cost: more than 1 when answers before it were duplicates, thrown
    # away and generated again (their tokens and seconds are counted in the fields above).
    calls: int = 1
    form: PromptForm = PromptForm.CODE
    # What the answer is read with: the prompt text a completion continues, or the code a chat
    # answer's prompt showed (`Prompt.shown_code`), which it may call without copying it.
    context: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "form", PromptForm(self.form))
        if self.form is PromptForm.CODE and self.context:
            raise ValueError("a generation of code on its own has no prompt context")
        for name in ("text", "context"):
            object.__setattr__(self, name, as_text(getattr(self, name)))

    @property
    def prefix(self) -> str:
        """The prompt text a completion continues (extraction reads prefix + text); empty otherwise."""
        return self.context if self.form is PromptForm.COMPLETION else ""

    @property
    def shown(self) -> str:
        """The code a chat answer's prompt showed; empty otherwise."""
        return self.context if self.form is PromptForm.CHAT else ""

    def after(self, discarded: "Generation") -> "Generation":
        """This answer, charged with the calls, tokens and seconds of a discarded one before it."""
        return dataclasses.replace(
            self, prompt_tokens=self.prompt_tokens + discarded.prompt_tokens, completion_tokens=self.completion_tokens + discarded.completion_tokens,
            seconds=self.seconds + discarded.seconds, calls=self.calls + discarded.calls,
        )


def as_text(text: str) -> str:
    """`text` with every character UTF-8 cannot encode (lone surrogates) replaced by U+FFFD."""
    try:
        text.encode("utf-8")
        return text
    except UnicodeEncodeError:  # a pair of surrogates is one character again; a lone one is U+FFFD
        return text.encode("utf-16", "surrogatepass").decode("utf-16", "replace")


class GeneratorError(RuntimeError):
    """The generator cannot go on (no server answers, a request is refused, a library is
    missing); the message is one line."""


# A probe says whether a program runs on the task (`colmo.generate.probe.ProgramProbe`).
Probe = Callable[[str], bool]


class Generator(abc.ABC):
    """Turns prompts into raw texts. Subclasses register under their `llm.name` with
    `@GENERATORS.register` and are built as `cls(cfg, seed, probe)`; `probe` is None unless
    `wants_probe`."""

    options: ClassVar[type[GeneratorConfig]]  # the schema of its `llm` option
    wants_probe: ClassVar[bool] = False
    library: ClassVar[Optional[Library]] = None  # the optional library it runs on
    # Whether an answer that brings no new program is answered in the same conversation, the
    # model told what was wrong (`colmo.answers.regenerate`): a chat model's, with `llm.follow_up`.
    follows_up: bool = False

    def __init__(self, cfg, seed: int, probe: Optional[Probe] = None) -> None:
        self.cfg = cfg
        self.probe = probe
        self._request_seeds = random.Random(seed)

    def request_seed(self) -> int:
        """A fresh sampling seed for one request to a model, drawn from the run's seed: the same
        prompt must not get the same answers every time, and a run must repeat."""
        return self._request_seeds.randrange(2**31)

    @abc.abstractmethod
    def generate(self, prompt: Prompt, n: int) -> list[Generation]:
        """Up to `n` candidate programs for `prompt`."""

    def cancel(self) -> None:
        """Abandon the generation in flight, where the generator can (the search is stopping);
        `generate` may then return early, and its result is discarded."""

    def tokens_so_far(self) -> Optional[int]:
        """Tokens the call in flight has generated so far, where the generator can tell (0: it is
        still reading the prompt); None where it cannot, or no call is in flight. Read from
        another thread while `generate` runs."""
        return None

    def cores(self) -> int:
        """The cores of this machine its calls keep busy while they run (0: the work is done
        elsewhere, a server or a GPU); what `search.model_share=by_yield` charges for its time."""
        return 0

    def close(self) -> None:
        """Release connections, threads or GPU memory."""


class LanguageModelGenerator(Generator):
    """A generator that asks a language model in the form `llm.prompt_format` says: the prompt's
    chat messages (`chat`), or its text for the model to continue, which its answers then
    continue (`prefix`)."""

    def __init__(self, cfg, seed: int, probe: Optional[Probe] = None) -> None:
        super().__init__(cfg, seed, probe)
        self.form = PromptForm(cfg.prompt_format)
        self.chat = self.form is PromptForm.CHAT
        self.follows_up = self.chat and cfg.follow_up

    def context(self, prompt: Prompt) -> str:
        """What an answer to `prompt` is read with (`Generation.context`): the prompt's code in the
        chat form, its text in the completion form."""
        return prompt.shown_code if self.chat else prompt.text


GENERATORS: Registry[type[Generator]] = Registry("llm.name")


def batch_of(
    texts: Sequence[str], generator: str, prompt_tokens: int, completion_tokens: Sequence[int], seconds: float,
    form: PromptForm = PromptForm.CODE, context: str = "",
) -> list[Generation]:
    """The generations of one request, each read in `form` with `context`. Its prompt is counted
    on the first only and its time is split evenly, so that sums over generations are the
    request's totals."""
    return [
        Generation(text, generator, prompt_tokens if i == 0 else 0, completion, seconds / len(texts), form=form, context=context)
        for i, (text, completion) in enumerate(zip(texts, completion_tokens))
    ]


def describe_error(error: BaseException) -> str:
    cause = f" ({one_line(error.__cause__)})" if error.__cause__ else ""
    return f"{type(error).__name__}: {one_line(error)}{cause}"
