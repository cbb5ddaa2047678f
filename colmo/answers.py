"""A model's answers as a search takes them in: each read once into the program it holds,
keyed as the run tells programs apart (`colmo.database.identity`: by structure with GFO, by
code and constants with `gfo=none`), or why no program could be read from it; and the answers
of a batch that bring no new program generated again, up to `search.duplicate_retries` times
(`regenerate`): a chat model is told in the same conversation what was wrong with its answer,
any other generator is asked for a duplicate again from a new selection of the database.

Reading is the coordinator's work (extraction and the static check), done once per answer:
the duplicate check and the submission of a sample both use the reading an answer carries.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Callable, Optional, Sequence, Union

from colmo.database import identity
from colmo.generate import Generation
from colmo.intake import Unusable, read_program
from colmo.program import ParametricProgram, structure_key
from colmo.prompt import Prompt, copied_feedback, unusable_feedback
from colmo.sandbox.check import ForbiddenProgram

log = logging.getLogger("colmo.search")

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
    """Reads answers as one run does: the spec's allowed imports, the size limits
    (`database.max_nodes`, `database.max_constants`), and programs told apart by structure (with GFO) or not."""

    allowed_imports: Sequence[str]
    max_nodes: Optional[int]
    by_structure: bool
    max_constants: Optional[int] = None

    def identified(self, program: ParametricProgram) -> ParametricProgram:
        """With GFO, programs that differ only in constants are one; with gfo=none, each set of constants is a program."""
        return identity(program, by_structure=self.by_structure)

    def key(self, skeleton: str, values: Sequence[float]) -> str:
        """The key of a stored program (its skeleton and constants), as `identified` gives it."""
        return self.identified(ParametricProgram(skeleton, tuple(values), structure_key(skeleton))).key

    def read(self, generation: Generation) -> Reading:
        """The program of an answer, or why none could be read (a chat answer may call what its
        prompt showed, `Generation.shown`)."""
        try:
            return self.identified(
                read_program(generation.text, self.allowed_imports, generation.prefix, self.max_nodes, generation.shown, self.max_constants),
            )
        except (Unusable, ForbiddenProgram) as error:
            return error

    def answer(self, prompt: Prompt, generation: Generation) -> Answer:
        return Answer(prompt, generation, self.read(generation))


def _duplicate_feedback(answer: Answer, by_structure: bool) -> str:
    """What a chat model is told of an answer whose program is known: which one it copied."""
    assert isinstance(answer.reading, ParametricProgram)
    shown = answer.prompt.parent_keys
    key = answer.reading.key
    return copied_feedback(shown.index(key) if key in shown else None, by_structure)


def _faults(answers: Sequence[Answer], is_known: Callable[[str], bool], by_structure: bool, unreadable: bool) -> dict[int, str]:
    """The positions in `answers` that bring no new program, with what was wrong, phrased for the
    model: a program known or the same as an earlier answer's, and (`unreadable`) an answer
    no program could be read from."""
    keys: set[str] = set()
    faults = {}
    for i, answer in enumerate(answers):
        if isinstance(answer.reading, ParametricProgram):
            key = answer.reading.key
            if is_known(key) or key in keys:
                faults[i] = _duplicate_feedback(answer, by_structure)
            keys.add(key)
        elif unreadable:
            faults[i] = unusable_feedback(str(answer.reading))
    return faults


def regenerate(
    answers: list[Answer], reader: AnswerReader, is_known: Callable[[str], bool],
    next_prompt: Callable[[int], Prompt], generate: Callable[[Prompt, int], Optional[list[Generation]]],
    retries: int, calls_left: int, follow_up: bool,
) -> list[Answer]:
    """`answers` with each that brings no new program generated again by `generate`, up to
    `retries` times and within `calls_left` model calls: a model's copy of a shown program would
    waste its turn. With `follow_up` (a chat model) the conversation goes on: the model is shown
    its answer and told what was wrong (a copy of `policy_v1` with other numbers, a name it never
    defined, a refused import), for duplicates and unreadable answers alike. Otherwise a
    duplicate is asked for again from `next_prompt(retry)`, a new selection of the database. A
    fresh seed comes with every request, and a language model samples each retry hotter
    (`llm.retry_temperature_step`). A regenerated answer carries the calls, tokens and seconds
    of the ones it replaces. `generate` returning None (the search is stopping) ends the retries."""
    for retry in range(1, retries + 1):
        faults = list(_faults(answers, is_known, reader.by_structure, unreadable=follow_up).items())[: max(calls_left, 0)]
        if not faults:
            break
        if follow_up:
            requests = [(answers[i].prompt.followed_up(answers[i].generation.text, feedback, retry), [i]) for i, feedback in faults]
        else:
            requests = [(next_prompt(retry), [i for i, _ in faults])]
        for _, feedback in faults:
            log.info("an answer generated again (retry %d): %s", retry, feedback.split(". ")[0])
        for prompt, positions in requests:
            fresh = generate(prompt, len(positions))
            if fresh is None:  # stopping: the answers so far are stored
                return answers
            calls_left -= len(fresh)
            for i, generation in zip(positions, fresh):
                answers[i] = reader.answer(prompt, generation.after(answers[i].generation))
    return answers
