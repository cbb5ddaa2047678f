"""The structure stays readable: the module map (docs/concepts.md) stays true (every path it names exists,
and every module of colmo/ is on it), no module imports itself through others (no import
cycle), and the config schemas import no component.

The map ("How colmo works") is how a newcomer finds the module that owns a concept; a rename or a new
module that the map does not follow makes it lie, so this test fails then. An import cycle
makes the order of a module's imports matter and hides which concept depends on which; the
import graph is read from every `import` statement of colmo/ (those inside functions and under
`TYPE_CHECKING` too: they are dependencies all the same).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MAP = ROOT / "docs" / "concepts.md"
MAP_ROW = re.compile(r"^\| (`colmo/[^|]+)\|")
PATH = re.compile(r"`(colmo/[\w/.]+)`")
# Parts of the package that are data or plumbing, not concepts of the method.
NOT_CONCEPTS = {"colmo/__init__.py", "colmo/__main__.py", "colmo/conf", "colmo/__pycache__"}


def map_paths() -> list[str]:
    """The paths in the first column of the module table."""
    rows = [MAP_ROW.match(line) for line in MAP.read_text().splitlines()]
    return [path.rstrip("/") for row in rows if row for path in PATH.findall(row.group(1))]


def test_the_module_map_names_only_modules_that_exist() -> None:
    paths = map_paths()
    assert len(paths) >= 20, paths
    missing = [path for path in paths if not (ROOT / path).exists()]
    assert not missing, f"the module map names paths that do not exist: {missing}"


def test_every_module_of_colmo_is_on_the_map() -> None:
    named = set(map_paths())
    present = {f"colmo/{entry.name}" for entry in (ROOT / "colmo").iterdir()} - NOT_CONCEPTS
    unmapped = sorted(present - named)
    assert not unmapped, f"modules missing from the module map (docs/concepts.md): {unmapped}"


def module_files() -> dict[str, Path]:
    """colmo's modules by dotted name (a package by its own name)."""
    modules = {}
    for path in (ROOT / "colmo").rglob("*.py"):
        parts = path.relative_to(ROOT).with_suffix("").parts
        modules[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return modules


def imports(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """The colmo modules that module `name` imports anywhere in its code: `from a.b import c`
    imports the module a.b.c if there is one, else a.b."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names if alias.name in modules}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parent = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(parent + ([base] if base else []))
            for alias in node.names:
                full = f"{base}.{alias.name}"
                found |= {full} if full in modules else ({base} if base in modules else set())
    return found - {name}


def import_graph() -> dict[str, set[str]]:
    modules = module_files()
    return {name: imports(name, path, modules) for name, path in modules.items()}


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        for successor in sorted(graph[node]):
            if successor not in index:
                visit(successor)
                low[node] = min(low[node], low[successor])
            elif successor in stack:
                low[node] = min(low[node], index[successor])
        if low[node] == index[node]:
            component = []
            while not component or component[-1] != node:
                component.append(stack.pop())
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def test_no_module_imports_itself_through_others() -> None:
    graph = import_graph()
    assert len(graph) > 80 and sum(map(len, graph.values())) > 250  # the graph was read
    assert cycles(graph) == []


def test_the_cycle_finder_finds_a_cycle() -> None:
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_the_config_schemas_import_no_component() -> None:
    """colmo/config/ describes options; the components they pick import it, never the reverse."""
    allowed = ("colmo.config", "colmo.errors", "colmo.registry")
    reached = {name: sorted(m for m in targets if not m.startswith(allowed)) for name, targets in import_graph().items() if name.startswith("colmo.config")}
    assert {name: targets for name, targets in reached.items() if targets} == {}


def test_every_parse_goes_through_the_one_lock() -> None:
    """CPython's AST constructor is not safe in two threads at once: colmo parses only through
    `colmo.astutil.parse` (see its docstring)."""
    direct = [
        f"{path.relative_to(ROOT)}:{node.lineno}"
        for path in (ROOT / "colmo").rglob("*.py") if path.name != "astutil.py"
        for node in ast.walk(ast.parse(path.read_text()))
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "parse"
        and isinstance(node.func.value, ast.Name) and node.func.value.id == "ast"
    ]
    assert direct == []


def test_parse_is_ast_parse() -> None:
    from colmo.astutil import parse

    assert ast.dump(parse("x = 1\n")) == ast.dump(ast.parse("x = 1\n"))
    assert isinstance(parse("1 + 2", mode="eval"), ast.Expression)
