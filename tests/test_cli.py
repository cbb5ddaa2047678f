"""The command line as a user meets it: the console scripts, `--help` built from the schemas for
the options chosen, shell completion, and one-line errors (exit 2 for a bad value, 1 for a
runtime failure, no traceback unless `hydra.verbose=true`) whatever Hydra flag is given. What a
command refuses before Hydra starts is checked in process (`refused`) beyond one run of each
kind of refusal through the console script."""

import shlex
import socket
import subprocess
import sys
from importlib import resources
from pathlib import Path

import pytest
from conftest import FakeOpenAIServer, refused
from mlflow import MlflowClient

from colmo.__main__ import main as colmo
from colmo.cli import refusal, renamed
from colmo.help import help_text
from colmo.shell import shell_override

BIN = Path(sys.executable).parent
TINY = ("search.max_samples=2", "gfo.budget=2", "task.episodes=1", "heldout.episodes=2", "finish.render=false", "finish.simplify=false",
        "executor.workers=1", "search.progress=false")
# A spec whose environment cannot be built: the coordinator loads the spec (it is fine), the
# sandboxed workers fail to make the environment when the starter is calibrated.
SPEC_ENV_RAISES = (
    '"""A task whose environment cannot be built."""\n\n'
    "def make_environment(**options):\n    raise RuntimeError('no such robot')\n\n\n"
    "def policy(obs):\n    return 0.0\n"
)


def script(name: str, *args: str, cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess:
    """Run an installed console script as a user would, in `cwd`."""
    path = BIN / name
    if not path.exists():
        pytest.skip(f"{name} is not installed (pip install -e .)")
    return subprocess.run([str(path), *args], cwd=cwd, capture_output=True, text=True, timeout=timeout)


def one_error_line(result: subprocess.CompletedProcess, code: int) -> str:
    """The single `colmo: error:` line of a failed run (colmo's log lines may come before it)."""
    assert result.returncode == code, (result.returncode, result.stderr)
    assert "Traceback" not in result.stderr, result.stderr
    errors = [line for line in result.stderr.splitlines() if line.startswith("colmo: error: ")]
    assert len(errors) == 1 and result.stderr.rstrip().endswith(errors[0]), result.stderr
    return errors[0]


def test_every_console_script_is_installed():
    for name in ("colmo", "colmo-optimize", "colmo-evaluate", "colmo-report", "colmo-simplify", "colmo-render"):
        assert (BIN / name).exists(), name


def test_help_explains_groups_and_fields_without_schema_entries(tmp_path):
    result = script("colmo", "--help", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    text = result.stdout
    assert text.startswith("colmo: the program search.") and "powered by Hydra" not in text
    assert "schema" not in text  # Hydra's own help listed mutate_schema, openai_schema, ...
    for group in ("task", "gfo", "llm", "database", "executor", "tracker"):
        assert f"\n  {group}\n" in text, group
    assert "    mutate       * The embedded baseline generator" in text  # the chosen option, marked
    assert "  gfo.budget=100\n      evaluations per program" in text
    assert "  task.name=pendulum\n" in text  # the value in the composed config, not the schema's ???
    assert "  tracker.tracking_uri=null\n" in text  # the default tracker is mlflow
    assert not list(tmp_path.iterdir())  # help runs nothing


def test_help_shows_the_fields_of_the_options_chosen():
    # In process: what `colmo llm=llamacpp gfo=bo gfo.budget=7 --help` prints (the test above
    # runs the command), and `colmo-optimize tracker=mlflow --help`.
    text = help_text("search", "", ["llm=llamacpp", "gfo=bo", "gfo.budget=7"])
    assert "    llamacpp     * In-process llama.cpp" in text and "    mutate         The embedded" in text
    assert "  llm.model_path=null\n      a local GGUF file" in text and "llm.crossover_rate" not in text
    assert "  gfo.sampler=tpe\n" in text and "  gfo.budget=7\n" in text
    optimize = help_text("optimize", "", ["tracker=mlflow"])
    assert ": tune the constants" in optimize.splitlines()[0]
    assert "  policy_file=???\n" in optimize and "  tracker.experiment=null\n" in optimize


def test_help_with_a_bad_override_is_one_line():
    with pytest.raises(Exception) as raised:  # what `colmo task=nope --help` prints in one line, exit 2
        help_text("search", "", ["task=nope"])
    assert "Could not find 'task/nope'" in refusal(raised.value)[1]


def completions(line: str, cwd: Path, shell: str = "bash") -> list[str]:
    """What a Tab after `line` offers: the shell runs `colmo -sc query=<shell>` with the line in COMP_LINE."""
    query = subprocess.run(
        [str(BIN / "colmo"), "-sc", f"query={shell}"], cwd=cwd, capture_output=True, text=True, timeout=120,
        env={"PATH": str(BIN), "COMP_LINE": line, "COMP_POINT": str(len(line))},
    )
    assert query.returncode == 0 and not query.stderr, query.stderr
    return query.stdout.split()


def test_shell_completion_installs_and_completes(tmp_path):
    result = script("colmo", "-sc", "install=bash", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "hydra_bash_completion" in result.stdout and "complete -o nospace -o default -F hydra_bash_completion colmo" in result.stdout
    assert "gfo=oneplusone" in completions("colmo gfo=o", tmp_path)
    assert "gfo.budget=" in completions("colmo gfo.", tmp_path)  # keys of the composed config
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("shell", ["bash", "fish"])
def test_shell_completion_offers_each_groups_options_and_no_schema_entry(tmp_path, shell):
    conf = resources.files("colmo.conf")
    for group in ("task", "gfo", "llm", "executor", "database", "tracker"):
        options = sorted(entry.name.removesuffix(".yaml") for entry in (conf / group).iterdir() if entry.name.endswith(".yaml"))
        assert completions(f"colmo {group}=", tmp_path, shell) == [f"{group}={option}" for option in options]  # not gfo=schema, gfo=bo_schema


def test_shell_completion_of_hydra_groups_offers_the_installed_plugins(tmp_path):
    pytest.importorskip("hydra_plugins.hydra_joblib_launcher")
    offered = completions("colmo hydra/launcher=", tmp_path)
    assert {"hydra/launcher=basic", "hydra/launcher=slurm", "hydra/launcher=joblib"} <= set(offered)


def test_cfg_job_prints_the_config_or_one_error_line(tmp_path, monkeypatch):
    good = script("colmo", "--cfg", "job", "gfo.budget=7", cwd=tmp_path)
    assert good.returncode == 0 and "budget: 7" in good.stdout, good.stderr
    monkeypatch.chdir(tmp_path)
    code, line = refused(colmo, "--cfg", "job", "task=nope")
    assert code == 2 and "Could not find 'task/nope'; available: a1, ball_in_cup, cheetah, pendulum, quadruped" in line
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("value", [
    "outputs/pendulum/2026-12-05_12-57-08",
    "/runs/cheetah/s0/0_llm=mutate,search.max_samples=1000000,seed=0,task=cheetah",  # a sweep job's directory
    "/tmp/a b/it's", "/x/[1]", "~/x", "/a/$HOME/`x`", 'q"x', "a\\b",
])
def test_a_printed_override_reads_back_as_its_value_through_the_shell_and_hydra(value):
    from hydra.core.override_parser.overrides_parser import OverridesParser

    line = shell_override("resume", value)
    [argument] = shlex.split(line)
    override = OverridesParser.create().parse_override(argument)
    assert (override.key_or_group, override.value()) == ("resume", value)
    assert (line == f"resume={value}") is (value == "outputs/pendulum/2026-12-05_12-57-08")  # plain where it can be


def test_renamed_keys_are_read_with_their_new_names(capsys):
    argv = ["-m", "evaluation.episodes=5", "evaluation.render=false", "+evaluation.top=2", "~evaluation.coverage",
            "evaluation.robustness_delays=[0,1]", "evaluation.top=1,2", "task=pendulum", "evaluations.x=1"]
    assert renamed(argv) == ["-m", "heldout.episodes=5", "finish.render=false", "+finish.top=2", "~finish.coverage",
                             "finish.robustness_delays=[0,1]", "finish.top=1,2", "task=pendulum", "evaluations.x=1"]
    said = capsys.readouterr().err.splitlines()
    assert said[0] == "colmo: evaluation.episodes is now heldout.episodes: use the new name, the old one will stop working"
    assert len(said) == 6


def test_an_old_key_on_the_command_line_composes_as_the_new_one(tmp_path):
    shown = script("colmo", "--cfg", "job", "evaluation.episodes=7", "evaluation.render=false", cwd=tmp_path)
    assert shown.returncode == 0, shown.stderr
    assert "heldout:\n  episodes: 7\n" in shown.stdout and "  render: false\n" in shown.stdout
    assert "colmo: evaluation.render is now finish.render" in shown.stderr


def test_a_bad_value_is_one_line_exit_2_and_leaves_nothing(tmp_path):
    line = one_error_line(script("colmo", "seed=-1", cwd=tmp_path), 2)
    assert "seed must be >= 0, got -1" in line, line
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("overrides, message", [
    (["-m", "seed=0,-1"], "seed must be >= 0, got -1"),  # every value of a sweep is checked before any job runs
    (["-m", "gfo.budget=tag(int,interval(0,4))"], "gfo.budget must be >= 1, got 0"),  # the ends of a sweeper's interval too
    (["hydra.run.dir=/proc/colmo/run"], "cannot create the output directory /proc/colmo/run"),
    # an episode of no steps would score every program 0, and a string would fail deep in a worker
    (["+task.env.horizon=0"], "task.env.horizon must be a whole number of control steps >= 1, got 0"),
    (["+task.env.horizon=abc"], "task.env.horizon must be a whole number of control steps >= 1, got 'abc'"),
], ids=["sweep", "interval", "output dir", "horizon 0", "horizon text"])
def test_bad_values_of_sweeps_and_output_directories_are_refused_before_anything_runs(tmp_path, monkeypatch, overrides, message):
    monkeypatch.chdir(tmp_path)
    code, line = refused(colmo, *overrides)
    assert code == 2 and message in line, line
    assert not list(tmp_path.iterdir())


def test_a_spec_whose_environment_fails_is_one_line_with_the_default_tracker(tmp_path):
    (tmp_path / "broken.py").write_text(SPEC_ENV_RAISES)
    result = script("colmo", f"task.spec={tmp_path / 'broken.py'}", *TINY, "hydra.run.dir=run", cwd=tmp_path)
    line = one_error_line(result, 2)
    assert "the starter policy in" in line and "building broken.py's environment: RuntimeError: no such robot" in line, line
    # The tracker built nothing of the task; its run records the failure.
    client = MlflowClient(f"sqlite:///{tmp_path / 'mlruns.db'}")
    (run,) = client.search_runs([client.get_experiment_by_name("pendulum").experiment_id])
    assert run.info.status == "FAILED"

    verbose = script("colmo", f"task.spec={tmp_path / 'broken.py'}", *TINY, "tracker=none", "hydra.run.dir=run2", "hydra.verbose=true", cwd=tmp_path)
    assert verbose.returncode != 0 and "Traceback" in verbose.stderr


def test_a_policy_file_that_is_a_directory_is_one_line(tmp_path):
    line = one_error_line(script("colmo-optimize", f"policy_file={tmp_path}", cwd=tmp_path), 2)
    assert f"policy_file is a directory, not a file: {tmp_path}" in line
    assert not list(tmp_path.iterdir())


def test_an_openai_server_that_does_not_answer_is_one_line_exit_1_before_anything_exists(tmp_path, monkeypatch):
    with socket.socket() as probe:  # a port nothing listens on: the connection is refused at once
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    result = script("colmo", "llm=openai", f"llm.base_url=http://127.0.0.1:{port}/v1", *TINY, cwd=tmp_path)  # the default tracker, mlflow
    line = one_error_line(result, 1)
    assert line.startswith(f"colmo: error: llm=openai: no OpenAI-compatible server answers at http://127.0.0.1:{port}/v1"), line
    assert "start one" in line and "llm.base_url" in line
    assert result.stderr == line + "\n" and not result.stdout  # nothing ran: no sandbox, no search, no MLflow run
    assert not list(tmp_path.iterdir())  # no output directory, no MLflow store
    monkeypatch.chdir(tmp_path)
    code, line = refused(colmo, "-m", "llm=openai", f"llm.base_url=http://127.0.0.1:{port}/v1", "seed=0,1", *TINY)
    assert code == 1 and "no OpenAI-compatible server answers" in line
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("status", ["404", "501"])
def test_an_openai_server_that_answers_but_serves_no_completion_is_one_line_exit_1_before_anything_exists(tmp_path, status):
    """It answers `/v1/models` (any HTTP answer), so only a real request shows it serves nothing;
    it used to pass the start-up check, and a search against it ended with 0 samples and exit 0."""
    fake = FakeOpenAIServer()
    try:
        fake.script = [status]
        result = script("colmo", "llm=openai", f"llm.base_url={fake.url}", *TINY, cwd=tmp_path)
        line = one_error_line(result, 1)
        assert line.startswith(f"colmo: error: llm=openai: no server serves a chat completion of model 'Qwen/Qwen2.5-Coder-7B-Instruct': {fake.url} answered HTTP {status}"), line
        assert [request["body"]["max_tokens"] for request in fake.requests] == [1]  # one request of one token
        assert not list(tmp_path.iterdir())  # no output directory, no MLflow store
    finally:
        fake.close()
