"""Typed schemas of every Hydra config group, with their documentation and validation.

Each YAML option in `conf/<group>/` is composed over the dataclass of its group and sets only
what differs from it; the defaults and the documentation of every field live here (a field's
`metadata["help"]`, which `colmo --help` shows). Ranges and names are checked in
`__post_init__`, which runs when the composed config is turned into objects (`colmo.cli`),
so a bad value is one `ConfigError` line. Groups whose options differ in kind have one schema
per kind (`gfo=bo` has a sampler, `executor=ray` an address, `llm=openai` a server).
`colmo.cli` registers the schemas with Hydra and runs the apps.

One module per concern: `fields` (documented fields and checks), `task`, `components` (the
groups that pick a component: `gfo`, `executor`, `tracker`), `generators` (`llm`), `search`
(database, search loop, held-out scores, the search's finish, simplifier) and `apps` (each app's root schema).
"""

from colmo.config.apps import (
    EvaluateConfig,
    OptimizeConfig,
    PolicyFileConfig,
    RenderConfig,
    ReportConfig,
    SearchConfig,
    SimplifyAppConfig,
)
from colmo.config.components import (
    BOConfig,
    ExecutorConfig,
    GFOConfig,
    MlflowConfig,
    RayExecutorConfig,
    TrackerConfig,
)
from colmo.config.fields import option
from colmo.config.generators import (
    PROMPT_FORMATS,
    GeneratorConfig,
    LanguageModelConfig,
    LlamaCppConfig,
    MutateConfig,
    OpenAIConfig,
    VLLMConfig,
)
from colmo.config.search import DatabaseConfig, FinishConfig, HeldoutConfig, SearchLoopConfig, SimplifyConfig
from colmo.config.task import PerturbConfig, TaskConfig

__all__ = [
    "PROMPT_FORMATS",
    "BOConfig",
    "DatabaseConfig",
    "EvaluateConfig",
    "ExecutorConfig",
    "FinishConfig",
    "GFOConfig",
    "GeneratorConfig",
    "HeldoutConfig",
    "LanguageModelConfig",
    "LlamaCppConfig",
    "MlflowConfig",
    "MutateConfig",
    "OpenAIConfig",
    "OptimizeConfig",
    "PerturbConfig",
    "PolicyFileConfig",
    "RayExecutorConfig",
    "RenderConfig",
    "ReportConfig",
    "SearchConfig",
    "SearchLoopConfig",
    "SimplifyAppConfig",
    "SimplifyConfig",
    "TaskConfig",
    "TrackerConfig",
    "VLLMConfig",
    "option",
]
