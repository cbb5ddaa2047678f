"""The documentation stays short, linked and light: the README within 400 lines, every relative
link of the README and of the site's pages pointing at a file that exists, no run store or log
kept under docs/ (results pages keep compact summaries), and the configuration reference
generated from `--help` rather than written (the site itself is built with warnings as errors
by .ci/run)."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
LINK = re.compile(r"\]\((?!https?://|#|mailto:)([^)\s#]+)(?:#[^)]*)?\)")


def relative_links(page: Path) -> list[str]:
    text = re.sub(r"```.*?```", "", page.read_text(), flags=re.DOTALL)  # links in code are code
    return LINK.findall(text)


def test_the_readme_is_at_most_400_lines():
    assert len((ROOT / "README.md").read_text().splitlines()) <= 400


@pytest.mark.parametrize("page", [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))], ids=lambda page: str(page.relative_to(ROOT)))
def test_every_relative_link_points_at_a_file(page):
    broken = [link for link in relative_links(page) if not (page.parent / link).exists()]
    assert not broken, f"{page.relative_to(ROOT)} links to what does not exist: {broken}"


def test_no_run_store_or_log_is_kept_under_docs():
    try:
        tracked = subprocess.run(["git", "ls-files", "docs"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    except (OSError, subprocess.CalledProcessError):
        tracked = [str(path.relative_to(ROOT)) for path in DOCS.rglob("*")]
    assert not [path for path in tracked if path.endswith((".db", ".log"))]


def test_the_configuration_reference_is_colmos_help(monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT / "scripts"))
    import docs_hooks

    page = "# Reference\n\n<!-- help: colmo gfo=cma | gfo=cma -->\n"
    expanded = docs_hooks.on_page_markdown(page)
    assert "<!-- help:" not in expanded
    assert "$ colmo gfo=cma --help" in expanded and "gfo.method=cma" in expanded and "gfo.budget=100" in expanded
    reference = (DOCS / "reference" / "configuration.md").read_text()
    assert reference.count("<!-- help: ") >= 15  # every group's options and every tool, none written out


def results_pages() -> list[str]:
    """The pages of the site's Results section, less its summary."""
    import yaml

    nav = yaml.safe_load((ROOT / "mkdocs.yml").read_text())["nav"]
    [results] = [entry["Results"] for entry in nav if isinstance(entry, dict) and "Results" in entry]
    return [page for entry in results for title, page in entry.items() if title != "Summary"]


@pytest.mark.parametrize("page", results_pages())
def test_every_results_page_opens_with_its_question_command_and_conclusion(page):
    # Before the page's first section: what was asked, how it was run (a date and a commit), what it showed.
    head = re.split(r"^## ", (DOCS / page).read_text(), maxsplit=1, flags=re.MULTILINE)[0]
    marks = [head.find(mark) for mark in ("**Question", "**Command", "**Conclusion")]
    assert -1 not in marks and marks == sorted(marks), f"{page}: the header wants **Question, **Command(s), **Conclusion, in order"
    assert re.search(r"\b20\d\d-\d\d-\d\d\b", head) and re.search(r"\bcommits? [0-9a-f]{7}", head), f"{page}: its header names no date or commit"


def test_the_results_section_is_found():
    assert "sweep-budget.md" in results_pages() and "results.md" not in results_pages()
