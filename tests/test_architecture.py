"""The README's module map stays true: every path it names exists, and every module of colmo/ is on it.

The map ("How it works") is how a newcomer finds the module that owns a concept; a rename or a new
module that the map does not follow makes it lie, so this test fails then.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MAP_ROW = re.compile(r"^\| (`colmo/[^|]+)\|")
PATH = re.compile(r"`(colmo/[\w/.]+)`")
# Parts of the package that are data or plumbing, not concepts of the method.
NOT_CONCEPTS = {"colmo/__init__.py", "colmo/__main__.py", "colmo/conf", "colmo/__pycache__"}


def map_paths() -> list[str]:
    """The paths in the first column of the README's module table."""
    rows = [MAP_ROW.match(line) for line in (ROOT / "README.md").read_text().splitlines()]
    return [path.rstrip("/") for row in rows if row for path in PATH.findall(row.group(1))]


def test_the_module_map_names_only_modules_that_exist() -> None:
    paths = map_paths()
    assert len(paths) >= 20, paths
    missing = [path for path in paths if not (ROOT / path).exists()]
    assert not missing, f"the README's module map names paths that do not exist: {missing}"


def test_every_module_of_colmo_is_on_the_map() -> None:
    named = set(map_paths())
    present = {f"colmo/{entry.name}" for entry in (ROOT / "colmo").iterdir()} - NOT_CONCEPTS
    unmapped = sorted(present - named)
    assert not unmapped, f"modules missing from the README's module map: {unmapped}"
