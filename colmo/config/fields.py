"""The building blocks of every schema: a documented field (`option`) and the checks that turn a
bad value into one `ConfigError` line (`require`, `at_least`, `above`)."""

from __future__ import annotations

from dataclasses import field
from typing import Any

from colmo.errors import ConfigError


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
