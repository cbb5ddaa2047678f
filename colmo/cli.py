"""The command-line front end: Hydra apps with one-line errors, input checks, and help.

`hydra_app(config_name, check)` wraps `hydra.main` over colmo's bundled configs. Before Hydra
starts, the command line is read with Hydra's own argument parser and the config of every job
of a sweep is composed and validated (every value of a choice or range sweep, both ends of a
sweeper's interval; the components it names have their optional libraries installed; `check` vets
the files it names), so anything a user can get wrong ends in
one line on stderr (`colmo: error: ...`) and exit code 2 whatever Hydra flag is used
(`--cfg job task=nope` too), and leaves no output directory (an app's `check_command_line(argv)`
runs these checks alone, in process). A `ConfigError` or `RunError` during the run ends in one
line and exit code 2 or 1 (a `RunError` from `check`, such as no language-model server
answering, too). `hydra.verbose=true` shows the traceback instead. Shell
completion (`-sc install=bash`, `-sc query=bash`) is Hydra's, without the schema entries and, on
each Tab, without importing the plugins it does not need (`_shell_completion`). Every file
and directory an app creates is private (umask 077: 0600 and 0700).
`--help` is colmo's own: every config group with its options, each described by the comment
heading its YAML file (schema entries hidden, the chosen ones marked), then every documented
field of the config that the other arguments compose, with its value there and its
documentation from the schemas in `colmo.config` (`colmo llm=openai --help` shows llm=openai's).
"""

from __future__ import annotations

import atexit
import contextlib
import functools
import io
import os
import sys
import tempfile
import threading
from pathlib import Path
from typing import Any, Callable, NoReturn, Optional, Protocol

import hydra
from omegaconf import DictConfig, OmegaConf, open_dict

from colmo.components import register_schemas, schema_names
from colmo.config.fields import check_libraries
from colmo.config.schemas import CONFIG_MODULE
from colmo.errors import EXIT_INTERRUPTED, EXIT_RUNTIME, EXIT_USAGE, ConfigError, RunError, one_line
from colmo.provenance import provenance


def to_objects(cfg: DictConfig) -> Any:
    """The composed config as validated dataclasses (the schemas' checks run here); `ConfigError`
    on a missing or bad value."""
    missing = sorted(OmegaConf.missing_keys(cfg))
    if missing:
        raise ConfigError(f"missing value for {', '.join(missing)}: pass it as an override, e.g. {missing[0]}=...")
    try:
        return OmegaConf.to_object(cfg)
    except Exception as error:
        cause = error.__cause__ if isinstance(error.__cause__, ConfigError) else error
        raise ConfigError(one_line(cause)) from None


def compose(config_name: str, overrides: list[str], output_dir: Optional[bool] = None) -> Any:
    """The validated config objects of `config_name` with `overrides` (`ConfigError` if bad).
    With `output_dir` (True for a sweep, False for a single run), also check that Hydra will be
    able to create the job's output directory."""
    from hydra import compose as hydra_compose
    from hydra import initialize_config_module

    register_schemas()
    with initialize_config_module(config_module=CONFIG_MODULE, version_base="1.3"):
        composed = hydra_compose(config_name=config_name, overrides=overrides, return_hydra_config=output_dir is not None)
        if output_dir is not None:
            _check_creatable(Path(composed.hydra.sweep.dir if output_dir else composed.hydra.run.dir))
            with open_dict(composed):
                del composed["hydra"]
        return to_objects(composed)


def _check_creatable(directory: Path) -> None:
    """`ConfigError` unless `directory` exists or can be made: a directory is made and removed
    in its nearest existing ancestor (permission bits do not tell: root ignores them, and
    /proc or a read-only file system refuses anyway)."""
    ancestor = directory.absolute()
    while not ancestor.exists():
        ancestor = ancestor.parent
    if ancestor == directory.absolute() and ancestor.is_dir():
        return
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".colmo-check-", dir=ancestor))
    except OSError as error:
        cause = error.strerror or type(error).__name__
        reason = f"{ancestor} is not a directory" if not ancestor.is_dir() else f"making a directory in {ancestor} fails: {cause}"
        raise ConfigError(f"cannot create the output directory {directory}: {reason}") from None


# Config keys renamed since a release, old prefix -> new (the old names keep working, with a
# line saying the new one): `evaluation` named both held-out scoring and the search's finish.
RENAMED_KEYS = {"evaluation.episodes": "heldout.episodes", "evaluation.": "finish."}


def renamed(argv: list[str]) -> list[str]:
    """`argv` with each override of a renamed key (`RENAMED_KEYS`) written with its new name, a
    line on stderr saying it (`evaluation={...}`, the whole group, is not rewritten)."""
    result = []
    for arg in argv:
        prefix = arg[: len(arg) - len(arg.lstrip("+~"))]
        key = arg[len(prefix) :].split("=", 1)[0]
        old = next((old for old in RENAMED_KEYS if key == old or (old.endswith(".") and key.startswith(old))), None)
        if old is not None and not arg.startswith("-"):
            new = RENAMED_KEYS[old] + key[len(old) :] if old.endswith(".") else RENAMED_KEYS[old]
            print(f"colmo: {key} is now {new}: use the new name, the old one will stop working", file=sys.stderr)
            arg = prefix + new + arg[len(prefix) + len(key) :]
        result.append(arg)
    return result


def _verbose(overrides: list[str]) -> bool:
    return any(arg.replace(" ", "").lower() == "hydra.verbose=true" for arg in overrides)


def _sweep_values(override: Any) -> list[str]:
    """The values of a sweep override as override strings: every choice or range value; the
    two ends of an interval (what a sweeper like Optuna's samples from), as integers when
    tagged `int` or written as integers."""
    from hydra.core.override_parser.types import Transformer

    if not override.is_interval_sweep():
        return list(override.sweep_string_iterator())
    interval = override.value()
    integer = "int" in interval.tags or (isinstance(interval.start, int) and isinstance(interval.end, int))
    ends = (interval.start, interval.end)
    return [str(int(end)) if integer else Transformer.encode(float(end)) for end in ends]


def _sweep_variants(overrides: list[str], multirun: bool) -> list[list[str]]:
    """The override lists of the first job and of each other value of each sweep, so that
    every value a sweep takes is composed once; `ConfigError` for a sweep without `multirun`
    (Hydra's own message is four lines)."""
    from hydra.core.override_parser.overrides_parser import OverridesParser

    parsed = OverridesParser.create().parse_overrides(overrides)
    for override in parsed:
        if override.is_sweep_override() and not multirun:
            key = override.get_key_element()
            raise ConfigError(f"{override.input_line} is a sweep: add -m for one job per value (or write a list {key}=[a,b], a string {key}='a,b')")
    first = [o.input_line if not o.is_sweep_override() else f"{o.get_key_element()}={_sweep_values(o)[0]}" for o in parsed]
    variants = [first]
    for index, override in enumerate(parsed):
        if override.is_sweep_override():
            for value in _sweep_values(override)[1:]:
                variant = list(first)
                variant[index] = f"{override.get_key_element()}={value}"
                variants.append(variant)
    return variants


class App(Protocol):
    """A colmo command (what `hydra_app` makes): called, it runs the command line in `sys.argv`;
    `check_command_line(argv)` raises what it would refuse `argv` with before Hydra starts
    (`ConfigError`, or a `RunError` from its input check) and runs nothing, so that the checks
    can be tested without starting a process per command line."""

    def __call__(self) -> None: ...

    def check_command_line(self, argv: list[str]) -> None: ...


def _overrides(args: Any) -> list[str]:
    """The overrides of a parsed command line, `--config-dir` as Hydra's search path."""
    overrides = list(args.overrides)
    if args.config_dir:
        overrides.append(f"hydra.searchpath=[file://{os.path.abspath(args.config_dir)}]")
    return overrides


def _parse(argv: list[str]) -> Any:
    """A command line as Hydra's own parser reads it."""
    from hydra._internal.utils import get_args_parser

    return get_args_parser().parse_args(argv)


def hydra_app(
    config_name: str, check: Optional[Callable[[Any], None]] = None, example: Optional[str] = None
) -> Callable[[Callable[[Any], Any]], App]:
    """`hydra.main` over colmo's bundled configs, with one-line errors (module docstring).

    `check(cfg)` vets the inputs a config names (files, directories) for every job of a sweep
    before Hydra starts, raising `ConfigError`, so a bad input leaves no output directory.
    `example`: the overrides of the one-run example in `--help` (default: two groups' options
    and `seed=1`)."""

    def decorate(run: Callable[[Any], Any]) -> App:
        @functools.wraps(run)
        def task_function(cfg: DictConfig) -> Any:
            provenance()  # taken as the job starts: editing the checkout during a run changes not what it records
            try:
                return run(to_objects(cfg))
            except (ConfigError, RunError) as error:
                from hydra.core.hydra_config import HydraConfig

                _fail(error, verbose=bool(HydraConfig.get().verbose))  # the job's config has no `hydra` node

        hydra_main = hydra.main(config_path=f"pkg://{CONFIG_MODULE}", config_name=config_name, version_base="1.3")(task_function)

        def check_overrides(args: Any) -> None:
            """Compose and validate the config of every job the parsed command line `args` would
            run, and `check` it; nothing to do for shell completion and `--hydra-help`."""
            if args.shell_completion or args.hydra_help:
                return
            for variant in _sweep_variants(_overrides(args), multirun=bool(args.multirun)):
                cfg = compose(config_name, variant, output_dir=None if args.cfg or args.info else args.multirun)
                if args.cfg or args.info:
                    continue
                check_libraries(cfg)
                if check is not None:
                    check(cfg)

        def main() -> None:
            try:
                register_schemas()  # imports installed packages' components: one may fail
            except ConfigError as error:
                _fail(error, verbose=_verbose(sys.argv[1:]))
            sys.argv[1:] = renamed(sys.argv[1:])  # Hydra reads sys.argv itself
            args = _parse(sys.argv[1:])
            if args.help:
                from colmo.help import help_text  # only for --help: textwrap, resources, inspect

                try:
                    text = help_text(config_name, run.__doc__ or "", list(args.overrides), example)
                except Exception as error:  # a bad override: one line, as for a run
                    _fail(error, verbose=_verbose(args.overrides), code=EXIT_USAGE)
                try:
                    print(text, flush=True)
                except BrokenPipeError:  # `colmo --help | head`: the reader has what it wanted
                    os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
                return
            if sum(map(bool, (args.run, args.multirun, args.cfg, args.info, args.shell_completion))) > 1:
                _fail(ConfigError("only one of --run, --multirun, --cfg, --info and --shell-completion can be given"), verbose=False)
            try:
                check_overrides(args)
            except Exception as error:  # one line: a composition error is the user's (exit 2), a RunError not (1)
                _fail(error, verbose=_verbose(_overrides(args)))
            # Whatever the run writes is private, in a directory the user made too: programs'
            # code and failure messages (a program chooses its own), logs, the tracking store,
            # videos, also those that Hydra, MLflow, SQLite and ffmpeg create.
            os.umask(0o077)
            try:
                if args.shell_completion:
                    _shell_completion(hydra_main, list(args.overrides))
                else:
                    hydra_main()
            except SystemExit as stop:
                _exit_now(stop.code)
            except KeyboardInterrupt:  # a Ctrl-C the app does not handle itself (or a second one)
                print("colmo: interrupted", file=sys.stderr)
                _exit_now(EXIT_INTERRUPTED)
            _exit_now(0)

        main.check_command_line = lambda argv: check_overrides(_parse(renamed(argv)))
        return main

    return decorate


def _shell_completion(hydra_main: Callable[[], None], overrides: list[str]) -> None:
    """Hydra's shell completion (`-sc install=bash`, `-sc query=bash`). A query, which the shell
    runs on every Tab, is answered without the schema entries (`gfo=schema`: not options a user
    picks) and, unless the line typed so far picks an option of Hydra's own groups
    (`hydra/launcher=joblib`, which installed plugins provide), with Hydra's core plugins only:
    Hydra imports every installed plugin before it answers, and the Optuna sweeper's imports of
    MLflow and Optuna alone cost over a second per Tab."""
    if not any(override.startswith("query=") for override in overrides):
        hydra_main()
        return
    if "hydra/" not in os.environ.get("COMP_LINE", ""):
        sys.modules["hydra_plugins"] = None  # its import fails: Hydra's "no plugins installed" case
    with contextlib.redirect_stdout(io.StringIO()) as answer:
        hydra_main()
    hidden = schema_names()
    for line in answer.getvalue().splitlines():  # bash: one line of words; fish: a word per line
        words = [word for word in line.split(" ") if word.lstrip("+~") not in hidden]
        if words or not line:
            print(" ".join(words))


def _exit_now(code: Any) -> NoReturn:
    """End the process once an app has run: the exit handlers run (logging, MLflow, thread
    pools), the interpreter's teardown does not. Tearing down the thousands of modules a search
    imports (Nevergrad brings pandas, pyarrow, scikit-learn) can take tens of seconds on a loaded
    machine, past `search.max_seconds`; everything colmo writes is closed by then.

    The exit is the interpreter's own up to the teardown, in its order: first the threading
    module's shutdown (its exit hooks, which stop thread and process pools such as joblib's
    loky workers, and the join of non-daemon threads), then the `atexit` handlers. With the
    `atexit` handlers alone, multiprocessing's waited on loky's idle workers for their
    300 s timeout after every `hydra/launcher=joblib` sweep."""
    if isinstance(code, str):  # sys.exit("message"), as Python itself reports it
        print(code, file=sys.stderr)
        code = 1
    threading._shutdown()
    atexit._run_exitfuncs()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0 if code is None else code)


def refusal(error: BaseException) -> tuple[int, str]:
    """The exit code and the one line (`colmo: error: ...`) an app ends with for `error`: the
    user's (2) unless it is a `RunError` (1)."""
    return EXIT_RUNTIME if isinstance(error, RunError) else EXIT_USAGE, f"colmo: error: {one_line(error)}"


def _fail(error: BaseException, verbose: bool, code: Optional[int] = None) -> None:
    if verbose:
        raise error
    default, line = refusal(error)
    print(line, file=sys.stderr)
    sys.exit(code if code is not None else default)
