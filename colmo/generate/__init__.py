"""Producing candidate programs from a prompt, behind one interface (`base.Generator`) and one
registry (`base.GENERATORS`, a `colmo.registry.Registry`) that each generator joins where it is
defined (`@GENERATORS.register`): the embedded mutation baseline (`mutate`), OpenAI-compatible
servers (`openai_server`), in-process vLLM (`vllm_engine`) and in-process llama.cpp
(`llamacpp_engine`). `make_generator(cfg.llm, seed)` builds the one `llm.name` names.
"""

from __future__ import annotations

from typing import Optional

from colmo.generate import llamacpp_engine, mutate, openai_server, vllm_engine  # noqa: F401 - they register
from colmo.generate.base import GENERATORS, Generation, Generator, GeneratorError, Probe, PromptForm

__all__ = ["GENERATORS", "Generation", "Generator", "GeneratorError", "Probe", "PromptForm", "make_generator"]


def make_generator(cfg, seed: int, probe: Optional[Probe] = None) -> Generator:
    """The generator `cfg.name` names, configured by `cfg` (the `llm` config group). `probe(code)`
    says whether a program runs on the task; it reaches only generators that want one (`mutate`
    offers only working children)."""
    cls = GENERATORS.chosen(cfg.name)
    return cls(cfg, seed, probe if cls.wants_probe else None)
