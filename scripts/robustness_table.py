"""A markdown table of robustness reports (robustness.json of `colmo-evaluate robustness=true`).

    python scripts/robustness_table.py RUN_DIR [RUN_DIR ...]

One row per report: the nominal score, every factor together at 10, 20 and 40 %, the factor
that costs most at 20 %, and a delay of 2 steps; each score ± its 95% interval, and for a
perturbed point its change from nominal ± its paired interval.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path


def cell(report: dict, block: str, index: int, key: str) -> str:
    score, interval = report[block][index][key], report[f"{block}_interval"][index][key]
    text = "failed" if score is None else f"{score:.1f} ± {interval:.1f}"
    if index and score is not None:
        change, paired = report[f"{block}_change"][index][key], report[f"{block}_change_interval"][index][key]
        text += f" ({change:+.1f} ± {paired:.1f})"
    return text


def row(run: Path) -> str:
    report = json.loads((run / "robustness.json").read_text())
    magnitudes = [entry["magnitude"] for entry in report["robustness"]]
    at = {m: i for i, m in enumerate(magnitudes)}
    twenty = report["robustness_change"][at[0.2]]
    worst = min((k for k in twenty if k not in ("magnitude", "all")), key=lambda k: twenty[k])
    delays = [entry["delay_steps"] for entry in report["delay"]]
    cells = [cell(report, "robustness", 0, "all")] + [cell(report, "robustness", at[m], "all") for m in (0.1, 0.2, 0.4)]
    cells += [f"{worst}: {cell(report, 'robustness', at[0.2], worst)}", cell(report, "delay", delays.index(2), "score")]
    return f"| {run.name} | " + " | ".join(cells) + " |"


if __name__ == "__main__":
    print("| policy | nominal | all 10 % | all 20 % | all 40 % | costliest factor at 20 % | delay 2 steps |")
    print("|---|---|---|---|---|---|---|")
    for argument in sys.argv[1:]:
        print(row(Path(argument)))
