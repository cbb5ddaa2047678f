"""Producing candidate programs from a prompt, behind one interface and a registry:
the embedded mutation baseline (`mutate`), OpenAI-compatible servers (`openai_server`) and
in-process vLLM (`vllm_engine`). `make_generator(cfg.llm, seed)` builds the one `llm.name` names.
"""

from __future__ import annotations

from typing import Callable, Optional

from colmo.config import ConfigError, GeneratorConfig
from colmo.generate.base import Generation, Generator, GeneratorError
from colmo.generate.mutate import MutateGenerator
from colmo.generate.openai_server import OpenAIGenerator
from colmo.generate.vllm_engine import VLLMGenerator

__all__ = [
    "GENERATORS", "Generation", "Generator", "GeneratorError", "MutateGenerator", "OpenAIGenerator",
    "VLLMGenerator", "make_generator",
]

GENERATORS: dict[str, type[Generator]] = {
    "mutate": MutateGenerator,
    "openai": OpenAIGenerator,
    "vllm": VLLMGenerator,
}


def make_generator(cfg: GeneratorConfig, seed: int, probe: Optional[Callable[[str], bool]] = None) -> Generator:
    """The generator `cfg.name` names, configured by `cfg` (the `llm` config group). `probe(code)`
    says whether a program runs on the task (see `colmo.sandbox.ProgramProbe`); the embedded
    generator uses it to offer only working children."""
    if cfg.name not in GENERATORS:
        raise ConfigError(f"llm.name must be one of {', '.join(GENERATORS)}; got {cfg.name!r}")
    if cfg.name == "mutate":
        return MutateGenerator(cfg, seed, probe)
    return GENERATORS[cfg.name](cfg, seed)
