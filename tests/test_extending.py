"""A component from an installed package (docs/extending.md): the page's example GFO method, as
written there, installed as a package with an entry point in the `colmo.components` group, is
`gfo=<name>` on the command line with its own option, checked like colmo's own; a package whose
module fails to import, or takes a name already taken, ends the command in one line."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import last_json_line

from colmo.errors import EXIT_USAGE
from colmo.registry import Registry

ROOT = Path(__file__).resolve().parent.parent
PAGE = (ROOT / "docs" / "extending.md").read_text()
[METHOD_CODE] = re.findall(r"```python\n(.*?)```", PAGE, re.DOTALL)
[ENTRY_POINTS] = re.findall(r"```toml\n(.*?)```", PAGE, re.DOTALL)


def install(site: Path, modules: dict[str, str], entry_points: dict[str, str]) -> Path:
    """A package `my_package` with `modules` and `entry_points` (name -> module) in the
    `colmo.components` group, installed into `site` as pip would lay it out (a `.dist-info`)."""
    package = site / "my_package"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text("")
    for name, code in modules.items():
        (package / f"{name}.py").write_text(code)
    info = site / "my_package-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: my-package\nVersion: 0.1\n")
    lines = "".join(f"{name} = {module}\n" for name, module in entry_points.items())
    (info / "entry_points.txt").write_text(f"[colmo.components]\n{lines}")
    return site


def run(site: Path, cwd: Path, *argv: str) -> subprocess.CompletedProcess:
    """`python -m colmo.optimize argv` with the package in `site` installed."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(site), os.environ.get("PYTHONPATH")])))
    return subprocess.run([sys.executable, "-m", "colmo.optimize", *argv], cwd=cwd, env=env, capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The page's example, with the page's entry point."""
    declared = dict(re.findall(r'^(\w+) = "([\w.]+)"$', ENTRY_POINTS, re.MULTILINE))  # tomllib is Python 3.11's
    assert ENTRY_POINTS.startswith('[project.entry-points."colmo.components"]\n')
    assert declared == {"random_search": "my_package.random_search"}
    return install(tmp_path_factory.mktemp("site"), {"random_search": METHOD_CODE}, declared)


def test_the_pages_method_runs_from_the_command_line_with_its_own_option(site, tmp_path, examples):
    result = run(
        site, tmp_path, f"policy_file={examples / 'pendulum_mistuned.py'}", "gfo=random_search", "gfo.spread=0.5", "gfo.budget=12",
        "task.episodes=2", "heldout.episodes=2", "executor.workers=2",
    )
    assert result.returncode == 0, result.stderr
    summary = last_json_line(result.stdout)
    assert summary["evaluations"] == 14  # its budget, the readable 4-digit code, the referee's final score
    assert summary["failure"] is None and summary["score"] >= summary["score_initial"]


@pytest.mark.parametrize(("override", "message"), [
    ("gfo.spread=-1", "gfo.spread must be > 0, got -1.0"),
    ("gfo.nope=1", "Key 'nope' not in 'RandomSearchConfig'"),
], ids=["its check", "a field it lacks"])
def test_its_options_are_checked_like_colmos_own(site, tmp_path, examples, override, message):
    result = run(site, tmp_path, f"policy_file={examples / 'pendulum_mistuned.py'}", "gfo=random_search", override)
    assert result.returncode == EXIT_USAGE and result.stderr.startswith("colmo: error: ") and message in result.stderr, result.stderr
    assert len(result.stderr.splitlines()) == 1 and not (tmp_path / "outputs").exists()


def test_help_lists_it(site, tmp_path):
    result = run(site, tmp_path, "gfo=random_search", "--help")
    assert result.returncode == 0, result.stderr
    assert "random_search" in result.stdout and "gfo.spread" in result.stdout


@pytest.mark.parametrize(("code", "message"), [
    ("import no_such_module\n", "the colmo.components entry point broken = my_package.broken fails to import: ModuleNotFoundError"),
    (
        "from colmo import METHODS, Method\n\n@METHODS.register('cma')\nclass Mine(Method):\n    pass\n",
        "fails to import: ValueError: gfo.method=cma is taken by colmo.optimize.methods.CMA: my_package.broken.Mine needs another name",
    ),
], ids=["an import error", "a name taken"])
def test_a_package_that_fails_to_register_ends_the_command_in_one_line(tmp_path, code, message):
    site = install(tmp_path / "site", {"broken": code}, {"broken": "my_package.broken"})
    result = run(site, tmp_path, "policy_file=x.py")
    assert result.returncode == EXIT_USAGE and result.stderr.startswith("colmo: error: ") and message in result.stderr, result.stderr
    assert len(result.stderr.splitlines()) == 1


def test_a_registry_refuses_a_second_component_under_a_name_taken():
    registry: Registry[type] = Registry("widget.name")
    registry.register("a")(int)
    registry.register("a")(int)  # the same one again: nothing changes
    with pytest.raises(ValueError, match=r"^widget.name=a is taken by builtins.int: builtins.float needs another name$"):
        registry.register("a")(float)
    assert dict(registry) == {"a": int}
