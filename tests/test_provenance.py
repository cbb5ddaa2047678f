"""A run records what produced its numbers (`colmo.provenance`): the commit of the checkout colmo
ran from and whether the checkout differed from it, and the versions of the libraries a score
depends on; `summary.json`, `result.json` and the MLflow tags carry it (tests/test_search.py,
test_optimize_cli.py and test_track.py check those)."""

from __future__ import annotations

import importlib.metadata
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import colmo
from colmo.provenance import LIBRARIES, installed_from, is_installed_copy, mlflow_tags, provenance, source_state


def git(directory: Path, *args: str) -> str:
    command = ["git", "-c", "user.name=t", "-c", "user.email=t@example.org", *args]
    return subprocess.run(command, cwd=directory, check=True, capture_output=True, text=True).stdout.strip()


def checkout(tmp_path: Path) -> Path:
    """A repository with a package `pkg/` at its top, committed, and `ignored/` in .gitignore."""
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "module.py").write_text("x = 1\n")
    (tmp_path / ".gitignore").write_text("ignored/\n")
    git(tmp_path, "init", "-q")
    git(tmp_path, "add", ".")
    git(tmp_path, "commit", "-q", "-m", "first")
    return tmp_path / "pkg"


def test_a_clean_checkout_gives_its_commit_and_no_changes(tmp_path):
    package = checkout(tmp_path)
    (tmp_path / "ignored").mkdir()
    (tmp_path / "ignored" / "run.log").write_text("what git ignores is not a change\n")
    assert source_state(package) == (git(tmp_path, "rev-parse", "HEAD"), False)


def test_a_changed_or_added_file_is_a_change(tmp_path):
    package = checkout(tmp_path)
    head = git(tmp_path, "rev-parse", "HEAD")
    (package / "module.py").write_text("x = 2\n")
    assert source_state(package) == (head, True)
    git(tmp_path, "checkout", "--", ".")
    (package / "new.py").write_text("y = 1\n")  # imported by the changed code, not committed
    assert source_state(package) == (head, True)


def test_a_package_that_is_not_at_the_top_of_a_checkout_has_no_commit(tmp_path):
    package = checkout(tmp_path)
    nested = package / "site-packages" / "colmo"  # installed inside some other repository's environment
    nested.mkdir(parents=True)
    assert source_state(nested) == (None, None)
    outside = tmp_path.parent / f"{tmp_path.name}-plain" / "pkg"
    outside.mkdir(parents=True)
    assert source_state(outside) == (None, None)


def test_an_installed_colmo_has_a_commit_only_where_pip_took_it_from_git():
    commit = "4c9f293f05d81552df94e2eab5ff3a920c6b56a0"
    from_git = '{"url": "https://github.com/o/colmo", "vcs_info": {"vcs": "git", "commit_id": "%s", "requested_revision": "main"}}' % commit
    assert installed_from(from_git) == ("https://github.com/o/colmo", commit)
    assert installed_from('{"dir_info": {}, "url": "file:///work/ciclone"}') == ("file:///work/ciclone", None)  # pip install .
    assert installed_from(None) == (None, None) and installed_from("not json") == (None, None)


def test_installed_facts_describe_only_the_installed_code(tmp_path):
    site = tmp_path / "site-packages" / "colmo"
    assert is_installed_copy(site, site, None)  # pip install .
    checkout = tmp_path / "checkout"
    assert is_installed_copy(checkout / "colmo", site, checkout.as_uri())  # pip install -e checkout
    assert not is_installed_copy(tmp_path / "copy" / "colmo", site, checkout.as_uri())  # PYTHONPATH=copy


def test_a_copy_run_through_pythonpath_records_its_folder_and_not_the_installed_colmo(tmp_path):
    copy = tmp_path / "frozen"
    shutil.copytree(Path(colmo.__file__).parent, copy / "colmo", ignore=shutil.ignore_patterns("__pycache__"))
    printed = subprocess.run(
        [sys.executable, "-c", "import json; from colmo.provenance import provenance; print(json.dumps(provenance()))"],
        env={**os.environ, "PYTHONPATH": str(copy)}, cwd=tmp_path, check=True, capture_output=True, text=True,
    ).stdout
    record = json.loads(printed)
    assert record["source"] == str(copy.resolve())
    assert record["commit"] is None and record["installed_from"] is None and record["uncommitted_changes"] is None


def test_the_record_names_the_installed_libraries_and_the_tags_carry_them():
    record = provenance()
    installed = {name: importlib.metadata.version(name) for name in ("numpy", "mujoco", "nevergrad")}
    assert installed.items() <= record["libraries"].items()
    assert set(record["libraries"]) <= set(LIBRARIES) and record["cpus"] >= 1
    assert record["source"] == str(Path(colmo.__file__).resolve().parent.parent)
    tags = mlflow_tags()
    assert tags["colmo.version"] == record["colmo"] == importlib.metadata.version("colmo")
    assert all(tags[f"colmo.lib.{name}"] == version for name, version in installed.items())
    # Run from a checkout (pip install -e), the commit is MLflow's source tag; installed (.ci/run), neither is set.
    assert tags.get("mlflow.source.git.commit") == record["commit"]
