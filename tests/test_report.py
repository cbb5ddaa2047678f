"""`python -m colmo.report` on a real tiny sweep: Table I, the runs, the best policies, the figure."""

import json
import statistics
import subprocess
import sys

import pytest
from PIL import Image

from colmo.report import main, mean_std


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    """gfo=none,oneplusone × seeds 0,1 on pendulum, tiny, then the report of that experiment."""
    cwd = tmp_path_factory.mktemp("report")
    sweep = subprocess.run(
        [sys.executable, "-m", "colmo", "-m", "gfo=none,oneplusone", "seed=0,1", "gfo.budget=3", "search.max_samples=8",
         "task.episodes=2", "llm.batch_size=4", "executor.workers=1", "search.progress=false", f"hydra.sweep.dir={cwd / 'multirun'}"],
        cwd=cwd, capture_output=True, text=True, timeout=300,
    )
    assert sweep.returncode == 0, sweep.stderr
    result = subprocess.run(
        [sys.executable, "-m", "colmo.report", "experiment=pendulum", "out=out"], cwd=cwd, capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "out/report.md"
    summaries = {}
    for run_dir in (path.parent for path in (cwd / "multirun").glob("*/summary.json")):
        overrides = (run_dir / ".hydra" / "overrides.yaml").read_text()
        summaries[("none" if "gfo=none" in overrides else "oneplusone", "seed=1" in overrides)] = (
            json.loads((run_dir / "summary.json").read_text()), run_dir
        )
    assert len(summaries) == 4
    return cwd / "out", summaries


def table(markdown: str, heading: str) -> list[list[str]]:
    """The cells of the first table under `## heading`, header row included."""
    section = markdown.split(f"## {heading}\n", 1)[1]
    end = next((i for i, line in enumerate(section.splitlines()) if line.startswith("## ")), None)
    rows = [line for line in section.splitlines()[:end] if line.startswith("|")]
    return [[cell.strip() for cell in row.strip("|").split("|")] for row in rows if not row.startswith("|---")]


def test_table_one_has_the_paper_columns_and_seed_statistics(report):
    out, summaries = report
    rows = table((out / "report.md").read_text(), "Table I")
    assert rows[0] == ["Task", "State dim", "Action dim", "GFO", "Reward, no GFO", "Reward, GFO", "Target",
                       "Samples to target, no GFO", "Samples to target, GFO"]
    assert len(rows) == 2  # one task, one GFO variant
    row = rows[1]
    assert row[:4] == ["pendulum", "3", "1", "oneplusone, budget 3"] and row[6] == "400"
    for cell, method in ((row[4], "none"), (row[5], "oneplusone")):
        scores = [summaries[(method, seed)][0]["best_score"] for seed in (False, True)]
        assert cell.strip("*") == f"{statistics.mean(scores):.1f} ± {statistics.stdev(scores):.1f}"
    assert all(cell == "—" or "seeds)" in cell for cell in row[7:])


def test_runs_and_best_policies_come_from_the_tracked_runs(report):
    out, summaries = report
    markdown = (out / "report.md").read_text()
    runs = table(markdown, "Runs")
    assert len(runs) == 5 and {r[0] for r in runs[1:]} == {
        f"pendulum-{m}-mutate-s{s}" for m in ("none", "oneplusone") for s in (0, 1)
    }
    for method, heading in (("none", "pendulum, no GFO"), ("oneplusone", "pendulum, oneplusone, budget 3")):
        best_summary, run_dir = max((summaries[(method, seed)] for seed in (False, True)), key=lambda s: s[0]["best_score"])
        section = markdown.split(f"### {heading}\n", 1)[1]
        code = section.split("```python\n", 1)[1].split("```", 1)[0]
        assert code.strip() == (run_dir / "best_policy.py").read_text().strip()


def test_figure_is_a_readable_png(report):
    out, _ = report
    path = out / "best_so_far.png"
    with Image.open(path) as image:
        width, height = image.size
        assert image.format == "PNG"
    assert 600 <= width <= 3000 and 400 <= height <= 2000
    assert path.stat().st_size > 10_000  # curves, labels and legend, not an empty canvas


def test_bad_command_lines_fail_in_one_line(report, tmp_path, monkeypatch, capsys):
    out, _ = report
    for cwd, args, message in (
        (out.parent, ["experiment=nope"], "no MLflow experiment named 'nope'"),
        (tmp_path, ["experiment=pendulum"], "no tracking database"),
        (tmp_path, ["out=x"], "experiment=NAME is required"),
        (tmp_path, ["colour=red"], "expected one of experiment=..."),
    ):
        monkeypatch.chdir(cwd)
        with pytest.raises(SystemExit) as exit:
            main(args)
        assert exit.value.code == 2 and message in capsys.readouterr().err


def test_mean_std_is_the_sample_std_and_a_lone_mean():
    assert mean_std([1.0, 3.0]) == "2.0 ± 1.4"
    assert mean_std([591.0]) == "591.0"
    assert mean_std([12, 20], 0) == "16 ± 6"
