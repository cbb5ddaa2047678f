"""The end of a `-m` sweep: a real two-job sweep prints one line per job with the scores its
summary holds, and a report command that selects exactly that sweep; a job with no result (no
summary, no program evaluated) is a line saying so, never a score, and the sweep exits 1 after
running every other job."""

import json
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import run_colmo
from mlflow import MlflowClient

from colmo.sweep_comparison import JobOutcome, comparison_lines, failure_line

TINY = ("llm=mutate", "search.max_samples=2", "gfo.budget=2", "task.episodes=1", "heldout.episodes=2", "finish.render=false",
        "finish.simplify=false", "executor.workers=1", "search.progress=false")


def test_a_sweep_ends_with_one_line_per_job_and_the_command_of_its_report(tmp_path):
    result = run_colmo("colmo", "-m", "seed=0,1", *TINY, "hydra.sweep.dir=sweep", cwd=tmp_path, timeout=600)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    start = lines.index("sweep sweep: 2 jobs")
    heading, *rows = lines[start + 1: start + 4]
    assert heading.split() == ["job", "variant", "best", "held-out", "samples", "seconds", "searched"]
    for number, row in enumerate(rows):
        summary = json.loads(next((tmp_path / "sweep").glob(f"{number}_*/summary.json")).read_text())
        assert row.split() == [
            str(number), f"seed={number}", f"{summary['best_score']:.2f}", f"{summary['best_heldout_score']:.2f}", str(summary["samples"]),
            f"{summary['seconds']:.1f}", f"{summary['search_seconds']:.1f}",
        ]
    report = lines[start + 4]
    assert report.startswith("report: colmo-report experiment=pendulum sweep=")
    client = MlflowClient(f"sqlite:///{tmp_path / 'mlruns.db'}")
    experiment = client.get_experiment_by_name("pendulum").experiment_id
    parents = [run for run in client.search_runs([experiment]) if "colmo.sweep" in run.data.tags]
    assert [parent.data.tags["colmo.sweep"] for parent in parents] == [report.rsplit("sweep=", 1)[1]]
    children = [run for run in client.search_runs([experiment]) if "colmo.sweep" not in run.data.tags]
    assert [child.data.tags["colmo.stop_reason"] for child in children] == ["max_samples"] * 2  # which limit each reached
    recorded = Path(client.download_artifacts(parents[0].info.run_id, "comparison.txt", str(tmp_path)))
    assert recorded.read_text().splitlines() == lines[start: start + 5]  # the table the sweep printed, in its parent run
    # ... and the sweep's report, as its report line would write it: Table I and the figures.
    artifacts = {artifact.path for artifact in client.list_artifacts(parents[0].info.run_id, "report")}
    assert {"report/report.md", "report/best_so_far.png", "report/best_so_far_seconds.png"} <= artifacts, artifacts
    parent_report = Path(client.download_artifacts(parents[0].info.run_id, "report/report.md", str(tmp_path))).read_text()
    assert "## Table I" in parent_report and "2 search runs read from MLflow" in parent_report
    assert f"`{report.removeprefix('report: ')}`" in parent_report
    # An unrelated run beside the sweep: the printed command still compares exactly its 2 jobs.
    assert run_colmo("colmo", *TINY, "seed=2", cwd=tmp_path, timeout=600).returncode == 0
    out = tmp_path / "report"
    command = [sys.executable, "-m", "colmo.report", *report.split()[2:], f"out={out}"]
    made = subprocess.run(command, cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert made.returncode == 0, made.stderr
    text = (out / "report.md").read_text()
    assert "2 search runs read from MLflow" in text and "; 2 count, 0 left out" in text


def summary(**fields) -> dict:
    return {"best_score": 180.0, "best_heldout_score": None, "samples": 4, "programs_evaluated": 3, "stop_reason": "max_samples",
            "seconds": 12.25, "search_seconds": 8.0, **fields}


def test_a_job_without_a_result_is_a_line_saying_why_never_a_score():
    jobs = [
        JobOutcome(0, ("task=pendulum", "seed=0"), summary(), None, "pendulum"),
        JobOutcome(1, ("task=pendulum", "seed=1"), None, None, "pendulum"),
        JobOutcome(2, ("task=pendulum", "seed=2"), summary(samples=0, programs_evaluated=0, stop_reason="max_seconds"), None, "pendulum"),
        JobOutcome(3, ("task=pendulum", "seed=3"), summary(samples=6, programs_evaluated=0), None, "pendulum"),
        JobOutcome(4, ("task=pendulum", "seed=4"), summary(stop_reason="generator failed: the server stopped"), None, "pendulum"),
    ]
    lines = comparison_lines(Path("/runs/sweep"), jobs)
    assert lines[0] == "sweep /runs/sweep: 5 jobs"
    assert lines[2].split() == ["0", "seed=0", "180.00", "-", "4", "12.2", "8.0"]
    assert lines[3].split()[:4] == ["1", "seed=1", "failed:", "no"]
    words = [" ".join(line.split()) for line in lines]
    assert words[4] == "2 seed=2 failed: no sample searched: search.max_seconds left no time after the start-up"
    assert words[5] == "3 seed=3 failed: no program evaluated in 6 samples"
    assert words[6] == "4 seed=4 failed: stopped: generator failed: the server stopped"
    assert "180.00" not in " ".join(lines[3:])
    assert len(lines) == 7  # no tracked job: no report line
    assert failure_line(jobs) == "colmo: error: 4 of 5 jobs failed (jobs 1, 2, 3, 4): no result to compare"
    assert failure_line(jobs[:1]) is None
    (row,) = comparison_lines(Path("/runs/sweep"), jobs[:1])[2:]  # one job: its own settings, not "(all alike)"
    assert row.split()[:3] == ["0", "task=pendulum", "seed=0"]


def test_a_sweep_with_a_job_that_searched_nothing_runs_the_others_and_exits_1(tmp_path):
    # A 1 s limit leaves no time to search after the start-up; the other job has no time limit.
    result = run_colmo("colmo", "-m", "search.max_seconds=1,0", *TINY, "tracker=none", "hydra.sweep.dir=sweep", cwd=tmp_path, timeout=600)
    assert result.returncode == 1, result.stderr
    assert result.stderr.strip().splitlines()[-1] == "colmo: error: 1 of 2 jobs failed (job 0): no result to compare"
    lines = result.stdout.splitlines()
    rows = lines[lines.index("sweep sweep: 2 jobs") + 2:][:2]
    assert " ".join(rows[0].split()).startswith("0 search.max_seconds=1 failed: no sample searched")
    finished = json.loads(next((tmp_path / "sweep").glob("1_*/summary.json")).read_text())
    assert finished["samples"] == 2 and finished["programs_evaluated"] > 0
    assert rows[1].split()[:3] == ["1", "search.max_seconds=0", f"{finished['best_score']:.2f}"]


def test_settings_compared_over_seeds_get_their_mean_and_the_difference_with_its_interval():
    scores = {("gfo=none", 0): 187.4, ("gfo=none", 1): 196.5, ("gfo=none", 2): 176.4,
              ("gfo=oneplusone", 0): 392.5, ("gfo=oneplusone", 1): 221.6, ("gfo=oneplusone", 2): 502.2}
    jobs = [JobOutcome(number, (gfo, f"seed={seed}"), summary(best_score=score), None, "pendulum")
            for number, ((gfo, seed), score) in enumerate(scores.items())]
    jobs.append(JobOutcome(6, ("gfo=oneplusone", "seed=3"), summary(programs_evaluated=0), None, "pendulum"))  # no result: not counted
    lines = comparison_lines(Path("/runs/sweep"), jobs)
    start = next(i for i, line in enumerate(lines) if line.strip().startswith("best score by setting"))
    none, tuned = (" ".join(line.split()) for line in lines[start + 1: start + 3])
    assert none == "gfo=none 186.77 ± 10.06 (187.40, 196.50, 176.40)"
    assert tuned.startswith("gfo=oneplusone 372.10 ± 141.41 (392.50, 221.60, 502.20) +185.33, 95% interval [+")
    assert "no significant" not in tuned
    close = [JobOutcome(n, (gfo, f"seed={n}"), summary(best_score=score), None, "pendulum")
             for n, (gfo, score) in enumerate((("gfo=none", 201.3), ("gfo=none", 180.0), ("gfo=oneplusone", 222.8), ("gfo=oneplusone", 190.0)))]
    assert comparison_lines(Path("/runs/sweep"), close)[-1].endswith(": no significant difference")
    assert not any("by setting" in line for line in comparison_lines(Path("/runs/sweep"), jobs[:3]))  # seeds only: nothing to compare


def provenance(commit: str = "a" * 40, changed: bool = False, nevergrad: str = "1.0.12", cpus: int = 2) -> dict:
    return {"colmo": "0.1.0", "commit": commit, "uncommitted_changes": changed, "python": "3.11.7", "cpus": cpus,
            "libraries": {"numpy": "2.4.6", "nevergrad": nevergrad}}


def test_jobs_run_on_different_code_or_libraries_are_named_with_what_differed():
    def job(number: int, record, **fields) -> JobOutcome:
        return JobOutcome(number, (f"seed={number}",), summary(provenance=record, **fields) if record != "none" else summary(), None, "pendulum")

    alike = [job(0, provenance()), job(1, provenance())]
    assert not any("different code" in line for line in comparison_lines(Path("/runs/sweep"), alike))
    # A sweep resumed after an upgrade: job 2 ran later code, with changes, and another nevergrad;
    # job 3 was written before colmo recorded provenance; job 4 has no result, so it is not compared.
    jobs = [*alike, job(2, provenance("b" * 40, changed=True, nevergrad="1.0.13")), job(3, "none"),
            job(4, provenance("c" * 40, cpus=64), programs_evaluated=0)]
    lines = comparison_lines(Path("/runs/sweep"), jobs)
    start = lines.index("  the jobs ran on different code or libraries (scores may differ for that alone):")
    assert lines[start + 1:] == [
        "    code: aaaaaaaaaaaa (jobs 0, 1), bbbbbbbbbbbb with uncommitted changes (job 2), not recorded (job 3)",
        "    python: 3.11.7 (jobs 0, 1, 2), not recorded (job 3)",
        "    cpus: 2 (jobs 0, 1, 2), not recorded (job 3)",
        "    numpy: 2.4.6 (jobs 0, 1, 2), not recorded (job 3)",
        "    nevergrad: 1.0.12 (jobs 0, 1), 1.0.13 (job 2), not recorded (job 3)",
    ]
    installed = [job(0, provenance()), job(1, {**provenance(), "commit": None, "libraries": {"numpy": "2.4.6"}})]
    assert comparison_lines(Path("/runs/sweep"), installed)[-2:] == [
        "    code: aaaaaaaaaaaa (job 0), colmo 0.1.0 (job 1)", "    nevergrad: 1.0.12 (job 0), not installed (job 1)",
    ]
    # Two copies of the code without a commit, each run through PYTHONPATH: told apart by their folders.
    copies = [job(0, {**provenance(), "commit": None, "source": "/work/exp9"}), job(1, {**provenance(), "commit": None, "source": "/work/exp21"})]
    assert comparison_lines(Path("/runs/sweep"), copies)[-1] == "    code: colmo 0.1.0 from /work/exp9 (job 0), colmo 0.1.0 from /work/exp21 (job 1)"


def test_time_limited_jobs_of_a_task_that_simulated_at_speeds_far_apart_are_named_with_each_speed():
    def job(number: int, task: str, speed: float, stop_reason: str = "max_seconds") -> JobOutcome:
        return JobOutcome(number, (f"task={task}", f"seed={number}"), summary(steps_per_worker_second=speed, stop_reason=stop_reason), None, task)

    close = [job(0, "quadruped", 9500.0), job(1, "quadruped", 7000.0), job(2, "cheetah", 3000.0)]  # tasks apart, not jobs of a task
    assert not any("different speeds" in line for line in comparison_lines(Path("/runs/sweep"), close))
    counted = [job(0, "quadruped", 9500.0, "max_samples"), job(1, "quadruped", 4600.0, "max_samples")]  # a time limit bought them nothing
    assert not any("different speeds" in line for line in comparison_lines(Path("/runs/sweep"), counted))
    apart = [*close, job(3, "quadruped", 4600.0), JobOutcome(4, ("task=quadruped", "seed=4"), summary(programs_evaluated=0), None, "quadruped")]
    assert comparison_lines(Path("/runs/sweep"), apart)[-1] == (
        "  quadruped: the time-limited jobs simulated at different speeds, control steps per worker-second: "
        "9.5k (job 0), 7.0k (job 1), 4.6k (job 3)"
    )


def test_the_comparison_of_settings_goes_into_the_sweeps_parent_run(tmp_path):
    from colmo.track import open_experiment
    from colmo.track.sweep import record_comparison, sweep_id

    uri = f"sqlite:///{tmp_path / 'mlruns.db'}"
    client, experiment_id = open_experiment(uri, "pendulum")
    parent = client.create_run(experiment_id, tags={"colmo.sweep": sweep_id(tmp_path / "sweep")}).info.run_id
    other = client.create_run(experiment_id, tags={"colmo.sweep": sweep_id(tmp_path / "other")}).info.run_id
    lines = ["sweep sweep: 6 jobs", "  job  variant  best", "  best score by setting, mean ± std over seeds (each seed), difference to the first:",
             "    gfo=none        325.07 ± 73.40 (380.40, 241.80, 353.00)",
             "    gfo=oneplusone  392.97 ± 111.01 (350.70, 518.90, 309.30)  +67.90, 95% interval [-43.70, +193.83]: no significant difference",
             "report: colmo-report experiment=pendulum sweep=abc"]
    record_comparison(uri, tmp_path, ["pendulum"], tmp_path / "sweep", lines)
    tag = client.get_run(parent).data.tags["colmo.comparison"]
    assert tag.splitlines()[2].endswith("+67.90, 95% interval [-43.70, +193.83]: no significant difference") and "report:" not in tag
    assert Path(client.download_artifacts(parent, "comparison.txt", str(tmp_path))).read_text() == "\n".join(lines) + "\n"
    assert "colmo.comparison" not in client.get_run(other).data.tags  # another sweep's parent is left alone


def test_a_comparison_mlflow_cannot_record_still_ends_the_sweep_with_its_exit_code(tmp_path, monkeypatch, capsys):
    from omegaconf import OmegaConf

    from colmo import sweep_comparison
    from colmo.track import sweep as tracked_sweep

    failed = JobOutcome(0, ("seed=0",), summary(programs_evaluated=0), {"name": "mlflow", "tracking_uri": "http://127.0.0.1:9"}, "pendulum")
    monkeypatch.setattr(sweep_comparison, "read_jobs", lambda sweep_dir: [failed])
    def server_gone(*args):
        raise ConnectionError("server gone")

    monkeypatch.setattr(tracked_sweep, "record_comparison", server_gone)
    monkeypatch.setattr(sweep_comparison, "sweep_report", server_gone)
    config = OmegaConf.create({"hydra": {"sweep": {"dir": "sweep"}, "runtime": {"cwd": str(tmp_path)}}})
    with pytest.raises(SystemExit) as stop:
        sweep_comparison.CompareJobs().on_multirun_end(config)
    assert stop.value.code == 1
    err = capsys.readouterr().err.splitlines()
    assert err == ["colmo: the comparison was not recorded in MLflow: server gone", "colmo: error: 1 of 1 jobs failed (job 0): no result to compare"]
