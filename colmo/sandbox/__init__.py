"""Sandboxed evaluation: untrusted policy code runs only in confined processes, never in the
coordinator. Every program was written by a model and is treated as hostile. The layers,
outermost first, one module each:

- `check`: the static check of a program's AST, here before it is submitted and again in the
  worker before it is compiled;
- `process`: the coordinator's handle on a worker process: a fresh interpreter with a clean
  environment, its own session, a private temporary directory, memory and file-size limits,
  JSON replies, and a backstop timeout that kills its process group;
- `worker`: the worker itself, trusted and pre-warmed, which forks one child per evaluation,
  so that no program ever runs where another ran, and owns each evaluation's time limit;
- `confine`: what the child does to itself before it runs a program: OS-level confinement
  (an unprivileged user, a seccomp filter, no inherited descriptors, CPU and memory limits)
  that holds when a program escapes the Python level;
- `namespace`: the namespace the program runs in: allowlisted builtins, private copies of the
  modules it may import;
- `referee`: scores a program cannot forge: the trusted worker runs the simulator and the
  reward, the confined child only maps observations to actions.

Failure reasons (`colmo.errors.failure_reason`) are one printable line: `syntax error: ...`,
`forbidden: ...`, `invalid: ...`, `exception: ZeroDivisionError: ... (step 3)`, `memory: ...`,
`timeout: ...`, `cpu time: ...`, `crash: ...`, `tampering: ...`, `environment: ...` (the spec's
fault), and the evaluator's `bad action ...`, `non-finite action ...`, `unstable simulation: ...`.
"""

from colmo.sandbox.check import ForbiddenProgram, check_program, check_tree, parse_program

__all__ = ["ForbiddenProgram", "check_program", "check_tree", "parse_program"]
