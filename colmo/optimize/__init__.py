"""Gradient-free tuning of a program's constants (the paper's inner loop).

- `methods`: the registry of GFO methods behind one ask/tell interface;
- `tune`: tuning with racing, and `optimize_program`, a program's whole evaluation with its
  final score measured by the referee;
- `__main__`: `python -m colmo.optimize`, which tunes one policy file.
"""

from colmo.optimize.methods import METHODS, Method
from colmo.optimize.tune import (
    DISPLAY_DIGITS,
    CandidateEvaluator,
    ProgramResult,
    Tuning,
    optimize_program,
    round_significant,
    step_sizes,
    tune,
)

__all__ = [
    "DISPLAY_DIGITS", "METHODS", "CandidateEvaluator", "Method", "ProgramResult", "Tuning",
    "optimize_program", "round_significant", "step_sizes", "tune",
]
