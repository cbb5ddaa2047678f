"""The end of a `-m` sweep: a real two-job sweep prints one line per job with the scores its
summary holds, and a report command that selects exactly that sweep; a job that wrote no
summary is a line saying so."""

import json
import subprocess
import sys
from pathlib import Path

from conftest import run_colmo
from mlflow import MlflowClient

from colmo.sweep_comparison import JobOutcome, comparison_lines

TINY = ("llm=mutate", "search.max_samples=2", "gfo.budget=2", "task.episodes=1", "evaluation.episodes=2", "evaluation.render=false",
        "evaluation.simplify=false", "executor.workers=1", "search.progress=false")


def test_a_sweep_ends_with_one_line_per_job_and_the_command_of_its_report(tmp_path):
    result = run_colmo("colmo", "-m", "seed=0,1", *TINY, "hydra.sweep.dir=sweep", cwd=tmp_path, timeout=600)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    start = lines.index("sweep sweep: 2 jobs")
    heading, *rows = lines[start + 1: start + 4]
    assert heading.split() == ["job", "variant", "best", "held-out", "samples"]
    for number, row in enumerate(rows):
        summary = json.loads(next((tmp_path / "sweep").glob(f"{number}_*/summary.json")).read_text())
        assert row.split() == [
            str(number), f"seed={number}", f"{summary['best_score']:.2f}", f"{summary['best_heldout_score']:.2f}", str(summary["samples"]),
        ]
    report = lines[start + 4]
    assert report.startswith("report: colmo-report experiment=pendulum sweep=")
    client = MlflowClient(f"sqlite:///{tmp_path / 'mlruns.db'}")
    experiment = client.get_experiment_by_name("pendulum").experiment_id
    parents = [run for run in client.search_runs([experiment]) if "colmo.sweep" in run.data.tags]
    assert [parent.data.tags["colmo.sweep"] for parent in parents] == [report.rsplit("sweep=", 1)[1]]
    # An unrelated run beside the sweep: the printed command still compares exactly its 2 jobs.
    assert run_colmo("colmo", *TINY, "seed=2", cwd=tmp_path, timeout=600).returncode == 0
    out = tmp_path / "report"
    command = [sys.executable, "-m", "colmo.report", *report.split()[2:], f"out={out}"]
    made = subprocess.run(command, cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert made.returncode == 0, made.stderr
    text = (out / "report.md").read_text()
    assert "2 search runs read from MLflow" in text and "; 2 count, 0 left out" in text


def test_a_job_without_a_summary_is_a_line_saying_so():
    jobs = [
        JobOutcome(0, ("task=pendulum", "seed=0"), {"best_score": 180.0, "best_heldout_score": None, "samples": 4}, None, "pendulum"),
        JobOutcome(1, ("task=pendulum", "seed=1"), None, None, "pendulum"),
    ]
    lines = comparison_lines(Path("/runs/sweep"), jobs)
    assert lines[0] == "sweep /runs/sweep: 2 jobs"
    assert lines[2].split() == ["0", "seed=0", "180.00", "-", "4"]
    assert lines[3].split()[:3] == ["1", "seed=1", "no"]
    assert len(lines) == 4  # no tracked job: no report line
