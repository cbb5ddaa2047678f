"""The schemas as Hydra knows them: each registered in Hydra's `ConfigStore` under the name the
YAML options of the bundled configs (`CONFIG_MODULE`, colmo/conf/) put in their defaults list
(`- schema`, `- bo_schema`), so that every option is composed over its group's dataclass. The
apps (`colmo.cli`) and `--help` (`colmo.help`) both read them from here."""

from __future__ import annotations

from typing import Optional

from hydra.core.config_store import ConfigStore

from colmo.config.apps import EvaluateConfig, OptimizeConfig, RenderConfig, ReportConfig, SearchConfig, SimplifyAppConfig
from colmo.config.components import BOConfig, ExecutorConfig, GFOConfig, MlflowConfig, RayExecutorConfig, TrackerConfig
from colmo.config.generators import LlamaCppConfig, MutateConfig, OpenAIConfig, VLLMConfig
from colmo.config.search import DatabaseConfig
from colmo.config.task import TaskConfig

CONFIG_MODULE = "colmo.conf"  # the bundled configs (colmo/conf/)
# Schemas by the name the YAML options put in their defaults list.
SCHEMAS: dict[tuple[Optional[str], str], type] = {
    ("task", "schema"): TaskConfig,
    ("gfo", "schema"): GFOConfig,
    ("gfo", "bo_schema"): BOConfig,
    ("executor", "schema"): ExecutorConfig,
    ("executor", "ray_schema"): RayExecutorConfig,
    ("database", "schema"): DatabaseConfig,
    ("tracker", "schema"): TrackerConfig,
    ("tracker", "mlflow_schema"): MlflowConfig,
    ("llm", "mutate_schema"): MutateConfig,
    ("llm", "openai_schema"): OpenAIConfig,
    ("llm", "vllm_schema"): VLLMConfig,
    ("llm", "llamacpp_schema"): LlamaCppConfig,
    (None, "search_schema"): SearchConfig,
    (None, "optimize_schema"): OptimizeConfig,
    (None, "evaluate_schema"): EvaluateConfig,
    (None, "simplify_schema"): SimplifyAppConfig,
    (None, "render_schema"): RenderConfig,
    (None, "report_schema"): ReportConfig,
}


def register_schemas() -> None:
    """Every schema in Hydra's `ConfigStore`, under its name (idempotent)."""
    store = ConfigStore.instance()
    for (group, name), schema in SCHEMAS.items():
        store.store(group=group, name=name, node=schema)
