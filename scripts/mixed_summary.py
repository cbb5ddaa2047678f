"""The table of scripts/mixed_experiment.sh: every finished run, and each variant's mean ± std.

    python scripts/mixed_summary.py OUT [OUT ...]

Per run (OUT/<task>/<variant>/s<seed>/<job>/summary.json, or without the job directory as the
results pages keep them, e.g. docs/mixed-generation): the best training and held-out scores,
samples, each generator's share (and its island bests and time calling, where recorded), the simplified winner's lines and parameters, and the machine's
mean load average over the run (— for a run from before colmo recorded it). Then per task,
each variant against mutation alone: the difference of means with its bootstrap interval
(`colmo.comparison.difference`), training and held-out.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

from colmo.comparison import difference, mean_std

BASELINE = "mutate"  # the variant every other is compared with


def _score(value: float | None) -> str:
    return "—" if value is None else f"{value:.1f}"


def _generator(name: str, entry: dict, seconds: float) -> str:
    """One generator's part of a run: samples, programs evaluated, best score, and where the run
    recorded them (colmo since search.model_share) its island bests and the share of the run's
    time it spent generating, where that is more than 5%."""
    parts = [f"{entry['programs_evaluated']} evaluated", f"best {_score(entry['best_score'])}"]
    if "island_bests" in entry:
        parts.append(f"{entry['island_bests']} island best{'' if entry['island_bests'] == 1 else 's'}")
        if entry["generation_seconds"] > 0.05 * seconds:
            parts.append(f"calling {entry['generation_seconds'] / seconds:.0%} of the time")
    return f"{name} {entry['samples']} ({', '.join(parts)})"


def row(path: Path) -> dict:
    summary = json.loads(path.read_text())
    at = max(i for i, part in enumerate(path.parts) if re.fullmatch(r"s\d+", part))  # the seed's directory
    task, variant, seed = path.parts[at - 2], path.parts[at - 1], path.parts[at]
    simplified = summary.get("simplified") or {}
    split = ", ".join(_generator(name, entry, summary["seconds"]) for name, entry in summary.get("by_generator", {}).items())
    return {
        "task": task,
        "variant": variant,
        "seed": seed,
        "best": summary["best_score"],
        "heldout": summary["best_heldout_score"],
        "samples": summary["samples"],
        "split": split,
        "lines": simplified.get("lines"),
        "params": simplified.get("n_params"),
        "seconds": summary["seconds"],
        "load": "—" if summary.get("load") is None else f"{summary['load']:.1f}",
        "stop": summary["stop_reason"],
    }


def main(outs: list[Path]) -> None:
    paths = sorted(path for out in outs for pattern in ("*/*/s*/summary.json", "*/*/s*/*/summary.json") for path in out.glob(pattern))
    # A run stopped before its 30 minutes (Ctrl-C, a killed session) is resumed, not reported.
    rows = [r for r in map(row, paths) if r["stop"] in ("max_seconds", "max_samples")]
    print("| task | variant | seed | best | held-out | samples | by generator | simplified lines | parameters | seconds | load |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        heldout = "-" if r["heldout"] is None else f"{r['heldout']:.1f}"
        print(
            f"| {r['task']} | {r['variant']} | {r['seed']} | {r['best']:.1f} | {heldout} | {r['samples']} | {r['split']} "
            f"| {r['lines']} | {r['params']} | {r['seconds']:.0f} | {r['load']} |"
        )
    print()
    print("| task | variant | seeds | best, mean ± std | held-out, mean ± std |")
    print("|---|---|---|---|---|")
    for key in sorted({(r["task"], r["variant"]) for r in rows}):
        group = [r for r in rows if (r["task"], r["variant"]) == key]
        best = [r["best"] for r in group]
        heldout = [r["heldout"] for r in group if r["heldout"] is not None]
        print(f"| {key[0]} | {key[1]} | {len(group)} | {mean_std(best)} | {mean_std(heldout) if heldout else '-'} |")
    print()
    print("| task | variant − mutate | seeds | best | held-out |")
    print("|---|---|---|---|---|")
    for task, variant in sorted({(r["task"], r["variant"]) for r in rows if r["variant"] != BASELINE}):
        mine = [r for r in rows if (r["task"], r["variant"]) == (task, variant)]
        theirs = [r for r in rows if (r["task"], r["variant"]) == (task, BASELINE)]
        if not theirs:
            continue
        best = difference([r["best"] for r in theirs], [r["best"] for r in mine])
        heldout = difference([r["heldout"] for r in theirs if r["heldout"] is not None], [r["heldout"] for r in mine if r["heldout"] is not None])
        print(f"| {task} | {variant} | {len(mine)} vs {len(theirs)} | {best.text()} | {heldout.text()} |")


if __name__ == "__main__":
    main([Path(arg) for arg in sys.argv[1:]])
