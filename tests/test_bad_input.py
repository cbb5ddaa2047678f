"""Bad input to `python -m colmo`: one clear line naming the problem and the fix, exit code 2.

The bad-input table of docs/security.md is this test's cases and the messages they print. They are checked
in process (`colmo.cli.App.check_command_line`), what the command prints and exits with in
tests/test_cli.py.
"""

import sys

import pytest
from conftest import EXAMPLES, refused, run_colmo

from colmo.__main__ import main as colmo
from colmo.optimize.__main__ import main as optimize

SPEC_WITH_SYNTAX_ERROR = '"""A task."""\ndef make_environment(:\n'
SPEC_WITHOUT_POLICY = '"""A task."""\nfrom colmo.environments.pendulum import PendulumSwingup\n\ndef make_environment(**options):\n    return PendulumSwingup(**options)\n'

CASES = [
    (["task=nope"], "Could not find 'task/nope'; available: a1, ball_in_cup, cheetah, pendulum, quadruped"),
    (["llm=gpt5"], "Could not find 'llm/gpt5'"),
    (["gfo=sgd"], "Could not find 'gfo/sgd'"),
    (["executor=slurm"], "Could not find 'executor/slurm'"),
    (["search.max_sampels=10"], "Could not override 'search.max_sampels': Key 'max_sampels' not in 'SearchLoopConfig'"),
    (["search.max_samples=-1"], "search.max_samples must be >= 1, got -1"),
    (["gfo.budget=0"], "gfo.budget must be >= 1, got 0"),
    (["gfo.budget=ten"], "Value 'ten' of type 'str' could not be converted to Integer"),
    (["task.episodes=0"], "task.episodes must be >= 1, got 0"),
    (["database.num_islands=0"], "database.num_islands must be >= 1, got 0"),
    (["database.max_constants=-1"], "database.max_constants must be >= 0, got -1"),
    (["llm.batch_size=0"], "llm.batch_size must be >= 1, got 0"),
    (["finish.retune_budget=-1"], "finish.retune_budget must be >= 0, got -1"),
    (["gfo=none", "finish.retune_budget=500"], "finish.retune_budget=500 re-tunes with gfo.method, and gfo=none tunes nothing"),
    (["search.steady_queue=1"], "search.steady_queue needs search.steady_state=true (without it, batches queue: search.queue_size)"),
    (["llm=openai", "search.steady_state=true"], "search.steady_state=true is for llm=mutate, whose answers take no time: with llm=openai"),
    (["executor.timeout_s=-1"], "executor.timeout_s must be > 0, got -1.0"),
    (["task.spec=missing_spec.py"], "spec file not found: 'missing_spec.py'"),
    (["task.spec={tmp}/syntax.py"], "syntax error in spec file: invalid syntax"),
    (["task.spec={tmp}/no_policy.py"], "no starter `def policy(obs)` in the spec file"),
    (["resume={tmp}"], "is not a colmo run directory (no programs.db in it)"),
]


@pytest.mark.parametrize("overrides, message", CASES, ids=[" ".join(o) for o, _ in CASES])
def test_bad_input_is_one_line_and_exit_2(tmp_path, monkeypatch, overrides, message):
    (tmp_path / "syntax.py").write_text(SPEC_WITH_SYNTAX_ERROR)
    (tmp_path / "no_policy.py").write_text(SPEC_WITHOUT_POLICY)
    monkeypatch.chdir(tmp_path)
    code, line = refused(colmo, *(o.format(tmp=tmp_path) for o in overrides), "tracker=none")
    assert code == 2 and message in line, line
    assert not (tmp_path / "outputs").exists()  # nothing ran


def test_verbose_shows_the_traceback(tmp_path):
    result = run_colmo("colmo", "gfo.budget=0", "tracker=none", "hydra.verbose=true", cwd=tmp_path)
    assert result.returncode != 0 and "Traceback" in result.stderr


@pytest.mark.parametrize("llm, module, message", [
    ("llamacpp", "llama_cpp", "llm=llamacpp needs llama-cpp-python: pip install 'colmo[llamacpp]'"),
    ("vllm", "vllm", "llm=vllm needs vLLM: pip install 'colmo[vllm]'"),
])
def test_a_generator_whose_library_is_not_installed(tmp_path, monkeypatch, llm, module, message):
    # Found missing before anything is made: no output directory, no MLflow store.
    model = tmp_path / "model.gguf"
    model.write_bytes(b"GGUF")
    monkeypatch.setitem(sys.modules, module, None)  # as if not installed
    monkeypatch.chdir(tmp_path)
    options = [f"llm.model_path={model}"] if llm == "llamacpp" else []
    code, line = refused(colmo, f"llm={llm}", *options)
    assert (code, line) == (2, f"colmo: error: {message}")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.gguf"]


def test_an_executor_whose_library_is_not_installed(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)
    monkeypatch.chdir(tmp_path)
    for app, argv in [(colmo, ["executor=ray"]), (optimize, [f"policy_file={EXAMPLES / 'paper_pendulum.py'}", "executor=ray"])]:
        assert refused(app, *argv) == (2, "colmo: error: executor=ray needs Ray: pip install 'colmo[ray]'")
    assert not any(tmp_path.iterdir())
