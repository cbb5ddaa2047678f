"""MkDocs hook: reference pages quote colmo's own `--help`, run at build time, never written twice.

A page line `<!-- help: COMMAND [OVERRIDES ...] -->` becomes the text of `COMMAND OVERRIDES --help`
(the console script installed beside this Python); `<!-- help: COMMAND OVERRIDES | SECTION -->`
keeps only the section that starts with the line ` SECTION:` (e.g. `llm=llamacpp`). A command
that fails stops the build.
"""

from __future__ import annotations

import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from mkdocs.exceptions import PluginError

MARKER = re.compile(r"^<!-- help: (?P<command>[^|]+?)(?: \| (?P<section>\S+))? -->$", re.MULTILINE)


def help_text(command: str, section: str | None) -> str:
    program, *overrides = command.split()
    run = subprocess.run(
        [str(Path(sys.executable).with_name(program)), *overrides, "--help"], capture_output=True, text=True, timeout=600, check=False
    )
    if run.returncode != 0:
        raise PluginError(f"`{command} --help` failed: {run.stderr.strip()[-500:]}")
    text = run.stdout.rstrip("\n")
    if section:
        found = re.search(rf"^ {re.escape(section)}:\n(.*?)(?=\n\n|\Z)", text, re.MULTILINE | re.DOTALL)
        if not found:
            raise PluginError(f"`{command} --help` has no section ' {section}:'")
        text = found.group(1)
    shown = f"$ {command} --help" + (f"   # the {section} section" if section else "")
    return f"```text\n{shown}\n{text}\n```"


def on_page_markdown(markdown: str, **_: object) -> str:
    markers = list(MARKER.finditer(markdown))
    with ThreadPoolExecutor(max_workers=2) as pool:
        texts = list(pool.map(lambda marker: help_text(marker["command"].strip(), marker["section"]), markers))
    for marker, text in reversed(list(zip(markers, texts))):
        markdown = markdown[: marker.start()] + text + markdown[marker.end() :]
    return markdown
