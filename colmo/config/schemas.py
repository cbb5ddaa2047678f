"""The schemas of the config groups and apps, by the name the YAML options of the bundled configs
(`CONFIG_MODULE`, colmo/conf/) put in their defaults list (`- schema`, `- search_schema`), so that
every option is composed over its group's dataclass. A component's own option schema
(`- bo_schema`) is not listed here: `colmo.components` adds it from the component's registry,
where the component says which schema it needs (its `options`)."""

from __future__ import annotations

from typing import Optional

from colmo.config.apps import EvaluateConfig, OptimizeConfig, RenderConfig, ReportConfig, SearchConfig, SimplifyAppConfig
from colmo.config.components import ExecutorConfig, GFOConfig, TrackerConfig
from colmo.config.search import DatabaseConfig
from colmo.config.task import TaskConfig

CONFIG_MODULE = "colmo.conf"  # the bundled configs (colmo/conf/)
# Schemas by the name the YAML options put in their defaults list.
SCHEMAS: dict[tuple[Optional[str], str], type] = {
    ("task", "schema"): TaskConfig,
    ("gfo", "schema"): GFOConfig,
    ("executor", "schema"): ExecutorConfig,
    ("database", "schema"): DatabaseConfig,
    ("tracker", "schema"): TrackerConfig,
    (None, "search_schema"): SearchConfig,
    (None, "optimize_schema"): OptimizeConfig,
    (None, "evaluate_schema"): EvaluateConfig,
    (None, "simplify_schema"): SimplifyAppConfig,
    (None, "render_schema"): RenderConfig,
    (None, "report_schema"): ReportConfig,
}
