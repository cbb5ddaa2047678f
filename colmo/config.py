"""Typed schemas of every Hydra config group, with their documentation and validation.

Each YAML option in `conf/<group>/` is composed over the dataclass of its group and sets only
what differs from it; the defaults and the documentation of every field live here (a field's
`metadata["help"]`, which `colmo --help` shows). Ranges and names are checked in
`__post_init__`, which runs when the composed config is turned into objects (`colmo.cli`),
so a bad value is one `ConfigError` line. Groups whose options differ in kind have one schema
per kind (`gfo=bo` has a sampler, `executor=ray` an address, `llm=openai` a server).
`colmo.cli` registers the schemas with Hydra and runs the apps.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Optional

from omegaconf import MISSING

from colmo.errors import ConfigError


def _require(condition: bool, message: str) -> None:
    if not condition:
        raise ConfigError(message)


def _at_least(config: Any, group: str, **minimums: float) -> None:
    """`ConfigError` for the first field of `config` below its minimum."""
    for name, minimum in minimums.items():
        value = getattr(config, name)
        _require(value >= minimum, f"{group}.{name} must be >= {minimum}, got {value}")


def _above(config: Any, group: str, **bounds: float) -> None:
    """`ConfigError` for the first field of `config` not above its bound."""
    for name, bound in bounds.items():
        value = getattr(config, name)
        _require(value > bound, f"{group}.{name} must be > {bound}, got {value}")


def option(default: Any, help: str) -> Any:  # noqa: A002 - the documented name
    """A schema field with its documentation (`colmo --help` shows it)."""
    if isinstance(default, (dict, list)):
        return field(default_factory=lambda: type(default)(default), metadata={"help": help})
    return field(default=default, metadata={"help": help})


@dataclass
class PerturbConfig:
    """Model mismatch drawn per episode from the episode seed, for every `MujocoEnvironment`
    (`colmo.environments.perturb`); every factor 0 (the default) is the nominal model.

    Each relative magnitude `m` scales its model fields by factors drawn uniformly from
    [1 - m, 1 + m] (one per body, dof, geom or actuator), from a random stream of their own, so
    the nominal episode draws are untouched and every candidate meets the same perturbations."""

    mass: float = option(0.0, "relative range of each body's mass and inertia (scaled together)")
    damping: float = option(0.0, "relative range of each joint dof's damping")
    frictionloss: float = option(0.0, "relative range of each joint dof's dry friction (frictionloss)")
    friction: float = option(0.0, "relative range of each geom's friction coefficients")
    gain: float = option(0.0, "relative range of each actuator's gain (and, for servos, its feedback gains)")
    obs_noise: float = option(0.0, "standard deviation of Gaussian noise added to every observation entry, in its units")
    action_noise: float = option(0.0, "standard deviation of Gaussian noise added to every action, relative to its control half-range")
    delay: int = option(0, "control delay: each action is applied this many control steps late")

    def __post_init__(self) -> None:
        _at_least(self, "task.perturb", delay=0, obs_noise=0, action_noise=0)
        for name in ("mass", "damping", "frictionloss", "friction", "gain"):
            value = getattr(self, name)
            _require(0 <= value < 1, f"task.perturb.{name} must be in [0, 1), got {value}")

    @property
    def active(self) -> bool:
        """Whether anything differs from the nominal model."""
        return any(getattr(self, name) for name in self.__dataclass_fields__)


@dataclass
class TaskConfig:
    """The control task: a spec file and how it is scored."""

    name: str = option(MISSING, "the task's name (MLflow experiment, output directory)")
    spec: str = option(MISSING, "spec file: a bundled name (pendulum.py) or a path")
    episodes: int = option(10, "training episodes per score; their seeds derive from `seed`")
    target_score: Optional[float] = option(None, "reports count the samples needed to reach this score")
    env: dict[str, Any] = option({}, "keyword arguments for the spec's make_environment")
    perturb: PerturbConfig = field(default_factory=PerturbConfig, metadata={"help": "per-episode model mismatch (default: none)"})

    def __post_init__(self) -> None:
        _at_least(self, "task", episodes=1)


@dataclass
class GFOConfig:
    """The gradient-free optimizer that tunes each program's constants."""

    method: str = option("oneplusone", "none, or a registered method: oneplusone, cma, de, bo")
    budget: int = option(100, "evaluations per program, its own constants included")
    workers: int = option(1, "candidates evaluated at a time, where the method allows it")
    relative_step: float = option(0.3, "initial step of each constant, relative to its magnitude")
    min_step: float = option(0.1, "floor of the initial step, for constants near 0")
    racing: Optional[bool] = option(
        None, "stop a candidate's episodes once a paired test on the same seeds says it very likely cannot beat the best "
        "(colmo.racing.Race); null: on for the comparison-based methods (oneplusone, cma, de)",
    )
    racing_min_episodes: int = option(2, "episodes a candidate always runs before racing may stop it (at least 2: the test needs a spread)")
    racing_margin: float = option(0.002, "racing also stops a candidate unlikely to beat the best by more than this fraction of its return")

    def __post_init__(self) -> None:
        from colmo.optimize.methods import METHODS

        names = ("none", *METHODS)
        _require(self.method in names, f"gfo.method must be one of {', '.join(names)}; got {self.method!r}")
        _require(self.method != "bo" or isinstance(self, BOConfig), "gfo.method=bo needs the bo options: use gfo=bo")
        _at_least(self, "gfo", budget=1, workers=1, racing_min_episodes=2, racing_margin=0)
        _above(self, "gfo", relative_step=0, min_step=0)

    @property
    def tunes_constants(self) -> bool:
        """Whether the method changes a program's constants: every method but `none`, which
        evaluates the program as written."""
        return self.method != "none"

    @property
    def racing_on(self) -> bool:
        if self.racing is not None:
            return self.racing
        from colmo.optimize.methods import METHODS

        return self.method in METHODS and METHODS[self.method].comparison_based


@dataclass
class BOConfig(GFOConfig):
    """Optuna's Bayesian optimization."""

    method: str = "bo"
    sampler: str = option("tpe", "tpe, or gp (needs PyTorch)")
    search_range: float = option(3.0, "each constant is searched within this many initial steps of its value")

    def __post_init__(self) -> None:
        super().__post_init__()
        _require(self.sampler in ("tpe", "gp"), f"gfo.sampler must be tpe or gp, got {self.sampler!r}")
        _above(self, "gfo", search_range=0)


@dataclass
class ExecutorConfig:
    """Where evaluations run: sandboxed worker processes on this machine."""

    name: str = option("local", "local or ray")
    workers: int = option(0, "worker processes; 0: one per core this process may use")
    timeout_s: Optional[float] = option(None, "wall-clock limit per evaluation; null: derived from the task (30 x the starter's time, at least 10 s)")
    memory_mb: int = option(4096, "address-space limit of each worker and of each program's process")
    max_retries: int = option(2, "an evaluation whose worker dies is retried this often, then recorded as failed")

    def __post_init__(self) -> None:
        _require(self.name in ("local", "ray"), f"executor.name must be local or ray; got {self.name!r}")
        _require(self.name != "ray" or isinstance(self, RayExecutorConfig), "executor.name=ray needs the ray options: use executor=ray")
        _at_least(self, "executor", max_retries=0, memory_mb=256)
        _require(self.workers >= 0, f"executor.workers must be >= 0 (0 = all cores), got {self.workers}")
        _require(self.timeout_s is None or self.timeout_s > 0, f"executor.timeout_s must be > 0, got {self.timeout_s}")

    @property
    def n_workers(self) -> int:
        # The cores this process may use (a SLURM allocation), not all the node's cores.
        return self.workers or len(os.sched_getaffinity(0)) or 1


@dataclass
class RayExecutorConfig(ExecutorConfig):
    """Evaluations on a Ray cluster: one actor per CPU, each with one sandboxed worker."""

    name: str = "ray"
    address: Optional[str] = option(None, "null: a private local Ray instance; auto: the cluster this machine joined; ray://host:10001: Ray Client")


@dataclass
class DatabaseConfig:
    """The programs database: islands, clusters, resets (FunSearch's)."""

    num_islands: int = option(10, "islands evolving independently")
    functions_per_prompt: int = option(2, "programs shown in each prompt")
    reset_every: int = option(400, "samples between resets of the weaker half of the islands (0: never)")
    cluster_temperature_init: float = option(0.1, "softmax temperature over cluster scores, annealed to 0 ...")
    cluster_temperature_period: int = option(30000, "... over this many programs per island, then restarted")
    length_temperature: float = option(1.0, "within a cluster, shorter programs are preferred")
    size_penalty: float = option(0.0, "clusters are drawn by score minus this many points per AST node of their smallest program")
    max_nodes: Optional[int] = option(None, "programs bigger than this many AST nodes are refused before they are evaluated; null: no cap")

    def __post_init__(self) -> None:
        _at_least(self, "database", num_islands=1, functions_per_prompt=1, cluster_temperature_period=1, size_penalty=0)
        _require(self.reset_every >= 0, f"database.reset_every must be >= 0 (0 = never), got {self.reset_every}")
        _above(self, "database", cluster_temperature_init=0, length_temperature=0)
        _require(self.max_nodes is None or self.max_nodes >= 1, f"database.max_nodes must be >= 1, got {self.max_nodes}")


PROMPT_FORMATS = ("chat", "completion")


@dataclass
class GeneratorConfig:
    """Fields every program generator (config group `llm`) has."""

    name: str = option(MISSING, "mutate, openai, vllm or llamacpp")
    batch_size: int = option(4, "programs generated from each prompt")

    def __post_init__(self) -> None:
        _at_least(self, "llm", batch_size=1)


@dataclass
class MutateConfig(GeneratorConfig):
    """The embedded generator: genetic operators on the program AST, no model, no network."""

    name: str = "mutate"
    crossover_rate: float = option(0.3, "chance a child starts as a crossover of the two prompt programs")
    max_mutations: int = option(3, "up to this many AST mutations per child")
    constant_sigma: float = option(0.5, "relative perturbation of constants")
    attempts: int = option(40, "redraws for a child with a new working structure; then a parent with perturbed constants")


@dataclass
class LanguageModelConfig(GeneratorConfig):
    """Sampling fields every language-model generator has."""

    prompt_format: str = option(
        "chat", "chat: the prompt's messages through the model's chat template; completion: the prompt text, "
        "ending with the header of the function to write, for the model to continue (base and code models)",
    )
    temperature: float = option(1.0, "sampling temperature")
    top_p: float = option(1.0, "nucleus sampling: the smallest set of tokens with this much probability")
    max_tokens: int = option(1024, "most tokens per answer")

    def __post_init__(self) -> None:
        super().__post_init__()
        _require(self.prompt_format in PROMPT_FORMATS, f"llm.prompt_format must be chat or completion, got {self.prompt_format!r}")
        _at_least(self, "llm", temperature=0, max_tokens=1)
        _require(0 < self.top_p <= 1, f"llm.top_p must be in (0, 1], got {self.top_p}")


@dataclass
class OpenAIConfig(LanguageModelConfig):
    """Any OpenAI-compatible server: vllm serve, Ollama, python -m llama_cpp.server, llama-server, OpenAI."""

    name: str = "openai"
    # Typed Any: structured configs allow no union of a string and a list. A tuple once validated.
    base_url: Any = option(["http://localhost:8000/v1"], "one URL, or a list of replicas: [http://a:8000/v1,http://b:8000/v1]")
    model: str = option("Qwen/Qwen2.5-Coder-7B-Instruct", "the model name the server knows")
    api_key_env: str = option("OPENAI_API_KEY", "name of the environment variable holding the key")
    use_n: bool = option(True, "ask for batch_size choices in one request; a server that returns fewer is asked one per request")
    max_concurrency: int = option(
        1, "requests in flight per server, the rest wait here: a llama.cpp server answers one at a time unless started "
        "with more slots (llama-server --parallel N, OLLAMA_NUM_PARALLEL); vLLM takes 16 or more",
    )
    timeout_s: float = option(120.0, "per request, from when it is sent")
    max_retries: int = option(5, "retries of a failed request before it is dropped")
    backoff_s: float = option(1.0, "first retry delay; doubled on every retry, with full jitter")
    max_backoff_s: float = option(60.0, "longest retry delay; a failed server is skipped this long")
    max_consecutive_failures: int = option(10, "failed attempts in a row, all servers together, that stop the search")

    def __post_init__(self) -> None:
        super().__post_init__()
        urls = [self.base_url] if isinstance(self.base_url, str) else self.base_url
        _require(
            isinstance(urls, (list, tuple)) and all(isinstance(url, str) for url in urls),
            f"llm.base_url must be one URL or a list of URLs, got {self.base_url!r}",
        )
        _require(len(urls) >= 1, "llm.base_url needs at least one URL")
        for url in urls:
            _require(url.startswith(("http://", "https://")), f"llm.base_url: {url!r} is not an http(s) URL")
        self.base_url = tuple(urls)
        _at_least(self, "llm", max_concurrency=1, max_retries=0)
        _above(self, "llm", timeout_s=0)


@dataclass
class VLLMConfig(LanguageModelConfig):
    """In-process vLLM on local GPUs (pip install 'colmo[vllm]')."""

    name: str = "vllm"
    model: str = option("Qwen/Qwen2.5-Coder-7B-Instruct", "a Hugging Face model id or a local directory")
    quantization: Optional[str] = option(None, "e.g. awq, gptq, bitsandbytes")
    dtype: str = option("auto", "weights and activations: auto, half, bfloat16, float")
    tensor_parallel_size: int = option(1, "GPUs each layer is split over")
    pipeline_parallel_size: int = option(1, "GPUs the layers are spread over")
    gpu_memory_utilization: float = option(0.9, "share of each GPU's memory vLLM may take")
    max_model_len: Optional[int] = option(None, "context length; null: the model's")
    seed: int = option(0, "the engine's seed (each request gets its own from the run's seed)")

    def __post_init__(self) -> None:
        super().__post_init__()
        _require(0 < self.gpu_memory_utilization <= 1, "llm.gpu_memory_utilization must be in (0, 1]")
        _at_least(self, "llm", tensor_parallel_size=1, pipeline_parallel_size=1)


@dataclass
class LlamaCppConfig(LanguageModelConfig):
    """In-process llama.cpp on the CPU (pip install 'colmo[llamacpp]'): a GGUF model loaded once per run."""

    name: str = "llamacpp"
    # Measured with Qwen2.5-Coder 0.5B/1.5B (README, "Program generators"): continuations were
    # valid programs more often than chat answers, copied the shown program less, at half the tokens.
    prompt_format: str = option("completion", "completion: the prompt text for the model to continue; chat: its messages through the chat template")
    model_path: Optional[str] = option(None, "a local GGUF file")
    repo_id: Optional[str] = option(
        None, "instead of model_path: a Hugging Face repository that llama-cpp-python downloads from and caches, "
        "e.g. Qwen/Qwen2.5-Coder-1.5B-Instruct-GGUF",
    )
    filename: Optional[str] = option(None, "the GGUF file in repo_id, e.g. qwen2.5-coder-1.5b-instruct-q4_k_m.gguf")
    max_tokens: int = option(512, "most tokens per answer")
    n_ctx: int = option(4096, "context length in tokens: prompt and answer")
    n_threads: int = option(
        1, "threads for the model; the evaluation workers use the other cores (on 2 busy cores 1 thread generated faster than 2)",
    )
    n_gpu_layers: int = option(0, "layers offloaded to a GPU, with a CUDA or Metal build of llama-cpp-python")

    def __post_init__(self) -> None:
        super().__post_init__()
        from_hub = self.repo_id is not None or self.filename is not None
        _require(
            (self.model_path is not None) != from_hub,
            "llm=llamacpp needs llm.model_path=<file.gguf>, or llm.repo_id and llm.filename (not both)",
        )
        if from_hub:
            _require(self.repo_id is not None and self.filename is not None, "llm.repo_id and llm.filename go together")
        else:
            _require(os.path.isfile(os.path.expanduser(self.model_path)), f"llm.model_path: no such file: {self.model_path}")
        _at_least(self, "llm", n_ctx=256, n_threads=1)


@dataclass
class HeldoutConfig:
    """Held-out evaluation: fresh episodes, their seeds disjoint from the training ones."""

    episodes: int = option(100, "held-out episodes per score")
    top: int = option(3, "the best programs of a search that get a held-out score at its end")
    render: bool = option(True, "at the end of a search, a video and a plot of the best policy on a held-out episode")
    simplify: bool = option(True, "at the end of a search, the best policy simplified (simplified_policy.py; options: simplify.*)")

    def __post_init__(self) -> None:
        _at_least(self, "evaluation", episodes=1, top=1)


@dataclass
class SimplifyConfig:
    """The simplifier (`colmo.simplify`): what a deletion may cost, and how far it goes."""

    tolerance: float = option(0.01, "share of the original training score a simplified program may lose (its held-out gap may widen as much)")
    max_rounds: int = option(200, "at most this many deletions")
    batch_size: Optional[int] = option(None, "candidates scored per executor call, largest deletion first; null: 4 per worker")

    def __post_init__(self) -> None:
        _require(0 <= self.tolerance < 1, f"simplify.tolerance must be in [0, 1), got {self.tolerance}")
        _at_least(self, "simplify", max_rounds=0)
        _require(self.batch_size is None or self.batch_size >= 1, f"simplify.batch_size must be >= 1 or null, got {self.batch_size}")


@dataclass
class SearchLoopConfig:
    """The search loop's limits and display."""

    max_samples: int = option(
        1000, "stop after this many model calls (generator requests' answers), duplicates, their regenerations and failures included",
    )
    duplicate_retries: int = option(
        2, "a sample whose program was already evaluated is generated again, from another selection of the database "
        "and with a fresh seed, up to this many times (each a model call) before it is recorded as a duplicate",
    )
    # One hour by default: 1000 quadruped samples at one evaluation a second would take a day and
    # more, and a user should not have to know that to get a run that ends on its own.
    max_seconds: float = option(
        3600.0, "wall-clock limit of the whole run from the process's start, held-out scores, simplification and video included; 0: none",
    )
    stop_at_score: Optional[float] = option(None, "stop once the best training score reaches this")
    queue_size: int = option(2, "batches in flight: generation overlaps evaluation")
    progress: bool = option(True, "live progress display on a terminal, a plain line every progress_every_s otherwise")
    progress_every_s: float = option(30.0, "seconds between plain progress lines when stderr is not a terminal")

    def __post_init__(self) -> None:
        _at_least(self, "search", max_samples=1, queue_size=1, duplicate_retries=0)
        _require(self.max_seconds >= 0, f"search.max_seconds must be >= 0 (0 = no limit), got {self.max_seconds}")
        _above(self, "search", progress_every_s=0)


@dataclass
class TrackerConfig:
    """Run tracking: `none` keeps only the run directory."""

    name: str = option("none", "mlflow or none")

    def __post_init__(self) -> None:
        _require(self.name in ("mlflow", "none"), f"tracker.name must be mlflow or none, got {self.name!r}")
        _require(self.name != "mlflow" or isinstance(self, MlflowConfig), "tracker.name=mlflow needs the mlflow options: use tracker=mlflow")


@dataclass
class MlflowConfig(TrackerConfig):
    """MLflow tracking: one run per search, a parent run per sweep."""

    name: str = "mlflow"
    tracking_uri: Optional[str] = option(None, "null: sqlite:///mlruns.db in the launch directory; or http://host:5000, postgresql://...")
    experiment: Optional[str] = option(None, "null: the task name")
    run_name: Optional[str] = option(None, "null: <task>-<gfo>-<llm>-s<seed>-<HHMMSS>, and -j<job number> in a sweep")


@dataclass
class SearchConfig:
    """`colmo`: the program search."""

    task: TaskConfig = MISSING
    gfo: GFOConfig = MISSING
    llm: GeneratorConfig = MISSING
    database: DatabaseConfig = MISSING
    executor: ExecutorConfig = MISSING
    tracker: TrackerConfig = MISSING
    search: SearchLoopConfig = field(default_factory=SearchLoopConfig)
    evaluation: HeldoutConfig = field(default_factory=HeldoutConfig)
    simplify: SimplifyConfig = field(default_factory=SimplifyConfig)
    seed: int = option(0, "episode seeds, prompts and optimizers derive from it")
    resume: Optional[str] = option(None, "an earlier run's directory to continue")

    def __post_init__(self) -> None:
        _require(self.seed >= 0, f"seed must be >= 0, got {self.seed}")


@dataclass
class OptimizeConfig:
    """`colmo-optimize`: tune the constants of one policy file."""

    task: TaskConfig = MISSING
    gfo: GFOConfig = MISSING
    executor: ExecutorConfig = MISSING
    tracker: TrackerConfig = MISSING
    policy_file: str = option(MISSING, "a .py file with `def policy(obs)`, or a raw language-model answer")
    evaluation: HeldoutConfig = field(default_factory=HeldoutConfig)
    seed: int = option(0, "episode seeds and the optimizer's randomness derive from it")

    def __post_init__(self) -> None:
        _require(self.seed >= 0, f"seed must be >= 0, got {self.seed}")
