"""scripts/tune_published.py's summary: the published policy as written on each seed, then each
GFO method's tuned scores over the seeds that finished (a failed run is not counted)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "tune_published.py"


def _result(out: Path, method: str, seed: int, **fields) -> None:
    directory = out / "cheetah" / method / f"seed_{seed}"
    directory.mkdir(parents=True)
    (directory / "result.json").write_text(json.dumps({"failure": None, **fields}))


def _tuned(out: Path, method: str, seed: int, initial: float, score: float, heldout: float) -> None:
    _result(out, method, seed, score_initial=initial, score=score, heldout_score=heldout, evaluations=1002, seconds=100.0)


def test_the_summary_shows_the_published_policy_per_seed_then_each_method(tmp_path):
    _result(tmp_path, "published", 1, score=201.2)
    _result(tmp_path, "published", 2, score=197.6)
    _tuned(tmp_path, "cma", 1, 210.0, 210.0, 201.2)
    _tuned(tmp_path, "cma", 2, 170.8, 259.1, 240.8)
    _tuned(tmp_path, "de", 1, 210.0, 257.3, 246.9)
    _result(tmp_path, "de", 2, failure="timed out")  # not a result
    made = subprocess.run([sys.executable, str(SCRIPT), str(tmp_path), "--summary"], capture_output=True, text=True, timeout=120)
    assert made.returncode == 0, made.stderr
    rows = [[cell.strip() for cell in line.strip("|").split("|")] for line in made.stdout.splitlines()[2:]]
    assert rows == [
        ["cheetah", "published, as written", "1, 2", "210.0, 170.8", "201.2, 197.6", "199.4 ± 2.5", "", ""],
        ["cheetah", "tuned by `cma`", "1, 2", "210.0, 259.1", "201.2, 240.8", "221.0 ± 28.0", "1002", "100"],
        ["cheetah", "tuned by `de`", "1", "257.3", "246.9", "246.9", "1002", "100"],
    ]
