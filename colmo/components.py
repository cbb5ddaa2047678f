"""Every component colmo can build, and the schema table Hydra composes their options with.

The components of each kind are in their registry (`colmo.registry`), filled where each is
defined: GFO methods (`gfo.method`), generators (`llm.name`), executors (`executor.name`) and
trackers (`tracker.name`). `load()` imports the modules that define colmo's own, and the modules
that installed packages name as entry points of the group `colmo.components`, for what they
register (in a package's pyproject.toml: `[project.entry-points."colmo.components"]` then
`my_method = "my_package.my_method"`).

`register_schemas()` builds the schema table from them: the config groups' own schemas and the
apps' (`colmo.config.schemas`), each component's option schema (its `options`) as
`<group>/<name>_schema` where it has its own, and, for a component that no bundled option file
describes, the option itself as `<group>/<name>`: an installed method is `gfo=<name>`, its
options `gfo.<field>=...`, with no YAML file (docs/extending.md).
"""

from __future__ import annotations

import functools
import importlib
from importlib import metadata, resources
from typing import Any

from hydra.core.config_store import ConfigStore
from omegaconf import OmegaConf

from colmo.config.schemas import CONFIG_MODULE, SCHEMAS
from colmo.errors import ConfigError
from colmo.registry import Registry

ENTRY_POINTS = "colmo.components"
_BUNDLED = ("colmo.optimize.methods", "colmo.generate", "colmo.executor", "colmo.trackers")


@functools.cache
def load() -> tuple[Registry, ...]:
    """The registries, with colmo's components and those of installed packages registered
    (once per process); `ConfigError` naming a package's entry point that fails to import."""
    registries: dict[int, Registry] = {}
    for module in _BUNDLED:
        registries |= {id(value): value for value in vars(importlib.import_module(module)).values() if isinstance(value, Registry)}
    for entry in metadata.entry_points(group=ENTRY_POINTS):
        try:
            entry.load()
        except Exception as error:
            raise ConfigError(f"the {ENTRY_POINTS} entry point {entry.name} = {entry.value} fails to import: {type(error).__name__}: {error}") from None
    return tuple(registries.values())


def schema_table() -> dict[tuple[str | None, str], Any]:
    """What Hydra's `ConfigStore` holds for colmo, by (group, name) (module docstring)."""
    table: dict[tuple[str | None, str], Any] = dict(SCHEMAS)
    for registry in load():
        base = SCHEMAS.get((registry.group, "schema"))
        field = registry.key.split(".", 1)[1]
        for name, component in registry.items():
            options = component.options
            if options is not base:
                table[(registry.group, f"{name}_schema")] = options
            if not (resources.files(CONFIG_MODULE) / registry.group / f"{name}.yaml").is_file():
                node = OmegaConf.structured(options)
                node[field] = name
                table[(registry.group, name)] = node
    return table


def schema_names() -> set[str]:
    """The `group=name` entries of the table that are schemas, not options a user picks."""
    return {f"{group}={name}" for group, name in schema_table() if group is not None and name.endswith("schema")}


def register_schemas() -> None:
    """Every entry of `schema_table()` in Hydra's `ConfigStore` (idempotent)."""
    store = ConfigStore.instance()
    for (group, name), node in schema_table().items():
        store.store(group=group, name=name, node=node)
