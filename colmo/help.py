"""colmo's `--help`: the app, its config groups with their options (the chosen ones marked),
and the documented fields of the composed config with their values, all read from the schemas in
`colmo.config` and the option files in `colmo/conf/` (each option's heading comment)."""

from __future__ import annotations

import dataclasses
import inspect
import json
import sys
import textwrap
from importlib import resources
from pathlib import Path
from typing import Optional

from omegaconf import DictConfig, ListConfig, OmegaConf, open_dict

from colmo import config
from colmo.components import register_schemas
from colmo.config.schemas import CONFIG_MODULE

_HELP_WIDTH = 100


def _group_options(group: str) -> list[str]:
    folder = resources.files(CONFIG_MODULE) / group
    return sorted(entry.name.removesuffix(".yaml") for entry in folder.iterdir() if entry.name.endswith(".yaml"))


def _option_summary(group: str, option: str) -> str:
    """The comment heading an option's YAML file, up to its first line that ends a sentence
    (pointers to the schema left out): what the option is."""
    text = (resources.files(CONFIG_MODULE) / group / f"{option}.yaml").read_text()
    comment: list[str] = []
    for line in text.splitlines():
        if not line.startswith("#") or (comment and comment[-1].endswith((".", ":"))):
            break
        comment.append(line.lstrip("# ").strip())
    return " ".join(comment).split(" Fields and defaults")[0]


def _wrapped(text: str, indent: int, hanging: int = 0) -> list[str]:
    return textwrap.wrap(text, _HELP_WIDTH, initial_indent=" " * indent, subsequent_indent=" " * (indent + hanging)) or [""]


def _shown(node: DictConfig, name: str) -> str:
    """A field's value in the composed config, as an override would write it."""
    if OmegaConf.is_missing(node, name):
        return "???"
    value = node[name]
    if isinstance(value, (DictConfig, ListConfig)):
        return json.dumps(OmegaConf.to_container(value, resolve=False), separators=(",", ":"))
    return "null" if value is None else str(value).lower() if isinstance(value, bool) else str(value)


def _field_lines(node: DictConfig, prefix: str) -> list[str]:
    """`prefix.field=value` and its documentation, for each documented field of the dataclass
    `node` was composed from (the chosen option's own schema); a field that is itself a schema
    (`task.perturb`) with each of its own fields."""
    schema = OmegaConf.get_type(node)
    lines = []
    for item in dataclasses.fields(schema):
        if "help" not in item.metadata:
            continue
        value = None if OmegaConf.is_missing(node, item.name) else node[item.name]
        if isinstance(value, DictConfig) and dataclasses.is_dataclass(OmegaConf.get_type(value)):
            lines += [f"  {prefix}{item.name}.*:", *_wrapped(_field_help(schema, item), 6), *_field_lines(value, f"{prefix}{item.name}.")]
        else:
            lines += [f"  {prefix}{item.name}={_shown(node, item.name)}", *_wrapped(_field_help(schema, item), 6)]
    return lines


def _field_help(schema: type, item: dataclasses.Field) -> str:
    """A field's documentation; for one naming a component, with the names its registry has."""
    if "registry" not in item.metadata:
        return item.metadata["help"]
    return f"{item.metadata['help']}: one of {config.fields.registry_of(schema, item.name).choices()}"


def _program_name() -> str:
    """How the user called the app: its console script, or `python -m colmo...`."""
    main = sys.modules.get("__main__")
    module = getattr(getattr(main, "__spec__", None), "name", None)
    if module:
        return "python -m " + module.removesuffix(".__main__")
    return Path(sys.argv[0]).name


def _usage(prog: str, example: str) -> list[str]:
    forms = [
        (f"{prog} [GROUP=OPTION ...] [KEY=VALUE ...]", f"one run, e.g. {example}"),
        (f"{prog} -m KEY=A,B [KEY=C,D ...]", "a sweep: one job per combination of values"),
        (f"{prog} [GROUP=OPTION ...] --help", "this help, for the options chosen"),
        (f'eval "$({prog} -sc install=bash)"', "shell completion of groups, options and keys"),
    ]
    width = max(len(form) for form, _ in forms)
    return [f"  {form:<{width}}   {what}" for form, what in forms]


def help_text(config_name: str, summary: str, overrides: list[str], example: Optional[str] = None) -> str:
    """colmo's `--help`: the app, its config groups with their options (the chosen ones marked),
    and the documented fields of the config that `overrides` compose, with their values."""
    from hydra import compose as hydra_compose
    from hydra import initialize_config_module

    register_schemas()
    with initialize_config_module(config_module=CONFIG_MODULE, version_base="1.3"):
        composed = hydra_compose(config_name=config_name, overrides=overrides, return_hydra_config=True)
    choices = composed.hydra.runtime.choices
    with open_dict(composed):
        del composed["hydra"]
    root = OmegaConf.get_type(composed)
    prog = _program_name()
    groups = [name for name in (item.name for item in dataclasses.fields(root)) if name in choices and (resources.files(CONFIG_MODULE) / name).is_dir()]
    lines = [
        f"{prog}: {(root.__doc__ or '').strip().split(': ', 1)[-1]}", *_wrapped(inspect.cleandoc(summary).split("\n\n")[0], 0), "",
        "Usage:",
        *_usage(prog, f"{prog} {example or ' '.join(f'{g}={choices[g]}' for g in groups[:2]) + ' seed=1'}"),
    ]
    if groups:
        lines += ["", "Config groups (GROUP=OPTION; * chosen):"]
    for group in groups:
        lines.append(f"  {group}")
        for option in _group_options(group):
            mark = "*" if option == choices[group] else " "
            lines += _wrapped(f"{option:<12} {mark} {_option_summary(group, option)}", 4, 15)
    lines += ["", "Options (KEY=VALUE, shown with their values in the config chosen above):"]
    lines += _field_lines(composed, "")
    for item in dataclasses.fields(root):
        node = None if OmegaConf.is_missing(composed, item.name) else composed[item.name]
        if isinstance(node, DictConfig) and dataclasses.is_dataclass(OmegaConf.get_type(node)):
            chosen = f"{item.name}={choices[item.name]}" if item.name in choices else item.name
            lines += ["", f" {chosen}:", *_field_lines(node, f"{item.name}.")]
    lines += ["", "More: --cfg job (the composed config), --hydra-help (Hydra's own flags), hydra.verbose=true (tracebacks)."]
    return "\n".join(lines)
