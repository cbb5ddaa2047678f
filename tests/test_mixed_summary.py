"""scripts/mixed_summary.py reads finished runs' summaries and compares each variant with mutation alone."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "mixed_summary.py"


def _run(
    out: Path, variant: str, seed: int, best: float, heldout: float, stop: str = "max_seconds", job: str = "0_job", load: float | None = 2.14,
) -> None:
    job = out / "pendulum" / variant / f"s{seed}" / job
    job.mkdir(parents=True)
    summary = {
        "best_score": best,
        "best_heldout_score": heldout,
        "samples": 10,
        "seconds": 1790.0,
        "stop_reason": stop,
        "by_generator": {"mutate": {"samples": 10, "programs_evaluated": 9, "best_score": best}},
        "simplified": {"lines": 4, "n_params": 2},
    }
    if load is not None:  # summaries from before colmo recorded the load have none
        summary["load"] = load
    (job / "summary.json").write_text(json.dumps(summary))


def test_the_table_compares_each_variant_with_mutation_alone(tmp_path: Path) -> None:
    for seed, (mixed, mutate) in enumerate([(700.0, 800.0), (720.0, 810.0), (710.0, 820.0)]):
        _run(tmp_path, "mixed", seed, mixed, mixed - 10)
        _run(tmp_path, "mutate", seed, mutate, mutate - 10)
    _run(tmp_path, "mutate", 3, 100.0, 90.0, stop="interrupted")  # stopped early: resumed, not reported
    text = subprocess.run([sys.executable, str(SCRIPT), str(tmp_path)], capture_output=True, text=True, check=True).stdout
    assert "| pendulum | mutate | 3 | 810.0 ± 10.0 | 800.0 ± 10.0 |" in text
    assert "| pendulum | mixed | 3 | 710.0 ± 10.0 | 700.0 ± 10.0 |" in text
    (line,) = [line for line in text.splitlines() if line.startswith("| pendulum | mixed | 3 vs 3 |")]
    assert line.count("-100.0, 95% interval [") == 2 and "no significant" not in line


def test_runs_of_several_directories_compare_the_results_pages_layout_too(tmp_path: Path) -> None:
    runs, page = tmp_path / "runs", tmp_path / "docs"
    for seed, (new, mutate) in enumerate([(300.0, 220.0), (310.0, 230.0), (320.0, 210.0)]):
        _run(runs, "default", seed, new, new - 20)
        _run(page, "mutate", seed, mutate, mutate - 40, job="", load=None)  # docs/<page>/<task>/<variant>/s<seed>/summary.json
    text = subprocess.run([sys.executable, str(SCRIPT), str(runs), str(page)], capture_output=True, text=True, check=True).stdout
    assert "| pendulum | mutate | 3 | 220.0 ± 10.0 | 180.0 ± 10.0 |" in text
    assert "| 4 | 2 | 1790 | 2.1 |" in text and "| 4 | 2 | 1790 | — |" in text  # each run's load, where it was recorded
    (line,) = [line for line in text.splitlines() if line.startswith("| pendulum | default | 3 vs 3 |")]
    assert line.startswith("| pendulum | default | 3 vs 3 | +90.0, 95% interval [")


def test_a_run_that_recorded_island_bests_shows_them_and_the_models_time_calling(tmp_path: Path) -> None:
    _run(tmp_path, "by_yield", 0, 800.0, 790.0)
    summary_path = tmp_path / "pendulum" / "by_yield" / "s0" / "0_job" / "summary.json"
    summary = json.loads(summary_path.read_text())
    summary["by_generator"] = {
        "mutate": {"samples": 400, "programs_evaluated": 390, "best_score": 800.0, "island_bests": 80, "generation_seconds": 15.0,
                   "evaluation_seconds": 3000.0},
        "llamacpp": {"samples": 12, "programs_evaluated": 5, "best_score": 500.0, "island_bests": 1, "generation_seconds": 358.0,
                     "evaluation_seconds": 90.0},
    }
    summary_path.write_text(json.dumps(summary))
    text = subprocess.run([sys.executable, str(SCRIPT), str(tmp_path)], capture_output=True, text=True, check=True).stdout
    assert "mutate 400 (390 evaluated, best 800.0, 80 island bests), llamacpp 12 (5 evaluated, best 500.0, 1 island best, calling 20% of the time)" in text
