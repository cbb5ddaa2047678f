"""How many stored programs hold a comparison their code decides (`colmo.bounds`), per run:
`python scripts/decided_comparisons.py TASK DIR...` reads every `programs.csv.gz` under each DIR
(as `scripts/export_programs.py` writes them) and prints, per file, the evaluated programs, how
many decide at least one comparison, and the most common such comparisons."""

from __future__ import annotations

import argparse
import collections
import csv
import gzip
import sys
from pathlib import Path

from colmo.bounds import decided_comparisons
from colmo.specs import load_spec


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("task", help="the bundled spec whose OBSERVATION_BOUNDS apply, e.g. pendulum")
    parser.add_argument("dirs", nargs="+", type=Path)
    args = parser.parse_args()
    bounds = load_spec(f"{args.task}.py").observation_bounds
    csv.field_size_limit(sys.maxsize)
    total, flagged, common = 0, 0, collections.Counter()
    print("| programs file | evaluated | with a decided comparison |\n|---|---|---|")
    for path in sorted(p for d in args.dirs for p in d.rglob("programs.csv.gz")):
        with gzip.open(path, "rt") as file:
            codes = [row["code"] for row in csv.DictReader(file) if row["status"] == "evaluated" and row["code"]]
        found = [decided_comparisons(code, bounds) for code in codes]
        hits = sum(1 for decided in found if decided)
        common.update(d.text for decided in found for d in decided)
        total, flagged = total + len(codes), flagged + hits
        print(f"| {path} | {len(codes)} | {hits} |")
    print(f"| all | {total} | {flagged} ({100 * flagged / max(total, 1):.1f}%) |")
    print("\nmost common:", "; ".join(f"`{text}` {count}" for text, count in common.most_common(8)))


if __name__ == "__main__":
    main()
