"""Every colmo command the README and the getting-started page show is one colmo accepts as
written: each is parsed and composed, its every sweep value validated and its input files
checked, by the command's own pre-flight (`colmo.cli.App.check_command_line`, what runs before
Hydra starts), in a directory laid out as the page assumes (the examples, a run to resume, a
tracking database, the best policy of a run). A renamed option, group or file in the code that
the pages do not follow fails here. What each command does when it runs is tested elsewhere:
the first run and the main job by tests/test_deadline.py and tests/test_task_searches.py, the
sweep by tests/test_sweep_comparison.py and tests/test_deadline.py, the model by tests/test_llm.py,
the tools by tests/test_optimize_cli.py, tests/test_robustness.py, tests/test_simplify.py,
tests/test_render.py and tests/test_report.py. The OpenAI-compatible server's command needs a
server (its check asks one): it is composed without that check."""

from __future__ import annotations

import importlib
import re
import shlex
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", ROOT / "docs" / "getting-started.md"]
APPS = {
    "colmo": "colmo.__main__", "colmo-optimize": "colmo.optimize.__main__", "colmo-evaluate": "colmo.heldout.__main__",
    "colmo-report": "colmo.report.__main__", "colmo-simplify": "colmo.simplify.__main__", "colmo-render": "colmo.render.__main__",
}
NEEDS_A_SERVER = "llm=openai"


def commands() -> list[str]:
    """The colmo command lines of the pages' bash blocks, comments cut, each once."""
    found: dict[str, None] = {}
    for page in PAGES:
        for block in re.findall(r"```bash\n(.*?)```", page.read_text(), re.DOTALL):
            for line in block.splitlines():
                line = re.sub(r"\s+#.*$", "", line).strip()
                if line.split(" ", 1)[0] in APPS:
                    found[line] = None
    return list(found)


def test_the_pages_show_every_command():
    shown = {line.split(" ", 1)[0] for line in commands()}
    assert shown == set(APPS), shown  # each of colmo's commands has an example


@pytest.fixture
def laid_out(tmp_path, monkeypatch) -> Path:
    """A working directory as the pages assume it: the checkout's examples and scripts, a stopped
    run to resume, a tracking database, a run's best policy."""
    for name in ("examples", "scripts"):
        (tmp_path / name).symlink_to(ROOT / name)
    shutil.copy(ROOT / "examples" / "paper_pendulum.py", tmp_path / "best_policy.py")
    (tmp_path / "mlruns.db").touch()
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize("line", commands())
def test_every_command_on_the_pages_is_accepted_as_written(line, laid_out, tmp_path):
    if "<run>" in line:  # a run with the settings the command has (what resuming checks), short: its directory as colmo names it
        from conftest import run_colmo

        first = run_colmo("colmo", "task=pendulum", "search.max_samples=1", "finish.render=false", "finish.simplify=false",
                          "heldout.episodes=2", "tracker=none", "search.progress=false", cwd=laid_out)
        assert first.returncode == 0, first.stderr
        line = line.replace("outputs/pendulum/<run>", str(next(laid_out.glob("outputs/pendulum/*")).relative_to(laid_out)))
    if "$(python scripts/fetch_test_model.py)" in line or "llm.model_path=..." in line:
        model = tmp_path / "model.gguf"  # what the fetch prints: a model file's path (its contents are the model tests')
        model.write_bytes(b"GGUF")
        line = line.replace("$(python scripts/fetch_test_model.py)", str(model)).replace("llm.model_path=...", f"llm.model_path={model}")
    program, *argv = shlex.split(line)
    app = importlib.import_module(APPS[program]).main
    if NEEDS_A_SERVER in argv:
        from colmo.cli import compose

        compose("search", argv)  # composed and validated; the server check needs the server
        return
    app.check_command_line(argv)  # raises what the command would refuse it with
