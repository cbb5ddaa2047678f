"""The one way a config option picks a component: a `Registry` of each kind, by name.

Generators (`llm.name`), GFO methods (`gfo.method`), executors (`executor.name`) and trackers
(`tracker.name`) each have one registry, filled where each component is defined
(`@REGISTRY.register("name")`, as Nevergrad's optimizers and evosax's strategies are). A
registry rather than Hydra's `_target_` + `instantiate`: a request stays plain data (a name
and typed fields), a name is checked against the registered ones before Hydra starts, and error
messages and help list the names from the registry itself. Each component says which option
schema it needs (`options`, a class of `colmo.config`), so an option file that sets a name its
schema does not fit ends in one line too. A name is registered once: a second component under
a taken name is refused. A component that runs on an optional library names it (`library`, a
`Library`), so that a command can check it is installed before it makes anything
(`Registry.check_installed`). `colmo.components` loads every registry, with the components of
installed packages, and builds Hydra's schema table from them.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from collections.abc import Iterator, Mapping
from types import ModuleType
from typing import Any, Callable, Generic, NamedTuple, TypeVar

from colmo.errors import ConfigError

T = TypeVar("T")


class Library(NamedTuple):
    """An optional library a component runs on: the module it imports, the package's name, and
    what `pip install` takes to install it (for colmo's own components, the extra of their name)."""

    module: str
    package: str
    requirement: str

    def installed(self) -> bool:
        """Whether the module can be imported: found, not imported (vLLM's import takes seconds)."""
        if self.module in sys.modules:  # imported already, or stood in for (None: hidden)
            return sys.modules[self.module] is not None
        return importlib.util.find_spec(self.module) is not None

    def missing(self, option: str) -> str:
        """The one line for `option` (`llm=vllm`) chosen without the library."""
        return f"{option} needs {self.package}: pip install '{self.requirement}'"

    def load(self, option: str, error: type[Exception] = ConfigError) -> ModuleType:
        """The imported module; `error` with the line `missing` says if it is not installed
        (a component built without `colmo.cli`'s check, from Python)."""
        try:
            return importlib.import_module(self.module)
        except ImportError:
            raise error(self.missing(option)) from None


class Registry(Mapping[str, T], Generic[T]):
    """Components of one kind by name, in registration order. `key` is the config field that
    names one (`gfo.method`); its group (`gfo`) is the option that sets it."""

    def __init__(self, key: str) -> None:
        self.key = key
        self.group = key.split(".")[0]
        self._entries: dict[str, T] = {}

    def register(self, name: str) -> Callable[[T], T]:
        """Decorator: make the component available as `<key>=<name>`; `ValueError` if another
        component has the name (a second registration of the same one changes nothing)."""

        def add(component: T) -> T:
            taken = self._entries.get(name)
            if taken is not None and taken is not component:
                raise ValueError(f"{self.key}={name} is taken by {_qualified(taken)}: {_qualified(component)} needs another name")
            self._entries[name] = component
            return component

        return add

    def __getitem__(self, name: str) -> T:
        return self._entries[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def choices(self) -> str:
        """The registered names, for an error message or help: `a, b, c`."""
        return ", ".join(sorted(self._entries))

    def chosen(self, name: str) -> T:
        """The component `name` registers; `ConfigError` listing the names if there is none."""
        if name not in self._entries:
            raise ConfigError(f"{self.key} must be one of {self.choices()}; got {name!r}")
        return self._entries[name]

    def check(self, name: str, options: Any) -> None:
        """`ConfigError` unless `name` is registered and `options` (the composed option's
        config object) is of the schema its component needs (`options` class attribute)."""
        component: Any = self.chosen(name)
        if not isinstance(options, component.options):
            raise ConfigError(f"{self.key}={name} needs the {name} options: use {self.group}={name}")


    def check_installed(self, name: str) -> None:
        """`ConfigError` unless the optional library the component `name` runs on (its `library`),
        if it has one, is installed."""
        library = getattr(self.chosen(name), "library", None)
        if library is not None and not library.installed():
            raise ConfigError(library.missing(f"{self.group}={name}"))


def _qualified(component: Any) -> str:
    return f"{getattr(component, '__module__', '?')}.{getattr(component, '__qualname__', repr(component))}"
