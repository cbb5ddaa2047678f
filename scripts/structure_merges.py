"""How many evaluated programs of stored GFO runs are one structure under the canonical key.

Reads every `programs.csv.gz` under the given directories (the runs' exports, `gfo-none` runs
left out: they tell programs apart by their constants), keeps each run's evaluated programs with
a skeleton of their own, and counts those whose structure key (`colmo.canonical`) an earlier one
of the same run already had: the programs a search would now skip as duplicates. One table row
per experiment (the path before `/runs/`, else the first three parts).

    python scripts/structure_merges.py docs
"""

from __future__ import annotations

import collections
import csv
import gzip
import sys
from pathlib import Path

from colmo.program import ProgramError, parametrize

csv.field_size_limit(sys.maxsize)


def run_counts(path: Path) -> tuple[int, int]:
    """(evaluated programs with a skeleton of their own, those whose key an earlier one had)."""
    skeletons, keys, merged = set(), set(), 0
    with gzip.open(path, "rt") as lines:
        for row in csv.DictReader(lines):
            if row["status"] != "evaluated":
                continue
            try:
                program = parametrize(row["code"])
            except ProgramError:
                continue
            if program.skeleton in skeletons:
                continue
            skeletons.add(program.skeleton)
            merged += program.key in keys
            keys.add(program.key)
    return len(skeletons), merged


def main(roots: list[str]) -> None:
    totals: dict[str, list[int]] = collections.defaultdict(lambda: [0, 0, 0])
    for root in roots:
        for path in sorted(Path(root).rglob("programs.csv.gz")):
            if "gfo-none" in path.parts:
                continue
            text = path.as_posix()
            experiment = text.split("/runs/")[0] if "/runs/" in text else "/".join(path.parts[:3])
            evaluated, merged = run_counts(path)
            totals[experiment][0] += 1
            totals[experiment][1] += evaluated
            totals[experiment][2] += merged
    print("| experiment | runs | evaluated structures | one structure with an earlier one | share |")
    print("|---|---|---|---|---|")
    for experiment, (runs, evaluated, merged) in totals.items():
        print(f"| {experiment} | {runs} | {evaluated} | {merged} | {100 * merged / max(evaluated, 1):.1f}% |")


if __name__ == "__main__":
    main(sys.argv[1:] or ["docs"])
