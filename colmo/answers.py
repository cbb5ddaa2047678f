"""A model's answers as a search takes them in: each read once into the program it holds,
keyed as the run tells programs apart (`colmo.database.identity`: by structure with GFO, by
code and constants with `gfo=none`), or why no program could be read from it; and the
duplicates of a batch generated again, from a new selection of the database, up to
`search.duplicate_retries` times (`regenerate_duplicates`).

Reading is the coordinator's work (extraction and the static check), done once per answer:
the duplicate check and the submission of a sample both use the reading an answer carries.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional, Sequence, Union

from colmo.database import identity
from colmo.generate import Generation
from colmo.intake import Unusable, read_program
from colmo.program import ParametricProgram
from colmo.prompt import Prompt
from colmo.sandbox.check import ForbiddenProgram

# An answer's program, keyed as the run tells programs apart, or why no program could be read from it.
Reading = Union[ParametricProgram, Unusable, ForbiddenProgram]


@dataclass(frozen=True)
class Answer:
    """A model's answer with the prompt it answered and its program as read, once."""

    prompt: Prompt
    generation: Generation
    reading: Reading


@dataclass(frozen=True)
class AnswerReader:
    """Reads answers as one run does: the spec's allowed imports, the size limit
    (`database.max_nodes`), and programs told apart by structure (with GFO) or not."""

    allowed_imports: Sequence[str]
    max_nodes: Optional[int]
    by_structure: bool

    def identified(self, program: ParametricProgram) -> ParametricProgram:
        """With GFO, programs that differ only in constants are one; with gfo=none, each set of constants is a program."""
        return identity(program, by_structure=self.by_structure)

    def read(self, generation: Generation) -> Reading:
        """The program of an answer, or why none could be read (a chat answer may call what its
        prompt showed, `Generation.shown`)."""
        try:
            return self.identified(read_program(generation.text, self.allowed_imports, generation.prefix, self.max_nodes, generation.shown))
        except (Unusable, ForbiddenProgram) as error:
            return error

    def answer(self, prompt: Prompt, generation: Generation) -> Answer:
        return Answer(prompt, generation, self.read(generation))


def duplicates(answers: Sequence[Answer], is_known: Callable[[str], bool]) -> list[int]:
    """The positions in `answers` whose program is known, or the same as an earlier answer's."""
    keys: set[str] = set()
    repeated = []
    for i, answer in enumerate(answers):
        if not isinstance(answer.reading, ParametricProgram):
            continue
        key = answer.reading.key
        if is_known(key) or key in keys:
            repeated.append(i)
        keys.add(key)
    return repeated


def regenerate_duplicates(
    answers: list[Answer], reader: AnswerReader, is_known: Callable[[str], bool],
    next_prompt: Callable[[int], Prompt], generate: Callable[[Prompt, int], Optional[list[Generation]]],
    retries: int, calls_left: int,
) -> list[Answer]:
    """`answers` with each duplicate generated again by `generate`, from `next_prompt(retry)` (a
    new selection of the database; a fresh seed comes with every request, and a language model
    samples each retry hotter, `llm.retry_temperature_step`), up to `retries` times and within
    `calls_left` model calls: a model's copy of a shown program would waste its turn.
    A regenerated answer carries the calls, tokens and seconds of the ones it replaces.
    `generate` returning None (the search is stopping) ends the retries."""
    for retry in range(1, retries + 1):
        repeated = duplicates(answers, is_known)[: max(calls_left, 0)]
        if not repeated:
            break
        prompt = next_prompt(retry)
        fresh = generate(prompt, len(repeated))
        if fresh is None:  # stopping: the answers so far are stored
            break
        calls_left -= len(fresh)
        for i, generation in zip(repeated, fresh):
            answers[i] = reader.answer(prompt, generation.after(answers[i].generation))
    return answers
