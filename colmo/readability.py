"""The readability report of a search's best policy: what a person reading it should know at once.

Beside its scores: the policy's size (lines, parameters, AST nodes) as the search found it and
as the simplifier left it; its branches (`if`, `while` and conditional expressions) and how many
were never taken or always taken over the training and held-out episodes (`colmo.coverage`);
its clips that returned a limit for every value (constants in disguise); its divisions whose
divisor was 0 for some value (a term that is inf or nan there); its variables whose names
contradict the task's (`colmo.names`); its comparisons whose outcome the code fixes, read from
the code (`colmo.bounds`); and what the simplifier removed, step by step. `report` makes it from
what the finish measured; it is `summary.json`'s `readability`, logged to MLflow as
`readability_*` metrics and shown per run by `colmo-report`.
"""

from __future__ import annotations

from typing import Any, Optional, Sequence

from colmo.coverage import CONDITION_KINDS
from colmo.program import measure

# The report's numbers, as the metrics a tracker logs (`readability_<name>`) and colmo-report reads.
METRICS = (
    "lines", "parameters", "branches", "branches_never_taken", "clips_at_a_limit", "divisions_by_zero", "misleading_names",
    "comparisons_decided",
    "simplified_lines", "simplified_parameters",
)


def report(
    code: str, coverage: dict[str, Any], simplified: dict[str, Any], misnamed: Sequence[str], decided: Sequence[str] = (),
) -> dict[str, Any]:
    """The readability report of `code` (the best policy) from the finish's `coverage`
    (`colmo.coverage.summary`, {} if not counted), `simplified` (`SimplifyResult.to_json`, {} if
    not simplified), `misnamed` (`colmo.names.misnamed`) and `decided` (`colmo.bounds`, read from the
    code: always counted). Counts that were not measured are None."""
    size = measure(code)
    sites = coverage.get("sites")
    conditions = [site["counts"] for site in sites or () if site["kind"] in CONDITION_KINDS]
    clips = [site["counts"] for site in sites or () if site["kind"] == "clip"]
    divisions = [site["counts"] for site in sites or () if site["kind"] == "division"]
    done = "score" in simplified  # a failed simplification says only why
    return {
        "lines": size.lines, "parameters": size.params, "nodes": size.nodes,
        "branches": len(conditions) if sites is not None else None,
        "branches_never_taken": sum(1 for tests, true, _ in conditions if tests and true in (0, tests)) if sites is not None else None,
        "clips_at_a_limit": sum(1 for values, raised, lowered in clips if values and raised + lowered == values) if sites is not None else None,
        "divisions_by_zero": sum(1 for _, zero, _ in divisions if zero) if sites is not None else None,
        "misleading_names": len(misnamed),
        "comparisons_decided": len(decided),
        "simplified_lines": simplified.get("lines") if done else None,
        "simplified_parameters": simplified.get("n_params") if done else None,
        "removed": [step["description"] for step in simplified.get("steps", ())] if done else [],
    }


def describe(readability: dict[str, Any]) -> Optional[str]:
    """The report in one line for the log, or None if there is none."""
    if not readability:
        return None
    parts = [f"{readability['lines']} lines, {readability['parameters']} parameters"]
    if readability["branches"] is not None:
        parts.append(f"{readability['branches_never_taken']} of {readability['branches']} branches decided the same way at every test")
        if readability["clips_at_a_limit"]:
            parts.append(f"{readability['clips_at_a_limit']} clip(s) returning a limit for every value")
        if readability.get("divisions_by_zero"):  # a report from before divisions were counted has none
            parts.append(f"{readability['divisions_by_zero']} division(s) by zero")
    parts.append(f"{readability['misleading_names']} misleading name(s)")
    if readability.get("comparisons_decided"):  # a report from before they were read has none
        parts.append(f"{readability['comparisons_decided']} comparison(s) the code decides")
    if readability["simplified_lines"] is not None:
        parts.append(f"simplified: {readability['simplified_lines']} lines, {readability['simplified_parameters']} parameters")
    return "; ".join(parts)
