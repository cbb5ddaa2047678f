"""The commands colmo prints for a person to paste (a resume hint, the simplifier on a run's best
policy): each `key=value` written so that the shell and then Hydra's override parser read back
the value as it was (a sweep job's directory holds `=` and `,`, which Hydra reads as syntax)."""

from __future__ import annotations

import re
import shlex

_PLAIN = re.compile(r"[\w/.\-:+@%]+")  # a value Hydra's grammar and a shell both take as it is


def shell_override(key: str, value: object) -> str:
    """`key=value` as a command line to paste into a shell: a value Hydra would read as
    something else (a sweep job's directory holds `=` and `,`) quoted for Hydra, and that
    quoted for the shell."""
    text = str(value)
    if _PLAIN.fullmatch(text):
        return f"{key}={text}"
    override = f"{key}='" + text.replace("'", "\\'") + "'"
    return f'"{override}"' if not set(override) & set('"$`\\!') else shlex.quote(override)
