"""Generators: the mutate baseline's children, the OpenAI client against a real local HTTP server
speaking the chat-completions and completions protocols, and the vLLM and llama.cpp wiring
through fake `vllm` and `llama_cpp` modules (tests/test_llm.py runs a real model)."""

from __future__ import annotations

import ast
import logging
import re
import socket
import sys
import threading
import time
import types

import numpy as np
import pytest
from conftest import EXAMPLES, FakeOpenAIServer, run_colmo, wait_for

from colmo.config import GeneratorConfig, LlamaCppConfig, MutateConfig, OpenAIConfig, VLLMConfig
from colmo.errors import ConfigError
from colmo.evaluation import EvalRequest, Evaluator
from colmo.executor import LocalExecutor
from colmo.extract import extract_policy
from colmo.generate import GENERATORS, Generation, GeneratorError, make_generator
from colmo.generate.mutate import MutateGenerator
from colmo.generate.probe import ProgramProbe
from colmo.program import parametrize
from colmo.prompt import COMPLETION_STOP, Prompt
from colmo.specs import load_spec

STARTER = load_spec("pendulum.py").starter_code
PAPER_PENDULUM = (EXAMPLES / "paper_pendulum.py").read_text()
MESSAGES = [{"role": "system", "content": "You write policies."}, {"role": "user", "content": "Improve policy_v1."}]


SHOWN_CODE = 'import numpy as np\n\n\ndef policy_v0(obs):\n    return 0.0'
PROMPT_TEXT = 'import numpy as np\n\n\ndef policy_v0(obs):\n    return 0.0\n\n\ndef policy_v1(obs):\n    """Improved version of policy_v0."""\n'


def make_prompt(*programs: str, text: str = "") -> Prompt:
    return Prompt(text=text, messages=MESSAGES, programs=list(programs), shown_code=SHOWN_CODE, island=0, parent_keys=[])


@pytest.fixture(scope="module")
def pendulum_probe():
    probe = ProgramProbe(Evaluator.for_task(load_spec("pendulum.py"), {}, [0], memory_mb=1024, timeout_s=3))
    yield probe
    probe.close()


@pytest.fixture(scope="module")
def cheetah_probe():
    probe = ProgramProbe(Evaluator.for_task(load_spec("cheetah.py"), {}, [0], memory_mb=1024, timeout_s=3))
    yield probe
    probe.close()


def run_on(code: str, obs: np.ndarray) -> np.ndarray:
    namespace: dict = {}
    exec(code, namespace)  # our own generator's output, in a test
    with np.errstate(all="ignore"):
        return np.asarray(namespace["policy"](obs), dtype=float)


def run_on_zeros(code: str, obs_size: int) -> np.ndarray:
    return run_on(code, np.zeros(obs_size))


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
    with LocalExecutor(1, memory_mb=1024) as executor:
        requests = [
            EvalRequest(str(spec.path), (), (12345,), p.skeleton, p.values, spec.allowed_imports, timeout_s=30)
            for p in map(parametrize, (c.text for c in children))
        ]
        failures = [e.failure for e in executor.evaluate(requests) if e.failure]
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


def test_where_the_action_is_a_vector_children_give_actuators_gains_of_their_own(cheetah_probe):
    """The cheetah's starter returns `np.zeros(6)`: every scalar term gives all six joints the
    same torque. Its children include actuator terms, a gain per joint, and their actions differ
    across joints; a scalar task's children never get one."""
    spec = load_spec("cheetah.py")
    children = MutateGenerator(MutateConfig(), seed=0, probe=cheetah_probe).generate(make_prompt(spec.starter_code), 30)
    vectors = [g.text for g in children if re.search(r"np\.array\(\[(?:[^,\]]+, ){5}[^,\]]+\]\) \*", g.text)]
    assert vectors, [g.text for g in children]
    obs = np.random.default_rng(0).normal(size=17)
    assert any(np.ptp(run_on(code, obs)) > 0 for code in vectors)  # joints that differ
    # As a search prompts it: the task's text says the action's shape, the shown code need not.
    bare = "import numpy as np\n\ndef policy(obs):\n    return np.zeros(6) + 0.5 * obs[8]\n"
    searched = MutateGenerator(MutateConfig(), seed=0, probe=cheetah_probe).generate(make_prompt(bare, text=spec.prompt_text), 30)
    assert any("np.array([" in g.text for g in searched)
    scalar = MutateGenerator(MutateConfig(), seed=0).generate(make_prompt(STARTER, text=load_spec("pendulum.py").prompt_text), 30)
    assert not any("np.array([" in g.text for g in scalar)


def test_a_joint_term_gives_one_actuator_a_gain_for_one_constant_where_asked(cheetah_probe):
    """`c * np.eye(6)[j] * f`: a gain for one joint, one tunable constant (the size and the index
    are structural), where an actuator term costs six: what a search capped at 10 constants can grow."""
    spec = load_spec("cheetah.py")
    children = MutateGenerator(MutateConfig(max_mutations=1, joint_terms=True), seed=0, probe=cheetah_probe).generate(make_prompt(spec.starter_code), 40)
    joint_terms = [g.text for g in children if re.search(r"\* np\.eye\(6\)\[[0-5]\] \*", g.text)]
    assert joint_terms, [g.text for g in children]
    obs = np.random.default_rng(0).normal(size=17)
    assert any(np.count_nonzero(run_on(code, obs)) == 1 and parametrize(code).n_params == 1 for code in joint_terms), joint_terms
    # Only where asked (llm.joint_terms=true).
    default = MutateGenerator(MutateConfig(max_mutations=1), seed=0, probe=cheetah_probe).generate(make_prompt(spec.starter_code), 40)
    assert not [g.text for g in default if "np.eye(" in g.text]


def test_children_of_a_program_without_numpy_import_it(pendulum_probe):
    children = MutateGenerator(MutateConfig(), seed=0, probe=pendulum_probe).generate(make_prompt("def policy(obs):\n    return 0.0\n", text="obs size is 3"), 20)
    assert any("np." in g.text for g in children)
    assert all(run_on_zeros(g.text, 3).shape == () for g in children)


def test_without_a_new_structure_a_child_is_its_parent_with_perturbed_constants():
    [child] = MutateGenerator(MutateConfig(attempts=0), seed=0).generate(make_prompt(PAPER_PENDULUM), 1)
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
    assert not pendulum_probe("def policy(obs):\n    while True:\n        pass\n")  # its 3 s limit ends it
    assert not pendulum_probe("def policy(obs):\n    return obs[:2]\n")  # two actions for one actuator
    assert not pendulum_probe("def policy(obs):\n    return float('nan')\n")
    assert not pendulum_probe("import os\ndef policy(obs):\n    return float(os.getpid() % 2)\n")
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
        generator = make_generator(openai_config(fake.url, max_concurrency=4), seed=0)
        assert len(generator.generate(make_prompt(STARTER), 4)) == 4
        assert [r["body"].get("n") for r in fake.requests] == [4, None, None, None]
        assert fake.max_active >= 2  # the three missing completions were asked for at once

        assert len(generator.generate(make_prompt(STARTER), 4)) == 4  # remembered: no n any more
        assert [r["body"].get("n") for r in fake.requests[4:]] == [None] * 4
        assert len({r["body"]["seed"] for r in fake.requests}) == 8
        generator.close()
    finally:
        fake.close()


@pytest.mark.parametrize("stream", [True, False], ids=["streamed", "whole"])
@pytest.mark.parametrize("failure, reason", [
    ("500", "500"), ("429", "429"), ("garbage", "JSONDecodeError"),
    ("html", "no completion text"), ("empty", "no completion text"),
])
def test_openai_retries_failed_and_unusable_answers(server, caplog, failure, reason, stream):
    if stream and failure == "garbage":
        reason = "no completion text"  # a body that is no event stream holds no chunk
    server.script = [failure]
    generator = make_generator(openai_config(server.url, stream=stream), seed=0)
    with caplog.at_level(logging.WARNING, logger="colmo.generate"):
        generations = generator.generate(make_prompt(STARTER), 1)
    generator.close()

    assert len(generations) == 1 and "def policy" in generations[0].text
    assert len(server.requests) == 2
    [message] = [r.getMessage() for r in caplog.records]
    assert "retry 1/3" in message and reason in message


def test_openai_streams_the_answers_and_counts_their_tokens_as_they_come():
    fake = FakeOpenAIServer(chunk_delay=0.05)
    try:
        generator = make_generator(openai_config(fake.url), seed=0)
        assert generator.tokens_so_far() is None  # no generation in flight
        done = threading.Event()
        result: list = []
        thread = threading.Thread(target=lambda: (result.extend(generator.generate(make_prompt(STARTER), 2)), done.set()))
        thread.start()
        counted = wait_for(lambda: not done.is_set() and generator.tokens_so_far(), what="tokens counted during the call")
        thread.join(timeout=120)
        assert 0 < counted <= 2 * 6  # each answer is 6 chunks of 8 characters
        assert generator.tokens_so_far() is None
        generator.close()
    finally:
        fake.close()
    [request] = fake.requests
    assert request["body"]["stream"] is True and request["body"]["stream_options"] == {"include_usage": True}
    assert [g.text.splitlines()[2] for g in result] == ["    return 0.0 * obs[0]", "    return 1.0 * obs[0]"]
    assert sum(g.prompt_tokens for g in result) == 10 and [g.completion_tokens for g in result] == [5, 5]  # the server's usage


def test_openai_asks_a_server_that_refuses_streaming_for_whole_answers(caplog):
    fake = FakeOpenAIServer(streams=False)
    try:
        generator = make_generator(openai_config(fake.url), seed=0)
        with caplog.at_level(logging.WARNING, logger="colmo.generate"):
            assert len(generator.generate(make_prompt(STARTER), 2)) == 2
            assert len(generator.generate(make_prompt(STARTER), 2)) == 2
        assert generator.tokens_so_far() is None
        generator.close()
    finally:
        fake.close()
    assert [r["body"].get("stream") for r in fake.requests] == [True, None, None]
    [message] = [r.getMessage() for r in caplog.records]
    assert "refused a streamed request (HTTP 400); asking for whole answers from now on" in message


def test_openai_asks_for_whole_answers_without_stream(server):
    generator = make_generator(openai_config(server.url, stream=False), seed=0)
    assert len(generator.generate(make_prompt(STARTER), 2)) == 2
    assert generator.tokens_so_far() is None
    generator.close()
    assert "stream" not in server.requests[0]["body"]


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


def test_openai_gives_up_after_consecutive_failures(server):
    generator = make_generator(openai_config(server.url, max_retries=10, max_consecutive_failures=3), seed=0)
    server.close()  # the server answered the start-up check, then went away
    with pytest.raises(GeneratorError) as raised:
        generator.generate(make_prompt(STARTER), 4)
    generator.close()
    message = str(raised.value)
    assert message.startswith("no OpenAI-compatible server answered after 3 attempts: APIConnectionError")
    assert "\n" not in message


@pytest.mark.parametrize("answers, serves", [(["ok"], True), (["500"], True), (["429"], True), (["400"], False), (["501"], False)])
def test_the_start_up_request_tells_a_server_that_serves_completions_from_one_that_does_not(server, answers, serves):
    """Busy answers count as serving (the search retries them); a refusal or 501 does not."""
    server.script = list(answers)
    generator = make_generator(openai_config(server.url), seed=0)
    try:
        if serves:
            generator.check_request()
        else:
            with pytest.raises(GeneratorError, match=rf"no server serves a chat completion of model .*: {server.url} answered HTTP {answers[0]}"):
                generator.check_request()
    finally:
        generator.close()
    assert [(r["path"], r["body"]["max_tokens"]) for r in server.requests] == [("/v1/chat/completions", 1)]


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


def test_openai_sends_no_more_than_max_concurrency_requests_to_a_server_and_queues_the_rest_here(caplog):
    # Six requests of 0.5 s each to a one-slot server take 3 s, longer than the 2 s timeout:
    # only a request waiting in the server's queue would time out, and none waits there.
    fake = FakeOpenAIServer(honour_n=False, delay=0.5)
    try:
        generator = make_generator(openai_config(fake.url, batch_size=6, timeout_s=2.0, max_concurrency=1), seed=0)
        with caplog.at_level(logging.WARNING, logger="colmo.generate"):
            assert len(generator.generate(make_prompt(STARTER), 6)) == 6
        generator.close()
        assert fake.max_active == 1 and len(fake.requests) == 6
        assert not [r.getMessage() for r in caplog.records if "retry" in r.getMessage() or "dropping" in r.getMessage()]
    finally:
        fake.close()


def test_openai_cancel_sends_none_of_the_queued_requests():
    fake = FakeOpenAIServer(honour_n=False, delay=2.0)
    try:
        generator = make_generator(openai_config(fake.url, batch_size=4, use_n=False, max_concurrency=1), seed=0)
        result: list = []
        thread = threading.Thread(target=lambda: result.append(generator.generate(make_prompt(STARTER), 4)))
        thread.start()
        deadline = time.monotonic() + 60
        while not fake.requests:
            assert time.monotonic() < deadline
            time.sleep(0.01)
        generator.cancel()
        thread.join(timeout=60)
        assert not thread.is_alive()
        assert len(fake.requests) == 1 and len(result[0]) == 1  # the one in flight ends on its own
        generator.close()
    finally:
        fake.close()


def test_openai_concurrency_limit_is_per_server():
    fakes = [FakeOpenAIServer(honour_n=False, delay=0.3) for _ in range(2)]
    try:
        generator = make_generator(openai_config(*(f.url for f in fakes), batch_size=8, use_n=False, max_concurrency=2), seed=0)
        assert len(generator.generate(make_prompt(STARTER), 8)) == 8
        generator.close()
        assert [f.max_active <= 2 for f in fakes] == [True, True]
        assert sum(len(f.requests) for f in fakes) == 8 and all(f.requests for f in fakes)
    finally:
        for fake in fakes:
            fake.close()


@pytest.mark.parametrize("value, urls", [
    ("http://127.0.0.1:8000/v1", ("http://127.0.0.1:8000/v1",)),
    (["http://a:1/v1", "https://b:2/v1"], ("http://a:1/v1", "https://b:2/v1")),
])
def test_base_url_is_one_url_or_a_list(value, urls):
    assert OpenAIConfig(base_url=value).base_url == urls


@pytest.mark.parametrize("value, message", [
    ([], "llm.base_url needs at least one URL"),
    ("localhost:8000", "is not an http(s) URL"),
    (8000, "llm.base_url must be one URL or a list of URLs"),
    ([1, 2], "llm.base_url must be one URL or a list of URLs"),
])
def test_a_bad_base_url_is_a_config_error(value, message):
    with pytest.raises(ConfigError, match=re.escape(message)):
        OpenAIConfig(base_url=value)


@pytest.mark.parametrize("base_url", ["{url}", "[{url},{url}]"])
def test_base_url_on_the_command_line_as_one_url_or_a_list(tmp_path, server, base_url):
    result = run_colmo(
        "colmo", "task=pendulum", "llm=openai", f"llm.base_url={base_url.format(url=server.url)}", "llm.model=test-model",
        "llm.batch_size=2", "search.max_samples=2", "gfo=none", "task.episodes=1", "executor.workers=1", "tracker=none",
        "search.progress=false", "heldout.episodes=2", "finish.render=false", "finish.simplify=false",
        f"hydra.run.dir={tmp_path}", cwd=tmp_path,
    )
    assert result.returncode == 0, result.stderr
    assert "after 2 samples" in result.stdout
    assert server.requests and all(r["path"] == "/v1/chat/completions" for r in server.requests)


def test_openai_completion_form_continues_the_prompt_text(server):
    generator = make_generator(openai_config(server.url, prompt_format="completion"), seed=0)
    generations = generator.generate(make_prompt(STARTER, text=PROMPT_TEXT), 3)
    generator.close()
    [request] = server.requests
    assert request["path"] == "/v1/completions"
    assert request["body"]["prompt"] == PROMPT_TEXT and request["body"]["stop"] == list(COMPLETION_STOP)
    assert request["body"]["n"] == 3 and "messages" not in request["body"]
    assert [g.text for g in generations] == [f"    return {i}.0 * obs[0]\n" for i in range(3)]
    assert {(g.prefix, g.shown) for g in generations} == {(PROMPT_TEXT, "")}
    assert [g.completion_tokens for g in generations] == [4, 4, 4]
    extracted = extract_policy(generations[2].text, prefix=generations[2].prefix)
    assert extracted == 'def policy(obs):\n    """Improved version of policy_v0."""\n    return 2.0 * obs[0]'


def test_chat_generations_continue_nothing_and_carry_the_shown_code(server):
    # A chat answer is read with the code its prompt showed (it may call policy_v0); a
    # completion continues the prompt text, which holds that code already.
    generator = make_generator(openai_config(server.url), seed=0)
    assert {(g.prefix, g.shown) for g in generator.generate(make_prompt(STARTER, text=PROMPT_TEXT), 2)} == {("", SHOWN_CODE)}
    generator.close()


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

    def generate(self, prompts, sampling_params=None, use_tqdm=True):
        return self.chat(prompts[0], sampling_params, use_tqdm)

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


def install_fake_module(monkeypatch, name: str, engine: type, **attributes) -> types.ModuleType:
    """A stand-in for an optional engine package (`vllm`, `llama_cpp`), importable by that name
    for the test, with `engine` as its model class, reset to no instances and no failure."""
    module = types.ModuleType(name)
    for attribute, value in attributes.items():
        setattr(module, attribute, value)
    monkeypatch.setitem(sys.modules, name, module)
    engine.instances, engine.fail_with = [], None
    return module


@pytest.fixture
def fake_vllm(monkeypatch):
    return install_fake_module(monkeypatch, "vllm", FakeLLM, LLM=FakeLLM, SamplingParams=FakeSamplingParams)


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


def test_vllm_completion_form_continues_the_prompt_text(fake_vllm):
    generator = make_generator(VLLMConfig(batch_size=2, prompt_format="completion"), seed=0)
    generations = generator.generate(make_prompt(STARTER, text=PROMPT_TEXT), 2)
    [(prompt, params, _)] = FakeLLM.instances[0].calls
    assert prompt == PROMPT_TEXT and params.stop == list(COMPLETION_STOP) and params.n == 2
    assert {g.prefix for g in generations} == {PROMPT_TEXT}


def test_vllm_missing_or_failing_is_a_generator_error(fake_vllm, monkeypatch):
    FakeLLM.fail_with = RuntimeError("CUDA out of memory\nlong traceback")
    with pytest.raises(GeneratorError, match=r"^vLLM could not load .*: RuntimeError: CUDA out of memory$"):
        make_generator(VLLMConfig(), seed=0)
    monkeypatch.setitem(sys.modules, "vllm", None)  # what an uninstalled package looks like to import
    with pytest.raises(GeneratorError, match=re.escape("llm=vllm needs vLLM: pip install 'colmo[vllm]'")):
        make_generator(VLLMConfig(), seed=0)


# ---------------------------------------------------------- llamacpp: a fake llama_cpp module

class FakeLlama:
    instances: list[FakeLlama] = []
    fail_with: Exception | None = None
    END_OF_TEXT = 7

    def __init__(self, **kwargs):
        if FakeLlama.fail_with:
            raise FakeLlama.fail_with
        self.kwargs = kwargs
        self.calls: list[dict] = []
        self.closed = False
        FakeLlama.instances.append(self)

    @classmethod
    def from_pretrained(cls, repo_id, filename, **kwargs):
        return cls(repo_id=repo_id, filename=filename, **kwargs)

    def create_chat_completion(self, messages, **sampling):
        self.calls.append({"messages": messages, **sampling})
        answer = {"message": {"role": "assistant", "content": f"def policy(obs):\n    return {len(self.calls)}.0"}}
        return {"choices": [answer], "usage": {"prompt_tokens": 40, "completion_tokens": 7}}

    def create_completion(self, prompt, **sampling):
        self.calls.append({"prompt": prompt, **sampling})
        return {"choices": [{"text": "    return obs[0]\n"}], "usage": {"prompt_tokens": 50, "completion_tokens": 5}}

    def token_eos(self):
        return FakeLlama.END_OF_TEXT

    def close(self):
        self.closed = True


@pytest.fixture
def fake_llama_cpp(monkeypatch):
    return install_fake_module(monkeypatch, "llama_cpp", FakeLlama, Llama=FakeLlama, LogitsProcessorList=list)


@pytest.fixture
def gguf(tmp_path):
    path = tmp_path / "tiny-q4.gguf"
    path.write_bytes(b"GGUF")
    return str(path)


def test_llamacpp_loads_the_model_once_and_samples_the_batch_with_fresh_seeds(fake_llama_cpp, gguf):
    cfg = LlamaCppConfig(model_path=gguf, prompt_format="chat", batch_size=3, temperature=0.8, top_p=0.95, max_tokens=300, n_ctx=2048, n_threads=2)
    generator = make_generator(cfg, seed=0)
    generations = generator.generate(make_prompt(STARTER), 3) + generator.generate(make_prompt(STARTER), 2)
    generator.close()
    [llm] = FakeLlama.instances
    assert llm.kwargs == dict(model_path=gguf, n_ctx=2048, n_threads=2, n_threads_batch=2, n_gpu_layers=0, verbose=False)
    assert all(call["messages"] == MESSAGES for call in llm.calls)
    assert all(len(call.pop("logits_processor")) == 1 for call in llm.calls)
    assert {(c["temperature"], c["top_p"], c["max_tokens"]) for c in llm.calls} == {(0.8, 0.95, 300)}
    assert len({c["seed"] for c in llm.calls}) == 5
    assert [g.text for g in generations] == [f"def policy(obs):\n    return {i}.0" for i in range(1, 6)]
    assert {g.generator for g in generations} == {"llamacpp:tiny-q4.gguf"}
    assert {(g.prompt_tokens, g.completion_tokens, g.prefix, g.shown) for g in generations} == {(40, 7, "", SHOWN_CODE)}
    assert all(g.seconds >= 0 for g in generations) and llm.closed


def test_llamacpp_logs_the_instruction_sets_its_build_uses(fake_llama_cpp, gguf, caplog):
    # A seed's answers can differ between machines whose builds differ: the run's log says which it had.
    fake_llama_cpp.llama_print_system_info = lambda: b"CPU : SSE3 = 1 | AVX = 1 | AVX2 = 0 | FMA = 1 | "
    with caplog.at_level(logging.INFO, logger="colmo.generate"):
        make_generator(LlamaCppConfig(model_path=gguf), seed=0).close()
    assert "llama.cpp built for SSE3 AVX FMA)" in caplog.text
    del fake_llama_cpp.llama_print_system_info  # a module without it
    caplog.clear()
    with caplog.at_level(logging.INFO, logger="colmo.generate"):
        make_generator(LlamaCppConfig(model_path=gguf), seed=0).close()
    assert "llama.cpp built for unknown)" in caplog.text


def test_a_regenerated_duplicate_is_sampled_hotter_up_to_max_temperature(fake_llama_cpp, gguf):
    cfg = LlamaCppConfig(model_path=gguf, temperature=0.8, retry_temperature_step=0.3, max_temperature=1.2)
    generator = make_generator(cfg, seed=0)
    for retry in range(4):
        generator.generate(Prompt(text=PROMPT_TEXT, messages=MESSAGES, programs=[STARTER], shown_code=SHOWN_CODE, island=0, parent_keys=[], retry=retry), 1)
    generator.close()
    assert [call["temperature"] for call in FakeLlama.instances[0].calls] == pytest.approx([0.8, 1.1, 1.2, 1.2])
    assert LlamaCppConfig(model_path=gguf, temperature=2.0, max_temperature=1.5).temperature_for(3) == 2.0  # never below llm.temperature


def test_only_a_chat_model_follows_up_a_wasted_answer_and_only_with_llm_follow_up(fake_llama_cpp, gguf):
    follows = {
        (form, follow_up): make_generator(LlamaCppConfig(model_path=gguf, prompt_format=form, follow_up=follow_up), seed=0).follows_up
        for form in ("chat", "completion") for follow_up in (True, False)
    }
    assert follows == {("chat", True): True, ("chat", False): False, ("completion", True): False, ("completion", False): False}


def test_llamacpp_completion_form_continues_the_prompt_text(fake_llama_cpp, gguf):
    generator = make_generator(LlamaCppConfig(model_path=gguf, prompt_format="completion"), seed=0)
    [generation] = generator.generate(make_prompt(STARTER, text=PROMPT_TEXT), 1)
    [call] = FakeLlama.instances[0].calls
    assert call["prompt"] == PROMPT_TEXT and call["stop"] == list(COMPLETION_STOP)
    assert (generation.text, generation.prefix, generation.prompt_tokens) == ("    return obs[0]\n", PROMPT_TEXT, 50)
    extracted = extract_policy(generation.text, prefix=generation.prefix)
    assert extracted == 'def policy(obs):\n    """Improved version of policy_v0."""\n    return obs[0]'


def test_llamacpp_cancel_ends_the_answer_being_written_and_the_batch(fake_llama_cpp, gguf):
    generator = make_generator(LlamaCppConfig(model_path=gguf), seed=0)
    generator.generate(make_prompt(STARTER), 1)
    [end_if_cancelled] = FakeLlama.instances[0].calls[0]["logits_processor"]
    scores = np.arange(10, dtype=np.float32)
    assert end_if_cancelled([], scores) is scores  # sampling as usual ...
    generator.cancel()
    ended = end_if_cancelled([], scores)  # ... then only the end-of-text token is left
    assert ended[FakeLlama.END_OF_TEXT] == 0 and np.isneginf(np.delete(ended, FakeLlama.END_OF_TEXT)).all()
    assert generator.generate(make_prompt(STARTER), 3) == []


def test_llamacpp_a_prompt_longer_than_the_context_is_a_generator_error(fake_llama_cpp, gguf, monkeypatch):
    def refuse(self, messages, **sampling):
        raise ValueError("Requested tokens (5000) exceed context window of 4096")

    monkeypatch.setattr(FakeLlama, "create_chat_completion", refuse)
    generator = make_generator(LlamaCppConfig(model_path=gguf, prompt_format="chat"), seed=0)
    with pytest.raises(GeneratorError, match=r"llama.cpp refused the prompt \(ValueError: Requested tokens .*\); raise llm.n_ctx"):
        generator.generate(make_prompt(STARTER), 1)


def test_llamacpp_downloads_from_the_hub_through_llama_cpp(fake_llama_cpp):
    cfg = LlamaCppConfig(repo_id="Qwen/Qwen2.5-Coder-0.5B-Instruct-GGUF", filename="qwen2.5-coder-0.5b-instruct-q4_k_m.gguf")
    generator = make_generator(cfg, seed=0)
    [llm] = FakeLlama.instances
    assert (llm.kwargs["repo_id"], llm.kwargs["filename"]) == (cfg.repo_id, cfg.filename)
    assert generator.name == "llamacpp:Qwen/Qwen2.5-Coder-0.5B-Instruct-GGUF/qwen2.5-coder-0.5b-instruct-q4_k_m.gguf"


@pytest.mark.parametrize("settings, message", [
    ({}, "llm=llamacpp needs llm.model_path=<file.gguf>, or llm.repo_id and llm.filename"),
    ({"model_path": "/nonexistent/model.gguf"}, "llm.model_path: no such file: /nonexistent/model.gguf"),
    ({"repo_id": "org/repo"}, "llm.repo_id and llm.filename go together"),
    ({"model_path": "GGUF", "repo_id": "org/repo", "filename": "m.gguf"}, "(not both)"),
    ({"model_path": "GGUF", "prompt_format": "fim"}, "llm.prompt_format must be chat or completion"),
    ({"model_path": "GGUF", "n_threads": 0}, "llm.n_threads must be >= 1"),
])
def test_llamacpp_config_errors(gguf, settings, message):
    settings = {key: gguf if value == "GGUF" else value for key, value in settings.items()}
    with pytest.raises(ConfigError, match=re.escape(message)):
        LlamaCppConfig(**settings)


def test_llamacpp_missing_or_failing_is_a_generator_error(fake_llama_cpp, gguf, monkeypatch):
    FakeLlama.fail_with = ValueError("Failed to load model from file\nmore")
    with pytest.raises(GeneratorError, match=r"^llama.cpp could not load .*tiny-q4.gguf: ValueError: Failed to load model from file$"):
        make_generator(LlamaCppConfig(model_path=gguf), seed=0)
    monkeypatch.setitem(sys.modules, "llama_cpp", None)
    with pytest.raises(GeneratorError, match=re.escape("llm=llamacpp needs llama-cpp-python: pip install 'colmo[llamacpp]'")):
        make_generator(LlamaCppConfig(model_path=gguf), seed=0)


# ------------------------------------------------------------------------------------ registry

def test_registry_names_every_generator():
    assert set(GENERATORS) == {"mutate", "openai", "vllm", "llamacpp"}
    generator = make_generator(MutateConfig(batch_size=2), seed=0)
    assert isinstance(generator, MutateGenerator)
    assert all(isinstance(g, Generation) for g in generator.generate(make_prompt(STARTER), 2))
    with pytest.raises(ConfigError, match="llm.name must be one of llamacpp, mutate, openai, vllm"):
        make_generator(GeneratorConfig(name="gpt"), seed=0)
