"""`llm=llamacpp`: in-process generation with llama.cpp (`pip install 'colmo[llamacpp]'`).

The GGUF model is loaded once, when the generator is made, from `llm.model_path` or from the
Hugging Face Hub (`llm.repo_id` + `llm.filename`, downloaded and cached by llama-cpp-python).
Completions are sampled one after another, each with its own seed drawn from the run's seed;
llama-cpp-python keeps the key-value cache of the longest prefix two consecutive prompts share,
so the prompt of a batch is read once. The chat form goes through the chat template stored in
the GGUF; the completion form continues the prompt text and stops at the next top-level
definition. llama.cpp releases the GIL while it decodes, so the search keeps feeding the
evaluation workers meanwhile. Sampling uses llama.cpp's defaults beyond temperature and top_p
(top_k 40, min_p 0.05), as `python -m llama_cpp.server` does. `cancel()` ends the answer being
written at its next token (only the end-of-text token is left to sample) and the batch with it.
"""

from __future__ import annotations

import threading
import time
from pathlib import Path
from typing import Any, Optional

import numpy as np

from colmo.config import LlamaCppConfig
from colmo.generate.base import GENERATORS, Generation, GeneratorError, LanguageModelGenerator, Library, Probe, describe_error, logger
from colmo.prompt import COMPLETION_STOP, Prompt


def built_for(llama_cpp: Any) -> str:
    """The instruction sets this llama.cpp build uses (`AVX2 FMA ...`, from its system info), or
    "unknown". Where two machines' builds differ, the same seed can give other answers: their
    arithmetic rounds differently."""
    system_info = getattr(llama_cpp, "llama_print_system_info", None)  # absent from older or stand-in modules
    if system_info is None:
        return "unknown"
    info = system_info()
    info = info.decode(errors="replace") if isinstance(info, bytes) else str(info)
    # "CPU : SSE3 = 1 | AVX = 1 | AVX2 = 0 | ...": the names set to 1, the "CPU :" prefix dropped.
    items = (item.partition("=") for item in info.split("|"))
    features = [name.split(":")[-1].strip() for name, _, value in items if value.strip() == "1"]
    return " ".join(features) or "unknown"


@GENERATORS.register("llamacpp")
class LlamaCppGenerator(LanguageModelGenerator):
    """A `llama_cpp.Llama` in this process; the batch is `n` completions sampled in turn."""

    options = LlamaCppConfig
    library = Library("llama_cpp", "llama-cpp-python", "colmo[llamacpp]")

    def __init__(self, cfg: LlamaCppConfig, seed: int, probe: Optional[Probe] = None):
        super().__init__(cfg, seed, probe)
        llama_cpp = self.library.load(f"llm={cfg.name}", GeneratorError)
        options = dict(
            n_ctx=cfg.n_ctx, n_threads=cfg.n_threads, n_threads_batch=cfg.n_threads, n_gpu_layers=cfg.n_gpu_layers,
            verbose=False,
        )
        if cfg.model_path is not None:
            model_path = Path(cfg.model_path).expanduser()
            source, model = str(model_path), model_path.name
        else:
            source, model = f"{cfg.repo_id}/{cfg.filename}", f"{cfg.repo_id}/{cfg.filename}"
        self.name = f"llamacpp:{model}"
        self._cancelled = threading.Event()
        self._tokens: Optional[int] = None  # the call in flight's tokens so far; None between calls
        start = time.perf_counter()
        try:
            if cfg.model_path is not None:
                self._llm = llama_cpp.Llama(model_path=source, **options)
            else:
                self._llm = llama_cpp.Llama.from_pretrained(repo_id=cfg.repo_id, filename=cfg.filename, **options)
        except Exception as error:  # a missing or corrupt file, no network, an unknown architecture
            raise GeneratorError(f"llama.cpp could not load {source}: {describe_error(error)}") from error
        logger.info(
            "llamacpp: loaded %s in %.1fs (%d threads, n_ctx %d; llama.cpp built for %s)",
            source, time.perf_counter() - start, cfg.n_threads, cfg.n_ctx, built_for(llama_cpp),
        )
        self._end_of_text = self._llm.token_eos()
        self._until_cancelled = llama_cpp.LogitsProcessorList([self._end_if_cancelled])

    def generate(self, prompt: Prompt, n: int) -> list[Generation]:
        generations = []
        while len(generations) < n and not self._cancelled.is_set():
            generations.append(self._sample(prompt))
        return generations

    def cancel(self) -> None:
        self._cancelled.set()

    def tokens_so_far(self) -> Optional[int]:
        return self._tokens

    def _end_if_cancelled(self, input_ids: Any, scores: np.ndarray) -> np.ndarray:
        """A logits processor, called once per token generated: unchanged scores, or only the
        end-of-text token once cancelled; it counts the call's tokens (`tokens_so_far`)."""
        self._tokens = (self._tokens or 0) + 1
        if not self._cancelled.is_set():
            return scores
        ended = np.full_like(scores, -np.inf)
        ended[self._end_of_text] = 0.0
        return ended

    def _sample(self, prompt: Prompt) -> Generation:
        cfg = self.cfg
        sampling = dict(
            temperature=cfg.temperature_for(prompt.retry), top_p=cfg.top_p, max_tokens=cfg.max_tokens, seed=self.request_seed(),
            logits_processor=self._until_cancelled,
        )
        start, self._tokens = time.perf_counter(), 0
        try:
            if self.chat:
                response = self._llm.create_chat_completion(messages=prompt.messages, **sampling)
            else:
                response = self._llm.create_completion(prompt=prompt.text, stop=list(COMPLETION_STOP), **sampling)
        except ValueError as error:  # llama-cpp-python's only documented refusal: a prompt longer than n_ctx
            raise GeneratorError(f"llama.cpp refused the prompt ({describe_error(error)}); raise llm.n_ctx") from error
        except Exception as error:
            raise GeneratorError(f"llama.cpp failed: {describe_error(error)}") from error
        finally:
            self._tokens = None
        seconds = time.perf_counter() - start
        text = _text(response, self.chat)
        usage: dict[str, Any] = response.get("usage") or {}
        prompt_tokens, completion_tokens = usage.get("prompt_tokens", 0), usage.get("completion_tokens", 0)
        logger.info(
            "llamacpp: %d prompt + %d completion tokens, %.1fs (%.1f tokens/s)",
            prompt_tokens, completion_tokens, seconds, completion_tokens / seconds if seconds else 0.0,
        )
        return Generation(text, self.name, prompt_tokens, completion_tokens, seconds, form=self.form, context=self.context(prompt))

    def cores(self) -> int:
        return self.cfg.n_threads if self.cfg.n_gpu_layers == 0 else 0  # offloaded layers run on the GPU

    def close(self) -> None:
        llm, self._llm = self._llm, None
        if llm is not None:
            llm.close()  # frees the model and its context now, not whenever it is collected


def _text(response: dict[str, Any], chat: bool) -> str:
    choice = response["choices"][0]
    return (choice["message"].get("content") if chat else choice.get("text")) or ""
