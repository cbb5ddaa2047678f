"""Generators: the mutate baseline's children, the OpenAI client against a real local HTTP server
speaking the chat-completions protocol, and the vLLM wiring through a fake `vllm` module."""

from __future__ import annotations

import ast
import logging
import re
import socket
import sys
import time
import types

import numpy as np
import pytest

from colmo.generate import mutate
from colmo.config import ConfigError, GeneratorConfig, MutateConfig, OpenAIConfig, VLLMConfig
from colmo.generate import GENERATORS, Generation, GeneratorError, MutateGenerator, make_generator
from colmo.program import parametrize
from colmo.prompt import Prompt
from colmo.sandbox import EvalRequest, ProgramProbe, WorkerPool
from colmo.spec import load_spec

from conftest import EXAMPLES, FakeOpenAIServer

STARTER = load_spec("pendulum.py").starter_code
PAPER_PENDULUM = (EXAMPLES / "paper_pendulum.py").read_text()
MESSAGES = [{"role": "system", "content": "You write policies."}, {"role": "user", "content": "Improve policy_v1."}]


def make_prompt(*programs: str, text: str = "") -> Prompt:
    return Prompt(text=text, messages=MESSAGES, programs=list(programs), island=0, parent_keys=[])


@pytest.fixture(scope="module")
def pendulum_probe():
    probe = ProgramProbe(load_spec("pendulum.py"), {}, seed=0, timeout_s=3, memory_mb=1024)
    yield probe
    probe.close()


@pytest.fixture(scope="module")
def cheetah_probe():
    probe = ProgramProbe(load_spec("cheetah.py"), {}, seed=0, timeout_s=3, memory_mb=1024)
    yield probe
    probe.close()


def run_on_zeros(code: str, obs_size: int) -> np.ndarray:
    namespace: dict = {}
    exec(code, namespace)  # our own generator's output, in a test
    with np.errstate(all="ignore"):
        return np.asarray(namespace["policy"](np.zeros(obs_size)), dtype=float)


def indices_read(code: str) -> set[int]:
    return {int(i) for i in re.findall(r"obs\[(\d+)\]", code)}


# ------------------------------------------------------------------------------------- mutate

def test_mutate_children_parse_run_and_differ_from_their_parents(pendulum_probe):
    prompt = make_prompt(STARTER, PAPER_PENDULUM)
    children = MutateGenerator(MutateConfig(), seed=0, probe=pendulum_probe).generate(prompt, 200)

    assert len(children) == 200 and all(c.generator == "mutate" for c in children)
    for child in children:
        fn = next(n for n in ast.parse(child.text).body if isinstance(n, ast.FunctionDef) and n.name == "policy")
        assert [a.arg for a in fn.args.args] == ["obs"]
        assert any(isinstance(n, ast.Return) and n.value is not None for n in ast.walk(fn))
    # Whole episodes in the sandbox, on an episode seed the probe never saw.
    spec = load_spec("pendulum.py")
    with WorkerPool(1, timeout_s=30, memory_mb=1024) as pool:
        requests = [
            EvalRequest(str(spec.path), (), (12345,), p.skeleton, p.values, spec.allowed_imports)
            for p in map(parametrize, (c.text for c in children))
        ]
        failures = [e.failure for e in pool.evaluate(requests) if e.failure]
    assert len(failures) <= 2, failures  # measured: 0 of 200

    keys = [parametrize(c.text).key for c in children]
    parents = {parametrize(p).key for p in prompt.programs}
    assert len(set(keys)) == 200  # no two children share a structure ...
    assert not set(keys) & parents  # ... nor one with a parent


def test_without_a_probe_children_are_only_parsed():
    children = MutateGenerator(MutateConfig(), seed=0).generate(make_prompt(STARTER, PAPER_PENDULUM), 50)
    assert len({parametrize(c.text).key for c in children}) == 50


def test_mutate_is_deterministic_given_the_seed():
    prompt = make_prompt(STARTER, PAPER_PENDULUM)
    first = [g.text for g in MutateGenerator(MutateConfig(), seed=3).generate(prompt, 10)]
    again = [g.text for g in MutateGenerator(MutateConfig(), seed=3).generate(prompt, 10)]
    other = [g.text for g in MutateGenerator(MutateConfig(), seed=4).generate(prompt, 10)]
    assert first == again
    assert first != other


def test_crossover_takes_material_from_both_parents():
    energy = "import numpy as np\n\ndef policy(obs):\n    energy = obs[2] ** 2 - 0.3 * obs[0]\n    return -0.5 * np.tanh(energy)\n"
    generator = MutateGenerator(MutateConfig(crossover_rate=1.0, max_mutations=1), seed=0)
    children = [g.text for g in generator.generate(make_prompt(energy, PAPER_PENDULUM), 50)]
    both = [c for c in children if "energy" in c and ("x1" in c or "np.pi" in c)]
    assert len(both) >= 15, f"only {len(both)} of 50 crossover children mix both parents"


def test_new_terms_read_observation_entries_below_the_stated_size():
    program = "import numpy as np\n\ndef policy(obs):\n    return 0.5 * obs[0]\n"
    stated = MutateGenerator(MutateConfig(), seed=0).generate(make_prompt(program, text="Observation (size 5): ..."), 50)
    read = set().union(*(indices_read(g.text) for g in stated))
    assert read == {0, 1, 2, 3, 4}

    unstated = "import numpy as np\n\ndef policy(obs):\n    return 0.5 * obs[0] - obs[2]\n"
    children = MutateGenerator(MutateConfig(), seed=0).generate(make_prompt(unstated), 50)
    assert set().union(*(indices_read(g.text) for g in children)) == {0, 2}


def test_children_keep_the_action_shape_of_array_policies(cheetah_probe):
    cheetah = (EXAMPLES / "paper_cheetah.py").read_text()
    children = MutateGenerator(MutateConfig(), seed=0, probe=cheetah_probe).generate(make_prompt(cheetah), 30)
    assert all(run_on_zeros(g.text, 17).shape == (6,) for g in children)
    assert len({parametrize(g.text).key for g in children}) == 30


def test_children_of_a_program_without_numpy_import_it(pendulum_probe):
    children = MutateGenerator(MutateConfig(), seed=0, probe=pendulum_probe).generate(make_prompt("def policy(obs):\n    return 0.0\n", text="obs size is 3"), 20)
    assert any("np." in g.text for g in children)
    assert all(run_on_zeros(g.text, 3).shape == () for g in children)


def test_without_a_new_structure_a_child_is_its_parent_with_perturbed_constants(monkeypatch):
    monkeypatch.setattr(mutate, "_ATTEMPTS", 0)
    [child] = MutateGenerator(MutateConfig(), seed=0).generate(make_prompt(PAPER_PENDULUM), 1)
    parent = parametrize(PAPER_PENDULUM)
    program = parametrize(child.text)
    assert program.key == parent.key
    assert program.values != parent.values


def test_mutate_skips_programs_it_cannot_parse():
    children = MutateGenerator(MutateConfig(), seed=0).generate(make_prompt("def policy(obs) return", PAPER_PENDULUM), 5)
    assert len(children) == 5
    with pytest.raises(GeneratorError, match="none of the prompt's programs"):
        MutateGenerator(MutateConfig(), seed=0).generate(make_prompt("def policy(obs) return", "x = 1"), 1)


def test_the_probe_passes_only_programs_that_run_on_the_task(pendulum_probe):
    start = time.perf_counter()
    assert not pendulum_probe("def policy(obs):\n    while True:\n        pass\n")  # its worker is replaced
    assert time.perf_counter() - start < 10
    assert not pendulum_probe("def policy(obs):\n    return obs[:2]\n")  # two actions for one actuator
    assert not pendulum_probe("def policy(obs):\n    return float('nan')\n")
    assert not pendulum_probe("import os\ndef policy(obs):\n    return 0.0\n")
    assert not pendulum_probe("def policy(obs) return")
    assert pendulum_probe(PAPER_PENDULUM)


# ---------------------------------------------------------------------- openai: a real server

@pytest.fixture
def server():
    fake = FakeOpenAIServer()
    yield fake
    fake.close()


@pytest.fixture
def dead_url():
    """A bound port that does not listen: connections to it are refused."""
    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    yield f"http://127.0.0.1:{sock.getsockname()[1]}/v1"
    sock.close()


def openai_config(*urls: str, **overrides) -> OpenAIConfig:
    settings = dict(
        base_url=list(urls), model="test-model", batch_size=4, api_key_env="COLMO_TEST_OPENAI_KEY",
        temperature=0.7, top_p=0.9, max_tokens=256, timeout_s=5.0, max_retries=3, backoff_s=0.01,
        max_backoff_s=30.0, max_consecutive_failures=5,
    )
    return OpenAIConfig(**{**settings, **overrides})


def logged_delays(caplog) -> list[float]:
    return [float(m) for r in caplog.records for m in re.findall(r"retry \d+/\d+ in ([\d.]+)s", r.getMessage())]


def test_openai_asks_for_the_batch_in_one_request_when_n_is_honoured(server):
    generator = make_generator(openai_config(server.url), seed=0)
    generations = generator.generate(make_prompt(STARTER), 4)
    generator.close()

    [request] = server.requests
    assert request["path"] == "/v1/chat/completions"
    body = request["body"]
    assert body["messages"] == MESSAGES and body["model"] == "test-model" and body["n"] == 4
    assert (body["temperature"], body["top_p"], body["max_tokens"]) == (0.7, 0.9, 256)
    assert isinstance(body["seed"], int)
    assert [g.text.splitlines()[2] for g in generations] == [f"    return {i}.0 * obs[0]" for i in range(4)]
    assert {g.generator for g in generations} == {f"openai:test-model@{server.url}"}
    assert sum(g.prompt_tokens for g in generations) == 10
    assert [g.completion_tokens for g in generations] == [5, 5, 5, 5]


def test_openai_falls_back_to_parallel_single_requests_when_n_is_ignored():
    fake = FakeOpenAIServer(honour_n=False, delay=0.3)
    try:
        generator = make_generator(openai_config(fake.url), seed=0)
        assert len(generator.generate(make_prompt(STARTER), 4)) == 4
        assert [r["body"].get("n") for r in fake.requests] == [4, None, None, None]
        assert fake.max_active >= 2  # the three missing completions were asked for at once

        assert len(generator.generate(make_prompt(STARTER), 4)) == 4  # remembered: no n any more
        assert [r["body"].get("n") for r in fake.requests[4:]] == [None] * 4
        assert len({r["body"]["seed"] for r in fake.requests}) == 8
        generator.close()
    finally:
        fake.close()


@pytest.mark.parametrize("failure, reason", [
    ("500", "500"), ("429", "429"), ("garbage", "JSONDecodeError"),
    ("html", "no completion text"), ("empty", "no completion text"),
])
def test_openai_retries_failed_and_unusable_answers(server, caplog, failure, reason):
    server.script = [failure]
    generator = make_generator(openai_config(server.url), seed=0)
    with caplog.at_level(logging.WARNING, logger="colmo.generate"):
        generations = generator.generate(make_prompt(STARTER), 1)
    generator.close()

    assert len(generations) == 1 and "def policy" in generations[0].text
    assert len(server.requests) == 2
    [message] = [r.getMessage() for r in caplog.records]
    assert "retry 1/3" in message and reason in message


def test_openai_backs_off_exponentially_with_full_jitter(server, caplog):
    server.script = ["500", "500", "500"]
    generator = make_generator(openai_config(server.url, backoff_s=0.02), seed=0)
    with caplog.at_level(logging.WARNING, logger="colmo.generate"):
        assert len(generator.generate(make_prompt(STARTER), 1)) == 1
    generator.close()
    delays = logged_delays(caplog)
    assert len(delays) == 3 and len(server.requests) == 4
    assert all(0 <= delay <= 0.02 * 2**attempt for attempt, delay in enumerate(delays))


def test_openai_drops_a_request_that_runs_out_of_retries(server, caplog):
    server.script = ["500", "500"]
    generator = make_generator(openai_config(server.url, max_retries=1, max_consecutive_failures=10), seed=0)
    with caplog.at_level(logging.WARNING, logger="colmo.generate"):
        assert generator.generate(make_prompt(STARTER), 1) == []
        assert len(generator.generate(make_prompt(STARTER), 1)) == 1
    generator.close()
    assert any("dropping a request after 2 attempts" in r.getMessage() for r in caplog.records)


def test_openai_gives_up_after_consecutive_failures(dead_url):
    generator = make_generator(openai_config(dead_url, max_retries=10, max_consecutive_failures=3), seed=0)
    with pytest.raises(GeneratorError) as raised:
        generator.generate(make_prompt(STARTER), 4)
    generator.close()
    message = str(raised.value)
    assert message.startswith("no OpenAI-compatible server answered after 3 attempts: APIConnectionError")
    assert "\n" not in message


def test_openai_raises_at_once_when_the_server_refuses_the_request(server):
    server.script = ["400"]
    generator = make_generator(openai_config(server.url), seed=0)
    with pytest.raises(GeneratorError, match=r"refused the request: HTTP 400"):
        generator.generate(make_prompt(STARTER), 1)
    generator.close()
    assert len(server.requests) == 1


def test_openai_sends_requests_to_the_live_server(server, dead_url, caplog):
    generator = make_generator(openai_config(dead_url, server.url, use_n=False), seed=0)
    with caplog.at_level(logging.WARNING, logger="colmo.generate"):
        generations = generator.generate(make_prompt(STARTER), 4) + generator.generate(make_prompt(STARTER), 4)
    generator.close()
    assert len(generations) == 8
    assert {g.generator for g in generations} == {f"openai:test-model@{server.url}"}
    # Round robin sends each of the first parallel requests to one server; once the dead one
    # has failed it is skipped for max_backoff_s.
    assert 1 <= sum(dead_url in r.getMessage() for r in caplog.records) <= 2
    assert len(server.requests) == 8


def test_openai_reads_the_api_key_from_the_named_variable(server, monkeypatch):
    monkeypatch.setenv("COLMO_TEST_OPENAI_KEY", "sk-colmo-test")
    make_generator(openai_config(server.url), seed=0).generate(make_prompt(STARTER), 1)
    monkeypatch.delenv("COLMO_TEST_OPENAI_KEY")
    make_generator(openai_config(server.url), seed=0).generate(make_prompt(STARTER), 1)
    assert [r["authorization"] for r in server.requests] == ["Bearer sk-colmo-test", "Bearer EMPTY"]


# ------------------------------------------------------------------- vllm: a fake vllm module

class FakeLLM:
    instances: list[FakeLLM] = []
    fail_with: Exception | None = None

    def __init__(self, **kwargs):
        if FakeLLM.fail_with:
            raise FakeLLM.fail_with
        self.kwargs = kwargs
        self.calls: list[tuple] = []
        FakeLLM.instances.append(self)

    def chat(self, messages, sampling_params=None, use_tqdm=True):
        self.calls.append((messages, sampling_params, use_tqdm))
        outputs = [
            types.SimpleNamespace(index=i, text=f"def policy(obs):\n    return {i}.0", token_ids=list(range(3 + i)))
            for i in range(sampling_params.n)
        ]
        return [types.SimpleNamespace(prompt_token_ids=list(range(42)), outputs=outputs, finished=True)]


class FakeSamplingParams:
    def __init__(self, **kwargs):
        self.__dict__.update(kwargs)


@pytest.fixture
def fake_vllm(monkeypatch):
    module = types.ModuleType("vllm")
    module.LLM = FakeLLM
    module.SamplingParams = FakeSamplingParams
    monkeypatch.setitem(sys.modules, "vllm", module)
    FakeLLM.instances, FakeLLM.fail_with = [], None
    return module


def test_vllm_builds_the_engine_from_the_config_and_samples_the_batch_in_one_chat_request(fake_vllm):
    cfg = VLLMConfig(
        model="tiny/instruct", batch_size=3, temperature=0.8, top_p=0.95, max_tokens=300, quantization="awq",
        dtype="half", tensor_parallel_size=2, pipeline_parallel_size=2, gpu_memory_utilization=0.5,
        max_model_len=4096, seed=7,
    )
    generator = make_generator(cfg, seed=0)
    [llm] = FakeLLM.instances
    assert llm.kwargs == dict(
        model="tiny/instruct", quantization="awq", dtype="half", tensor_parallel_size=2, pipeline_parallel_size=2,
        gpu_memory_utilization=0.5, max_model_len=4096, seed=7,
    )

    generations = generator.generate(make_prompt(STARTER), 3)
    generator.generate(make_prompt(STARTER), 3)
    generator.close()
    (messages, params, use_tqdm), (_, params_again, _) = llm.calls
    assert messages == MESSAGES and use_tqdm is False
    assert (params.n, params.temperature, params.top_p, params.max_tokens) == (3, 0.8, 0.95, 300)
    assert params.seed != params_again.seed  # the same prompt twice is not answered the same
    assert [g.text for g in generations] == [f"def policy(obs):\n    return {i}.0" for i in range(3)]
    assert {g.generator for g in generations} == {"vllm:tiny/instruct"}
    assert [g.prompt_tokens for g in generations] == [42, 0, 0]
    assert [g.completion_tokens for g in generations] == [3, 4, 5]


def test_vllm_missing_or_failing_is_a_generator_error(fake_vllm, monkeypatch):
    FakeLLM.fail_with = RuntimeError("CUDA out of memory\nlong traceback")
    with pytest.raises(GeneratorError, match=r"^vLLM could not load .*: RuntimeError: CUDA out of memory$"):
        make_generator(VLLMConfig(), seed=0)
    monkeypatch.setitem(sys.modules, "vllm", None)  # what an uninstalled package looks like to import
    with pytest.raises(GeneratorError, match=re.escape("llm=vllm needs vLLM: pip install 'colmo[vllm]'")):
        make_generator(VLLMConfig(), seed=0)


# ------------------------------------------------------------------------------------ registry

def test_registry_names_every_generator():
    assert set(GENERATORS) == {"mutate", "openai", "vllm"}
    generator = make_generator(MutateConfig(batch_size=2), seed=0)
    assert isinstance(generator, MutateGenerator)
    assert all(isinstance(g, Generation) for g in generator.generate(make_prompt(STARTER), 2))
    with pytest.raises(ConfigError, match="llm.name must be one of mutate, openai, vllm"):
        make_generator(GeneratorConfig(name="gpt"), seed=0)
