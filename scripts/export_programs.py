"""A run store's programs as a compact CSV: what a results page keeps instead of the store.

    python scripts/export_programs.py RUN_DIR [RUN_DIR ...]

Writes RUN_DIR/programs.csv.gz beside RUN_DIR/programs.db: one row per sample with its status,
island, generator, scores, size, model calls, tokens, timings, failure and code (the raw model
output, the prompt and the per-episode returns stay in the store, which the run's command
regenerates).
"""

from __future__ import annotations

import csv
import gzip
import sqlite3
import sys
from pathlib import Path

COLUMNS = (
    "sample", "batch", "status", "island", "generator", "initial_score", "score", "heldout_score", "lines", "nodes",
    "n_params", "evaluations", "steps", "model_calls", "completion_tokens", "generation_seconds", "evaluation_seconds",
    "failure", "code",
)


def export(run: Path) -> Path:
    connection = sqlite3.connect(f"file:{run / 'programs.db'}?mode=ro", uri=True)
    try:
        rows = connection.execute(f"SELECT {', '.join(COLUMNS)} FROM samples ORDER BY sample").fetchall()
    finally:
        connection.close()
    out = run / "programs.csv.gz"
    with gzip.open(out, "wt", newline="") as file:
        writer = csv.writer(file)
        writer.writerow(COLUMNS)
        writer.writerows(rows)
    return out


if __name__ == "__main__":
    for argument in sys.argv[1:]:
        print(export(Path(argument)))
