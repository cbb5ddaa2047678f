"""The sampler: answers from the generators to prompts built from the database's selections.

A search's generator (`llm`) answers in a thread of its own, so that the search can abandon a
call at its deadline and, with `search.fill=mutate`, give idle workers batches of the filler (the
embedded mutation generator, which answers at once) while a slow model thinks. An answer that
brings no new program is generated again (`colmo.answers.regenerate`). A generator that fails
ends the sampling with `failure` set; the answers generated before it are kept.
"""

from __future__ import annotations

import concurrent.futures
import dataclasses
import functools
import logging
import time
from typing import Callable, Optional

from colmo.answers import Answer, AnswerReader, regenerate
from colmo.config import MutateConfig, SearchConfig
from colmo.database import ProgramDatabase
from colmo.errors import RunError
from colmo.evaluation import Evaluator
from colmo.generate import GENERATORS, Generation, Generator, GeneratorError, make_generator
from colmo.generate.probe import ProgramProbe
from colmo.optimize.methods import tunes_constants
from colmo.prompt import Prompt, build_prompt
from colmo.specs import Spec

log = logging.getLogger("colmo.search")

POLL_S = 0.2  # how often a wait for the generator asks whether to go on


class Sampler:
    """The generators of one search (`generator` if given, else `cfg.llm`'s; the filler if
    `cfg.search.fill`) and how their answers are asked for and read."""

    def __init__(self, cfg: SearchConfig, spec: Spec, reader: AnswerReader, generator: Optional[Generator] = None):
        self.cfg, self.spec, self.reader = cfg, spec, reader
        self.generator = generator
        self.filler: Optional[Generator] = None
        self.probe: Optional[ProgramProbe] = None  # what mutation asks whether a child runs
        self.failure = ""  # "generator failed: ...", once one has
        self.calling_since: Optional[float] = None  # when the generator's call in flight began (`time.perf_counter()`)
        self.calling: Optional[Generator] = None  # the generator of that call
        self.thread = concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="colmo-generate")

    @functools.cached_property
    def task_text(self) -> str:
        """What heads every prompt; built at the first prompt, once the starter's evaluation has
        shown that the task's environment builds with its options."""
        return self.spec.prompt_text_for(self.cfg.task.env)

    def needs_evaluator(self) -> bool:
        """Whether the generator can only start once the task's evaluator exists (it probes programs)."""
        return self.generator is None and GENERATORS[self.cfg.llm.name].wants_probe

    def start(self, evaluator: Optional[Evaluator]) -> None:
        """The generator of `cfg.llm` (unless one was given) and the filler; a generator that
        cannot start is a `RunError` (a server that does not answer, a model that does not load)."""
        if self.generator is None:
            self.probe = ProgramProbe(evaluator) if self.needs_evaluator() else None
            try:
                self.generator = make_generator(self.cfg.llm, self.cfg.seed, self.probe)
            except GeneratorError as error:
                raise RunError(f"llm={self.cfg.llm.name}: {error}") from None
        if self.cfg.search.fill and self.filler is None and evaluator is not None:
            self.probe = self.probe or ProgramProbe(evaluator)
            self.filler = make_generator(MutateConfig(), self.cfg.seed + 1, self.probe)

    def prompt(self, database: ProgramDatabase, retry: int = 0) -> Prompt:
        """A prompt from a new selection of `database`; `retry`: the regeneration of an answer it is for."""
        prompt = build_prompt(
            self.task_text, database.select(), constants_tuned=tunes_constants(self.cfg.gfo), allowed_imports=self.spec.allowed_imports,
        )
        return dataclasses.replace(prompt, retry=retry)

    def answers(
        self, generator: Generator, database: ProgramDatabase, n: int, calls_left: int, abandon: Callable[[int], bool],
    ) -> Optional[list[Answer]]:
        """`n` answers of `generator` (duplicates generated again within `calls_left` more model
        calls); None if `abandon(n)`, asked while a call is in flight, says to stop, or the
        generator failed (`failure`)."""
        prompt = self.prompt(database)
        generations = self._generated(generator, prompt, n, abandon)
        if generations is None:
            return None
        answers = [self.reader.answer(prompt, generation) for generation in generations]
        return regenerate(
            answers, self.reader, database.is_known, lambda retry: self.prompt(database, retry),
            lambda again, k: self._generated(generator, again, k, abandon), self.cfg.search.duplicate_retries, calls_left,
            follow_up=generator.follows_up,
        )

    def _generated(self, generator: Generator, prompt: Prompt, n: int, abandon: Callable[[int], bool]) -> Optional[list[Generation]]:
        if generator is self.filler:  # it answers at once, in the search's thread
            return generator.generate(prompt, n)
        self.calling_since, self.calling = time.perf_counter(), generator
        generating = self.thread.submit(generator.generate, prompt, n)
        try:
            while not generating.done():
                if abandon(n):
                    generating.cancel()
                    generator.cancel()
                    return None
                concurrent.futures.wait([generating], timeout=POLL_S)
            return generating.result()
        except GeneratorError as error:  # the batches in flight are still integrated
            self.failure = f"generator failed: {error}"
            log.error("%s", self.failure)
            return None
        finally:
            self.calling_since = self.calling = None

    def call_seconds(self) -> Optional[float]:
        """How long the generator's call in flight has run; None when none is."""
        since = self.calling_since
        return None if since is None else time.perf_counter() - since

    def call_tokens(self) -> Optional[int]:
        """The tokens the call in flight has generated so far, where its generator tells (`Generator.tokens_so_far`)."""
        calling = self.calling
        return None if calling is None else calling.tokens_so_far()

    def stop(self) -> None:
        """Abandon the call in flight."""
        self.thread.shutdown(wait=False, cancel_futures=True)

    def close(self) -> None:
        for resource in filter(None, (self.generator, self.filler, self.probe)):
            resource.close()
