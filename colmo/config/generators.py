"""The schemas of config group `llm`, the program generators: the embedded genetic operators
(`llm=mutate`) and the language models (`llm=openai`, `llm=vllm`, `llm=llamacpp`)."""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any, Optional

from omegaconf import MISSING

from colmo.config.fields import above, at_least, check_component, component, option, require

PROMPT_FORMATS = ("chat", "completion")


@dataclass
class GeneratorConfig:
    """Fields every program generator (config group `llm`) has."""

    name: str = component(MISSING, "the generator the llm option runs", "colmo.generate:GENERATORS")
    batch_size: int = option(4, "programs generated from each prompt")

    def __post_init__(self) -> None:
        check_component(self, "name")
        at_least(self, "llm", batch_size=1)


@dataclass
class MutateConfig(GeneratorConfig):
    """The embedded generator: genetic operators on the program AST, no model, no network."""

    name: str = "mutate"
    crossover_rate: float = option(0.3, "chance a child starts as a crossover of the two prompt programs")
    max_mutations: int = option(3, "up to this many AST mutations per child")
    constant_sigma: float = option(0.5, "relative perturbation of constants")
    attempts: int = option(40, "redraws for a child with a new working structure; then a parent with perturbed constants")
    joint_terms: bool = option(
        False, "where the action is a vector, also insert joint terms `c * np.eye(K)[j] * f`: one actuator's gain, one constant "
        "(an actuator term has K); off by default, as it was not found to pay (docs/mixed-generation.md)",
    )


@dataclass
class LanguageModelConfig(GeneratorConfig):
    """Sampling fields every language-model generator has."""

    prompt_format: str = option(
        "chat", "chat: the prompt's messages through the model's chat template; completion: the prompt text, "
        "ending with the header of the function to write, for the model to continue (base and code models)",
    )
    follow_up: bool = option(
        True, "chat form: an answer that brings no new program (a copy, a name never defined) is answered in the same "
        "conversation, the model told what was wrong; false: asked again from a new selection of the database",
    )
    temperature: float = option(1.0, "sampling temperature")
    retry_temperature_step: float = option(
        0.25, "each regeneration of a duplicate answer (search.duplicate_retries) samples this much hotter ...",
    )
    max_temperature: float = option(1.5, "... up to this temperature (never below llm.temperature)")
    top_p: float = option(1.0, "nucleus sampling: the smallest set of tokens with this much probability")
    max_tokens: int = option(1024, "most tokens per answer")

    def __post_init__(self) -> None:
        super().__post_init__()
        require(self.prompt_format in PROMPT_FORMATS, f"llm.prompt_format must be chat or completion, got {self.prompt_format!r}")
        at_least(self, "llm", temperature=0, retry_temperature_step=0, max_tokens=1)
        require(0 < self.top_p <= 1, f"llm.top_p must be in (0, 1], got {self.top_p}")

    def temperature_for(self, retry: int) -> float:
        """The sampling temperature of an answer's `retry`-th regeneration (0: its first answer):
        a model that copied a shown program at one temperature is asked again hotter, bounded."""
        return max(self.temperature, min(self.temperature + retry * self.retry_temperature_step, self.max_temperature))


@dataclass
class OpenAIConfig(LanguageModelConfig):
    """Any OpenAI-compatible server: vllm serve, Ollama, python -m llama_cpp.server, llama-server, OpenAI."""

    name: str = "openai"
    # Typed Any: structured configs allow no union of a string and a list. A tuple once validated.
    base_url: Any = option(["http://localhost:8000/v1"], "one URL, or a list of replicas: [http://a:8000/v1,http://b:8000/v1]")
    model: str = option("Qwen/Qwen2.5-Coder-7B-Instruct", "the model name the server knows")
    api_key_env: str = option("OPENAI_API_KEY", "name of the environment variable holding the key")
    use_n: bool = option(True, "ask for batch_size choices in one request; a server that returns fewer is asked one per request")
    stream: bool = option(
        True, "answers streamed, so the display counts their tokens as they come; a server that refuses a streamed request "
        "(HTTP 400 or 422 naming it) is asked for whole answers from then on; false: whole answers",
    )
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
        require(
            isinstance(urls, (list, tuple)) and all(isinstance(url, str) for url in urls),
            f"llm.base_url must be one URL or a list of URLs, got {self.base_url!r}",
        )
        require(len(urls) >= 1, "llm.base_url needs at least one URL")
        for url in urls:
            require(url.startswith(("http://", "https://")), f"llm.base_url: {url!r} is not an http(s) URL")
        self.base_url = tuple(urls)
        at_least(self, "llm", max_concurrency=1, max_retries=0)
        above(self, "llm", timeout_s=0)


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
        require(0 < self.gpu_memory_utilization <= 1, "llm.gpu_memory_utilization must be in (0, 1]")
        at_least(self, "llm", tensor_parallel_size=1, pipeline_parallel_size=1)


@dataclass
class LlamaCppConfig(LanguageModelConfig):
    """In-process llama.cpp on the CPU (pip install 'colmo[llamacpp]'): a GGUF model loaded once per run."""

    name: str = "llamacpp"
    # Chat, as for the servers: in completion form the 1.5B model in process mostly repeats the
    # shown program (docs/llm-duplicates.md: programs evaluated per model call, both forms).
    prompt_format: str = option("chat", "chat: the prompt's messages through the GGUF's chat template; completion: the prompt text for the model to continue")
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
        require(
            (self.model_path is not None) != from_hub,
            "llm=llamacpp needs llm.model_path=<file.gguf>, or llm.repo_id and llm.filename (not both)",
        )
        if from_hub:
            require(self.repo_id is not None and self.filename is not None, "llm.repo_id and llm.filename go together")
        else:
            require(os.path.isfile(os.path.expanduser(self.model_path)), f"llm.model_path: no such file: {self.model_path}")
        at_least(self, "llm", n_ctx=256, n_threads=1)

