"""`llm=vllm`: in-process batched generation on local GPUs.

vllm runs `vllm.LLM` in this process (`pip install 'colmo[vllm]'`) and samples the batch as the
`n` outputs of one request: the chat messages through the model's chat template
(`prompt_format=chat`), or the prompt text continued up to the next top-level definition
(`prompt_format=completion`).
"""

from __future__ import annotations

import time
from typing import Optional

from colmo.config import VLLMConfig
from colmo.generate.base import GENERATORS, Generation, GeneratorError, LanguageModelGenerator, Library, Probe, batch_of, describe_error, logger
from colmo.prompt import COMPLETION_STOP, Prompt


@GENERATORS.register("vllm")
class VLLMGenerator(LanguageModelGenerator):
    """`vllm.LLM` in this process; the batch is the `n` outputs of one request."""

    options = VLLMConfig
    library = Library("vllm", "vLLM", "colmo[vllm]")

    def __init__(self, cfg: VLLMConfig, seed: int, probe: Optional[Probe] = None):
        super().__init__(cfg, seed, probe)
        vllm = self.library.load(f"llm={cfg.name}", GeneratorError)
        self.name = f"vllm:{cfg.model}"
        self._sampling_params = vllm.SamplingParams
        try:
            self._llm = vllm.LLM(
                model=cfg.model, quantization=cfg.quantization, dtype=cfg.dtype,
                tensor_parallel_size=cfg.tensor_parallel_size, pipeline_parallel_size=cfg.pipeline_parallel_size,
                gpu_memory_utilization=cfg.gpu_memory_utilization, max_model_len=cfg.max_model_len, seed=cfg.seed,
            )
        except Exception as error:  # CUDA, download, memory and argument errors all end the run
            raise GeneratorError(f"vLLM could not load {cfg.model}: {describe_error(error)}") from error

    def generate(self, prompt: Prompt, n: int) -> list[Generation]:
        cfg = self.cfg
        params = self._sampling_params(
            # the engine's seed is the config's; each request gets its own
            n=n, temperature=cfg.temperature_for(prompt.retry), top_p=cfg.top_p, max_tokens=cfg.max_tokens, seed=self.request_seed(),
            **({} if self.chat else {"stop": list(COMPLETION_STOP)}),
        )
        start = time.perf_counter()
        if self.chat:
            [output] = self._llm.chat(prompt.messages, sampling_params=params, use_tqdm=False)
        else:
            [output] = self._llm.generate([prompt.text], sampling_params=params, use_tqdm=False)
        seconds = time.perf_counter() - start
        prompt_tokens = len(output.prompt_token_ids or ())
        completion_tokens = [len(completion.token_ids) for completion in output.outputs]
        logger.info(
            "vllm: %d completions, %d prompt + %d completion tokens, %.1fs",
            len(output.outputs), prompt_tokens, sum(completion_tokens), seconds,
        )
        texts = [completion.text for completion in output.outputs]
        return batch_of(texts, self.name, prompt_tokens, completion_tokens, seconds, self.form, self.context(prompt))

    def close(self) -> None:
        self._llm = None  # the engine frees its GPU memory when collected

