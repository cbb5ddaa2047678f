"""The building blocks of every schema: a documented field (`option`), a field naming a registered
component (`component`), and the checks that turn a bad value into one `ConfigError` line
(`require`, `at_least`, `above`, `check_component`), and the check that the components a config
names have their optional libraries (`check_libraries`)."""

from __future__ import annotations

import dataclasses
import importlib
from dataclasses import field
from typing import TYPE_CHECKING, Any, Optional

from colmo.errors import ConfigError

if TYPE_CHECKING:
    from colmo.registry import Registry


def require(condition: bool, message: str) -> None:
    if not condition:
        raise ConfigError(message)


def at_least(config: Any, group: str, **minimums: float) -> None:
    """`ConfigError` for the first field of `config` below its minimum."""
    for name, minimum in minimums.items():
        value = getattr(config, name)
        require(value >= minimum, f"{group}.{name} must be >= {minimum}, got {value}")


def above(config: Any, group: str, **bounds: float) -> None:
    """`ConfigError` for the first field of `config` not above its bound."""
    for name, bound in bounds.items():
        value = getattr(config, name)
        require(value > bound, f"{group}.{name} must be > {bound}, got {value}")


def option(default: Any, help: str) -> Any:  # noqa: A002 - the documented name
    """A schema field with its documentation (`colmo --help` shows it)."""
    if isinstance(default, (dict, list)):
        return field(default_factory=lambda: type(default)(default), metadata={"help": help})
    return field(default=default, metadata={"help": help})


def component(default: Any, help: str, registry: str) -> Any:  # noqa: A002 - the documented name
    """A schema field naming a registered component (`colmo.registry`). `registry` says where
    its registry is, `module:NAME`: imported when a name is checked or shown, since the modules
    that define the components import these schemas."""
    return field(default=default, metadata={"help": help, "registry": registry})


def registry_of(schema: Any, name: str) -> Registry:
    """The registry of the `component` field `name` of a schema (a dataclass or an instance),
    declared where the field is (a subclass may give it another default: `BOConfig.method`)."""
    where = _registry_path(schema, name)
    if where is None:
        schema = schema if isinstance(schema, type) else type(schema)
        raise TypeError(f"{schema.__name__}.{name} is not a component field")
    module, attribute = where.split(":")
    return getattr(importlib.import_module(module), attribute)


def _registry_path(schema: Any, name: str) -> Optional[str]:
    """Where the registry of field `name` is (`module:NAME`), None if it names no component."""
    schema = schema if isinstance(schema, type) else type(schema)
    for base in schema.__mro__:
        if dataclasses.is_dataclass(base):
            metadata = {item.name: item.metadata for item in dataclasses.fields(base)}.get(name, {})
            if "registry" in metadata:
                return metadata["registry"]
    return None


def check_component(config: Any, name: str) -> None:
    """`ConfigError` unless the `component` field `name` of `config` names a registered
    component whose option schema `config` is."""
    registry_of(config, name).check(getattr(config, name), config)


def check_libraries(config: Any) -> None:
    """`ConfigError` unless every component a validated config names, at any depth, has the
    optional library it runs on installed (`Registry.check_installed`)."""
    for item in dataclasses.fields(config):
        value = getattr(config, item.name)
        if dataclasses.is_dataclass(value):
            check_libraries(value)
        elif _registry_path(config, item.name) is not None:
            registry_of(config, item.name).check_installed(value)
