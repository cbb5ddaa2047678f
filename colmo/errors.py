"""Errors and the one-line texts made from them: what a user is told, and what is stored.

- `ConfigError`: a user error in configuration or input (a bad override, a missing file, a
  broken spec). Entry points print it as one line, `colmo: error: ...`, and exit with
  `EXIT_USAGE` (2); `colmo.cli` does this for every Hydra app.
- `RunError`: the run could not go on for a reason outside the user's input (a disk that is
  full, a generator that stopped answering); one line, exit `EXIT_RUNTIME` (1).
- A Ctrl-C that an app does not turn into a clean stop: `colmo: interrupted`, exit
  `EXIT_INTERRUPTED` (130).
- `one_line(error)`: the first line of an error, with its cause when that says more.
- `failure_reason(text)`: a program's failure reason as stored and logged: one line of
  printable characters, at most `MAX_REASON_CHARS` (programs choose their own exception
  messages; they must not inject lines or terminal escapes into logs).
"""

from __future__ import annotations

EXIT_RUNTIME = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130  # 128 + SIGINT, as a shell reports a command Ctrl-C ended
MAX_REASON_CHARS = 500


class ConfigError(ValueError):
    """A user error in configuration or input; the message is one line naming problem and fix."""


class RunError(RuntimeError):
    """The run cannot go on (not the user's input); the message is one line."""


def one_line(error: BaseException) -> str:
    """The first line of an error, with the first line of its cause when that says more."""
    first = (str(error).strip().splitlines() or [type(error).__name__])[0]
    options = getattr(error, "options", None)  # Hydra's MissingConfigException knows the choices
    if options:
        choices = [o for o in options if not o.endswith("schema")]
        return f"{first}; available: {', '.join(choices)}"
    cause = error.__cause__
    if cause is not None and str(cause).strip():
        detail = str(cause).strip().splitlines()[0]
        if detail not in first:
            return f"{first.rstrip('.')}: {detail}"
    return first


def failure_reason(text: str) -> str:
    """A failure reason as stored and logged: bounded, one line, printable."""
    return "".join(c if c.isprintable() else " " for c in text[:MAX_REASON_CHARS])


def describe_exception(error: BaseException, where: str = "") -> str:
    """The failure reason for an exception raised by a program (`where`: e.g. " (step 3)")."""
    if isinstance(error, MemoryError):
        return failure_reason(f"memory: {_message(error) or 'out of memory'}{where}")
    return failure_reason(f"exception: {type(error).__name__}: {_message(error)}{where}")


def _message(error: BaseException) -> str:
    """`str(error)`, which a program can make fail (`ValueError(10 ** 5000)`: too many digits to
    print); then a message saying so, not a crash of the process describing it."""
    try:
        return str(error)
    except Exception as unprintable:
        return f"(its message cannot be printed: {type(unprintable).__name__})"
