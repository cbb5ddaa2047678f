"""The root schemas, one per app: what each command line composes (`conf/<app>.yaml`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

from omegaconf import MISSING

from colmo.config.components import ExecutorConfig, GFOConfig, TrackerConfig
from colmo.config.fields import option, require
from colmo.config.generators import GeneratorConfig
from colmo.config.search import DatabaseConfig, HeldoutConfig, SearchLoopConfig, SimplifyConfig
from colmo.config.task import TaskConfig


@dataclass
class SearchConfig:
    """`colmo`: the program search."""

    task: TaskConfig = MISSING
    gfo: GFOConfig = MISSING
    llm: GeneratorConfig = MISSING
    database: DatabaseConfig = MISSING
    executor: ExecutorConfig = MISSING
    tracker: TrackerConfig = MISSING
    search: SearchLoopConfig = field(default_factory=SearchLoopConfig)
    evaluation: HeldoutConfig = field(default_factory=HeldoutConfig)
    simplify: SimplifyConfig = field(default_factory=SimplifyConfig)
    seed: int = option(0, "episode seeds, prompts and optimizers derive from it")
    resume: Optional[str] = option(None, "an earlier run's directory to continue")

    def __post_init__(self) -> None:
        require(self.seed >= 0, f"seed must be >= 0, got {self.seed}")


@dataclass
class OptimizeConfig:
    """`colmo-optimize`: tune the constants of one policy file."""

    task: TaskConfig = MISSING
    gfo: GFOConfig = MISSING
    executor: ExecutorConfig = MISSING
    tracker: TrackerConfig = MISSING
    policy_file: str = option(MISSING, "a .py file with `def policy(obs)`, or a raw language-model answer")
    evaluation: HeldoutConfig = field(default_factory=HeldoutConfig)
    seed: int = option(0, "episode seeds and the optimizer's randomness derive from it")

    def __post_init__(self) -> None:
        require(self.seed >= 0, f"seed must be >= 0, got {self.seed}")
