"""What produced a run's numbers: colmo's version, the folder its code was imported from and, when
that is a git checkout, its commit and whether the checkout differed from it (installed, where pip
took it from; neither where the code imported is not the installed one: a `PYTHONPATH` copy); Python,
the platform and its cores; and the versions of the libraries a score depends on (the
simulator, the optimizers, numpy, the model runtime). `summary.json` and `result.json` carry
it as `provenance`, and the MLflow run as tags, so a number can be traced to the code and
libraries that made it.
"""

from __future__ import annotations

import functools
import importlib.metadata
import json
import os
import platform
import subprocess
from pathlib import Path
from typing import Any, Optional

# The distributions whose versions can change a score or a search's path.
LIBRARIES = (
    "numpy", "scipy", "mujoco", "dm-control", "nevergrad", "cma", "optuna", "llama-cpp-python", "vllm", "hydra-core",
)


def source_state(package: Path) -> tuple[Optional[str], Optional[bool]]:
    """The commit of the git checkout whose top folder holds `package`, and whether the checkout
    differs from it (a file changed, or one added that git does not ignore); (None, None) where
    `package` is not at the top of a checkout (an installed package, even one inside some other
    repository's virtual environment) or git is missing."""
    try:
        top = subprocess.run(
            ["git", "rev-parse", "--show-toplevel", "HEAD"], cwd=package, capture_output=True, text=True, timeout=10
        )
        lines = top.stdout.split()
        if top.returncode != 0 or len(lines) != 2 or Path(lines[0]).resolve() != package.resolve().parent:
            return None, None
        changes = subprocess.run(["git", "status", "--porcelain"], cwd=package, capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        return None, None
    return lines[1], (bool(changes.stdout.strip()) if changes.returncode == 0 else None)


def installed_from(direct_url: Optional[str]) -> tuple[Optional[str], Optional[str]]:
    """The URL pip installed colmo from and, for a git URL (`pip install git+https://...`), the
    commit, read from PEP 610's `direct_url.json` (`direct_url`, its text); (None, None) without one."""
    try:
        record = json.loads(direct_url or "")
    except ValueError:
        return None, None
    return record.get("url"), (record.get("vcs_info") or {}).get("commit_id")


def is_installed_copy(package: Path, located: Path, url: Optional[str]) -> bool:
    """Whether the code imported at `package` is the installed distribution's: its files are where
    the distribution put them (`located`), or the distribution is an editable install of
    `package`'s folder (its PEP 610 `url`)."""
    return located.resolve() == package.resolve() or url == package.resolve().parent.as_uri()


@functools.cache
def provenance() -> dict[str, Any]:
    """This process's provenance (module docstring), taken once: `colmo.cli` asks as each job
    starts, so edits to the checkout while a run goes on do not change what it records. An
    installed colmo has the commit only where pip installed it from git."""
    package = Path(__file__).resolve().parent
    commit, uncommitted = source_state(package)
    url = None
    if commit is None:
        try:
            distribution = importlib.metadata.distribution("colmo")
            url, commit = installed_from(distribution.read_text("direct_url.json"))
            if not is_installed_copy(package, Path(str(distribution.locate_file("colmo"))), url):
                url, commit = None, None  # what pip installed is not what runs
        except importlib.metadata.PackageNotFoundError:
            pass
        uncommitted = False if commit else None
    return {
        "colmo": _version("colmo"),
        "source": str(package.parent),
        "commit": commit,
        "uncommitted_changes": uncommitted,
        "installed_from": url,
        "python": platform.python_version(),
        "platform": platform.platform(),
        "cpus": os.cpu_count(),
        "libraries": {name: version for name in LIBRARIES if (version := _version(name)) is not None},
    }


def mlflow_tags() -> dict[str, str]:
    """The provenance as MLflow tags: MLflow's own source-commit tag (shown on the run's page)
    and `colmo.*` tags for the rest."""
    record = provenance()
    tags = {"colmo.version": record["colmo"] or "unknown", "colmo.python": record["python"], "colmo.cpus": str(record["cpus"])}
    if record["commit"]:
        tags["mlflow.source.git.commit"] = record["commit"]
        tags["colmo.uncommitted_changes"] = str(record["uncommitted_changes"]).lower()
    tags.update({f"colmo.lib.{name}": version for name, version in record["libraries"].items()})
    return tags


def _version(distribution: str) -> Optional[str]:
    try:
        return importlib.metadata.version(distribution)
    except importlib.metadata.PackageNotFoundError:
        return None
