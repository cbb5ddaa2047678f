"""Typed schemas for every Hydra config group, their validation, and the Hydra entry point.

Each YAML option in `conf/<group>/` is composed over the dataclass of its group. Ranges and
names are checked in `__post_init__`, which runs when the composed config is turned into
objects (`OmegaConf.to_object`). `hydra_app` wraps `hydra.main` so that anything a user can
get wrong (an unknown option, a value out of range, a missing file) ends in one line on
stderr and exit code 2, with the full traceback only under `hydra.verbose=true`.
"""

from __future__ import annotations

import functools
import os
import sys
from dataclasses import dataclass, field
from typing import Any, Callable, Optional

import hydra
from hydra.core.config_store import ConfigStore
from omegaconf import MISSING, DictConfig, OmegaConf

CONFIG_MODULE = "colmo.conf"
EXIT_USAGE = 2


class ConfigError(ValueError):
    """A user error in configuration or input; the message is one line naming problem and fix."""


def _require(condition: bool, message: str) -> None:
    if not condition:
        raise ConfigError(message)


@dataclass
class TaskConfig:
    name: str = MISSING
    spec: str = MISSING
    episodes: int = 10
    target_score: Optional[float] = None
    env: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        _require(self.episodes >= 1, f"task.episodes must be >= 1, got {self.episodes}")


GFO_METHODS = ("none", "oneplusone", "cma", "de", "bo")


@dataclass
class GFOConfig:
    method: str = "oneplusone"
    budget: int = 100
    workers: int = 1
    relative_step: float = 0.3
    min_step: float = 0.1
    sampler: str = "tpe"
    search_range: float = 3.0

    def __post_init__(self) -> None:
        _require(self.method in GFO_METHODS, f"gfo.method must be one of {', '.join(GFO_METHODS)}; got {self.method!r}")
        _require(self.budget >= 1, f"gfo.budget must be >= 1, got {self.budget}")
        _require(self.workers >= 1, f"gfo.workers must be >= 1, got {self.workers}")
        _require(self.relative_step > 0, f"gfo.relative_step must be > 0, got {self.relative_step}")
        _require(self.min_step > 0, f"gfo.min_step must be > 0, got {self.min_step}")
        _require(self.sampler in ("tpe", "gp"), f"gfo.sampler must be tpe or gp, got {self.sampler!r}")
        _require(self.search_range > 0, f"gfo.search_range must be > 0, got {self.search_range}")


EXECUTORS = ("local", "ray")


@dataclass
class ExecutorConfig:
    name: str = "local"
    workers: int = 0
    timeout_s: float = 600.0
    memory_mb: int = 4096
    address: Optional[str] = None
    max_retries: int = 2

    def __post_init__(self) -> None:
        _require(self.name in EXECUTORS, f"executor.name must be one of {', '.join(EXECUTORS)}; got {self.name!r}")
        _require(self.max_retries >= 0, f"executor.max_retries must be >= 0, got {self.max_retries}")
        _require(self.workers >= 0, f"executor.workers must be >= 0 (0 = all cores), got {self.workers}")
        _require(self.timeout_s > 0, f"executor.timeout_s must be > 0, got {self.timeout_s}")
        _require(self.memory_mb >= 256, f"executor.memory_mb must be >= 256, got {self.memory_mb}")

    @property
    def n_workers(self) -> int:
        # The cores this process may use (a SLURM allocation), not all the node's cores.
        return self.workers or len(os.sched_getaffinity(0)) or 1


@dataclass
class DatabaseConfig:
    num_islands: int = 10
    functions_per_prompt: int = 2
    reset_every: int = 400
    cluster_temperature_init: float = 0.1
    cluster_temperature_period: int = 30000
    length_temperature: float = 1.0

    def __post_init__(self) -> None:
        _require(self.num_islands >= 1, f"database.num_islands must be >= 1, got {self.num_islands}")
        _require(self.functions_per_prompt >= 1, f"database.functions_per_prompt must be >= 1, got {self.functions_per_prompt}")
        _require(self.reset_every >= 0, f"database.reset_every must be >= 0 (0 = never), got {self.reset_every}")
        _require(self.cluster_temperature_init > 0, "database.cluster_temperature_init must be > 0")
        _require(self.cluster_temperature_period >= 1, "database.cluster_temperature_period must be >= 1")
        _require(self.length_temperature > 0, "database.length_temperature must be > 0")


@dataclass
class GeneratorConfig:
    """Fields every program generator (config group `llm`) has."""

    name: str = MISSING
    batch_size: int = 4

    def __post_init__(self) -> None:
        _require(self.batch_size >= 1, f"llm.batch_size must be >= 1, got {self.batch_size}")


@dataclass
class MutateConfig(GeneratorConfig):
    """The embedded generator: genetic operators on the program AST, no model, no network."""

    name: str = "mutate"
    crossover_rate: float = 0.3
    max_mutations: int = 3
    constant_sigma: float = 0.5


@dataclass
class OpenAIConfig(GeneratorConfig):
    """Any OpenAI-compatible chat-completions endpoint (vllm serve, Ollama, llama.cpp, OpenAI)."""

    name: str = "openai"
    base_url: list[str] = field(default_factory=lambda: ["http://localhost:8000/v1"])
    model: str = "Qwen/Qwen2.5-Coder-7B-Instruct"
    api_key_env: str = "OPENAI_API_KEY"
    temperature: float = 1.0
    top_p: float = 1.0
    max_tokens: int = 1024
    use_n: bool = True
    timeout_s: float = 120.0
    max_retries: int = 5
    backoff_s: float = 1.0
    max_backoff_s: float = 60.0
    max_consecutive_failures: int = 10

    def __post_init__(self) -> None:
        super().__post_init__()
        _require(len(self.base_url) >= 1, "llm.base_url needs at least one URL")
        _require(self.max_tokens >= 1, f"llm.max_tokens must be >= 1, got {self.max_tokens}")
        _require(self.timeout_s > 0, f"llm.timeout_s must be > 0, got {self.timeout_s}")
        _require(self.max_retries >= 0, f"llm.max_retries must be >= 0, got {self.max_retries}")


@dataclass
class VLLMConfig(GeneratorConfig):
    """In-process `vllm.LLM` batched generation on local GPUs."""

    name: str = "vllm"
    model: str = "Qwen/Qwen2.5-Coder-7B-Instruct"
    temperature: float = 1.0
    top_p: float = 1.0
    max_tokens: int = 1024
    quantization: Optional[str] = None
    dtype: str = "auto"
    tensor_parallel_size: int = 1
    pipeline_parallel_size: int = 1
    gpu_memory_utilization: float = 0.9
    max_model_len: Optional[int] = None
    seed: int = 0

    def __post_init__(self) -> None:
        super().__post_init__()
        _require(0 < self.gpu_memory_utilization <= 1, "llm.gpu_memory_utilization must be in (0, 1]")
        _require(self.tensor_parallel_size >= 1 and self.pipeline_parallel_size >= 1, "llm parallel sizes must be >= 1")


@dataclass
class SearchLoopConfig:
    max_samples: int = 1000
    max_seconds: float = 0.0
    target_score: Optional[float] = None
    queue_size: int = 2
    progress: bool = True

    def __post_init__(self) -> None:
        _require(self.max_samples >= 1, f"search.max_samples must be >= 1, got {self.max_samples}")
        _require(self.max_seconds >= 0, f"search.max_seconds must be >= 0 (0 = no limit), got {self.max_seconds}")
        _require(self.queue_size >= 1, f"search.queue_size must be >= 1, got {self.queue_size}")


@dataclass
class TrackerConfig:
    """Where runs are logged: `mlflow` (default) or `none`."""

    name: str = "mlflow"
    tracking_uri: Optional[str] = None
    experiment: Optional[str] = None
    run_name: Optional[str] = None

    def __post_init__(self) -> None:
        _require(self.name in ("mlflow", "none"), f"tracker.name must be mlflow or none, got {self.name!r}")


@dataclass
class SearchConfig:
    task: TaskConfig = MISSING
    gfo: GFOConfig = MISSING
    llm: Any = MISSING
    database: DatabaseConfig = MISSING
    executor: ExecutorConfig = MISSING
    tracker: TrackerConfig = MISSING
    search: SearchLoopConfig = field(default_factory=SearchLoopConfig)
    seed: int = 0
    resume: Optional[str] = None


@dataclass
class OptimizeConfig:
    task: TaskConfig = MISSING
    gfo: GFOConfig = MISSING
    executor: ExecutorConfig = MISSING
    policy_file: str = MISSING
    seed: int = 0


def register_schemas() -> None:
    store = ConfigStore.instance()
    store.store(group="task", name="schema", node=TaskConfig)
    store.store(group="gfo", name="schema", node=GFOConfig)
    store.store(group="executor", name="schema", node=ExecutorConfig)
    store.store(group="database", name="schema", node=DatabaseConfig)
    store.store(group="tracker", name="schema", node=TrackerConfig)
    store.store(group="llm", name="mutate_schema", node=MutateConfig)
    store.store(group="llm", name="openai_schema", node=OpenAIConfig)
    store.store(group="llm", name="vllm_schema", node=VLLMConfig)
    store.store(name="optimize_schema", node=OptimizeConfig)
    store.store(name="search_schema", node=SearchConfig)


def to_objects(cfg: DictConfig) -> Any:
    """The composed config as validated dataclasses; `ConfigError` on a missing or bad value."""
    missing = sorted(OmegaConf.missing_keys(cfg))
    if missing:
        raise ConfigError(f"missing value for {', '.join(missing)}: pass it as an override, e.g. {missing[0]}=...")
    try:
        return OmegaConf.to_object(cfg)
    except Exception as error:
        cause = error.__cause__ if isinstance(error.__cause__, ConfigError) else error
        raise ConfigError(one_line(cause)) from None


def one_line(error: BaseException) -> str:
    """The first line of an error, with the first line of its cause when that says more."""
    first = (str(error).strip().splitlines() or [type(error).__name__])[0]
    options = getattr(error, "options", None)  # Hydra's MissingConfigException knows the choices
    if options:
        choices = [o for o in options if not o.endswith("schema")]
        return f"{first}; available: {', '.join(choices)}"
    cause = error.__cause__
    if cause is not None and str(cause).strip():
        detail = str(cause).strip().splitlines()[0]
        if detail not in first:
            return f"{first.rstrip('.')}: {detail}"
    return first


def _verbose() -> bool:
    return any(arg.replace(" ", "") in ("hydra.verbose=true", "hydra.verbose=True") for arg in sys.argv[1:])


def _validate_overrides(config_name: str, overrides: list[str], check: Optional[Callable[[Any], None]]) -> None:
    """Compose the config for every value of every sweep before Hydra starts, so a bad override
    is reported in one line (Hydra's own report is several lines and exits 1)."""
    from hydra import compose, initialize_config_module
    from hydra.core.override_parser.overrides_parser import OverridesParser

    parsed = OverridesParser.create().parse_overrides(overrides)
    user = [o for o in parsed if not o.key_or_group.startswith("hydra") or o.key_or_group == "hydra.searchpath"]
    first = [o.input_line if not o.is_sweep_override() else f"{o.get_key_element()}={next(iter(o.sweep_string_iterator()))}" for o in user]
    variants = [first]
    for index, override in enumerate(user):
        if override.is_sweep_override():
            for value in override.sweep_string_iterator():
                variant = list(first)
                variant[index] = f"{override.get_key_element()}={value}"
                variants.append(variant)
    with initialize_config_module(config_module=CONFIG_MODULE, version_base="1.3"):
        for variant in variants:
            cfg = to_objects(compose(config_name=config_name, overrides=variant))
            if check is not None:
                check(cfg)


def hydra_app(
    config_name: str, check: Optional[Callable[[Any], None]] = None
) -> Callable[[Callable[[Any], Any]], Callable[[], None]]:
    """`hydra.main` over colmo's bundled configs, with one-line user errors and exit code 2.

    `check(cfg)` vets the inputs a config names (files, directories) for every job of a sweep
    before Hydra starts, raising `ConfigError`, so a bad input leaves no output directory."""

    def decorate(run: Callable[[Any], Any]) -> Callable[[], None]:
        @functools.wraps(run)
        def task_function(cfg: DictConfig) -> Any:
            try:
                return run(to_objects(cfg))
            except ConfigError as error:
                _fail(error)

        hydra_main = hydra.main(config_path=f"pkg://{CONFIG_MODULE}", config_name=config_name, version_base="1.3")(task_function)

        def main() -> None:
            register_schemas()
            overrides, config_dir = _split_command_line(sys.argv[1:])
            if config_dir:
                overrides.append(f"hydra.searchpath=[file://{os.path.abspath(config_dir)}]")
            if not any(a in ("--help", "-h", "--hydra-help", "--info", "-i", "--cfg", "-c") for a in sys.argv[1:]):
                try:
                    _validate_overrides(config_name, overrides, check)
                except Exception as error:  # every composition error is the user's: one line
                    _fail(error)
            hydra_main()

        return main

    return decorate


_FLAGS_WITH_VALUE = ("--config-path", "-cp", "--config-name", "-cn", "--config-dir", "-cd", "--experimental-rerun")


def _split_command_line(args: list[str]) -> tuple[list[str], str | None]:
    """The overrides on a Hydra command line, and its --config-dir if any."""
    overrides, config_dir = [], None
    iterator = iter(args)
    for arg in iterator:
        if arg in _FLAGS_WITH_VALUE:
            value = next(iterator, None)
            if arg in ("--config-dir", "-cd"):
                config_dir = value
        elif not arg.startswith("-"):
            overrides.append(arg)
    return overrides, config_dir


def _fail(error: BaseException) -> None:
    if _verbose():
        raise error
    message = one_line(error)
    print(f"colmo: error: {message}", file=sys.stderr)
    sys.exit(EXIT_USAGE)
