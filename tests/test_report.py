"""`colmo-report` on runs logged as colmo's tracker logs them (params of real composed configs,
metric histories at step = samples, best_policy.py): Table I with held-out scores, the runs that
count and those left out (repeats, unfinished runs), variants, the x axes, and a new output
directory every time. The report of a real sweep is read in tests/test_track.py."""

import dataclasses
import tempfile
from pathlib import Path

import pytest
from conftest import compose, refused, run_colmo
from mlflow.entities import Metric
from PIL import Image

from colmo.comparison import difference
from colmo.errors import ConfigError
from colmo.report import AXES, default_out, mean_std, read_runs
from colmo.report.__main__ import main as report_app
from colmo.report.__main__ import make_report
from colmo.track import flatten, open_experiment
from colmo.track.backend import log_params

START = 1_700_000_000_000  # ms; runs start a minute apart, in the order they are logged


@dataclasses.dataclass
class Logged:
    name: str
    method: str
    seed: int
    best: list[float]  # at samples 4, 8
    heldout: float | None


def log_run(client, experiment_id, index: int, run: Logged, *overrides: str, status: str = "FINISHED", seconds: bool = True, tags=None) -> str:
    cfg = compose("search", f"gfo={run.method}", "gfo.budget=3", f"seed={run.seed}", *overrides)
    mlflow_run = client.create_run(
        experiment_id, start_time=START + 60_000 * index, run_name=run.name,
        tags={"colmo.command": "search", "overrides": " ".join(overrides), **(tags or {})},
    )
    run_id = mlflow_run.info.run_id
    params = flatten(dataclasses.asdict(cfg)) | {"spec.observation_size": "3", "spec.action_size": "1"}
    metrics = []
    for batch, best in enumerate(run.best):
        step = 4 * (batch + 1)
        values = {"best_score": best, "best_score_island_0": best, "best_score_island_1": best / 2, "evaluations": 10.0 * step, "samples": step,
                  "worker_seconds": 3.0 * step, "programs_evaluated": step * (0.75 if run.method == "none" else 0.5)}
        if run.method == "oneplusone":  # a search of two generators (search.fill): each one's calls and programs
            values |= {"samples_mutate": 0.75 * step, "programs_evaluated_mutate": 0.25 * step}
        if seconds:
            values["seconds"] = 2.0 * step
        metrics += [Metric(key, value, START, step) for key, value in values.items()]
    if run.heldout is not None:
        metrics.append(Metric("best_heldout_score", run.heldout, START, 8))
    if run.method == "oneplusone":  # the best policy's readability report, logged at the end
        readable = {"lines": 9, "parameters": 6, "simplified_lines": 4, "simplified_parameters": 3, "branches": 2, "branches_never_taken": 1}
        metrics += [Metric(f"readability_{name}", value, START, 8) for name, value in (readable | {"clips_at_a_limit": 0, "divisions_by_zero": 2, "misleading_names": 1, "comparisons_decided": 3}).items()]
    log_params(client, run_id, params)  # as colmo's tracker logs them: in batches, not a transaction each
    client.log_batch(run_id, metrics=metrics)
    with tempfile.TemporaryDirectory() as scratch:
        policy = Path(scratch) / "best_policy.py"
        policy.write_text(f"def policy(obs):\n    return {run.best[-1]}  # {run.name}\n")
        client.log_artifact(run_id, str(policy))
    client.set_terminated(run_id, status, end_time=START + 60_000 * index + 30_000)
    return run_id


COUNTED = [
    Logged("none-s0", "none", 0, [100.0, 200.0], 180.0),
    Logged("none-s1", "none", 1, [50.0, 100.0], 90.0),
    Logged("opo-s1", "oneplusone", 1, [300.0, 420.0], 400.0),
    Logged("opo-s0", "oneplusone", 0, [250.0, 380.0], None),
]
REPEAT = Logged("opo-s0-older", "oneplusone", 0, [1.0, 2.0], 1.0)  # same settings and seed as opo-s0, started before it


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    """An experiment with the runs above, a repeat, a failed run, a sweep parent and a
    colmo-optimize run, in <cwd>/mlruns.db."""
    cwd = tmp_path_factory.mktemp("report")
    client, experiment_id = open_experiment(f"sqlite:///{cwd / 'mlruns.db'}", "pendulum")
    log_run(client, experiment_id, 0, REPEAT)
    for index, run in enumerate(COUNTED, start=1):
        log_run(client, experiment_id, index, run)
    log_run(client, experiment_id, 5, Logged("crashed", "oneplusone", 2, [10.0], None), status="FAILED")
    log_run(client, experiment_id, 6, Logged("sweep parent", "none", 0, [200.0], None), tags={"colmo.sweep": "abc"})
    log_run(client, experiment_id, 7, Logged("tuned", "oneplusone", 0, [999.0], None), tags={"colmo.command": "optimize"})
    return cwd, client


def report(cwd: Path, monkeypatch, *args: str) -> str:
    """The Markdown of `colmo-report experiment=pendulum <args>`, run in `cwd` (the app's own
    command line is run in test_bad_command_lines_fail_in_one_line)."""
    monkeypatch.chdir(cwd)
    return (cwd / make_report(compose("report", "experiment=pendulum", *args))).read_text()


def table(markdown: str, heading: str) -> list[list[str]]:
    """The cells of the first table under `## heading`, header row included."""
    section = markdown.split(f"## {heading}\n", 1)[1]
    end = next((i for i, line in enumerate(section.splitlines()) if line.startswith("## ")), None)
    rows = [line for line in section.splitlines()[:end] if line.startswith("|")]
    return [[cell.strip() for cell in row.strip("|").split("|")] for row in rows if not row.startswith("|---")]


def test_table_one_has_training_and_heldout_rewards_over_the_seeds(store, monkeypatch):
    cwd, _ = store
    rows = table(report(cwd, monkeypatch, "out=table"), "Table I")
    assert rows[0] == ["Task", "State dim", "Action dim", "GFO", "Reward, no GFO", "Reward, GFO", "Held-out, no GFO", "Held-out, GFO",
                       "Target", "Samples to target, no GFO", "Samples to target, GFO"]
    assert len(rows) == 2
    row = rows[1]
    assert row[:4] == ["pendulum", "3", "1", "oneplusone, budget 3"] and row[8] == "400"
    assert row[4] == mean_std([200.0, 100.0]) and row[5] == f"**{mean_std([420.0, 380.0])}**"  # the repeat does not count
    assert row[6] == mean_std([180.0, 90.0]) and row[7] == "400.0 (1/2 seeds)"  # one seed: no interval, no winner
    assert row[9] == "not reached (0/2 seeds)" and row[10] == "8 (1/2 seeds)"


def test_variants_are_compared_by_the_difference_of_means_with_its_interval_and_their_cost(store, monkeypatch):
    cwd, _ = store
    rows = table(report(cwd, monkeypatch, "out=compared"), "Variants compared")
    assert rows[0][:5] == ["Task", "Variant", "Seeds", "Best score", "Difference to the baseline"]
    baseline, tuned = rows[1], rows[2]
    assert baseline[1:5] == ["no GFO", "2", mean_std([200.0, 100.0]), "baseline"]
    best = difference([200.0, 100.0], [420.0, 380.0])
    assert best.significant and tuned[4] == best.text() and tuned[4].startswith("+250.0, 95% interval [")
    assert tuned[6] == "+265.0 (no interval: fewer than 2 seeds a side)"  # held-out: one seed of GFO has one
    assert tuned[7] == "16 ± 0" and tuned[8] == "24 ± 0" and tuned[9] == "8 ± 0" and tuned[10] == "80 ± 0"  # wall and worker s (as logged), model calls, evaluations


def test_a_difference_whose_interval_holds_0_is_said_to_be_none():
    assert difference([201.3, 180.0], [222.8, 190.0]).text().endswith(": no significant difference")
    assert not difference([201.3, 180.0], [222.8, 190.0]).significant
    assert difference([187.4, 196.5, 176.4], [392.5, 221.6, 502.2]).low > 0


def test_the_model_calls_that_yield_a_program_are_counted_per_variant_and_generator(store, monkeypatch):
    cwd, _ = store
    rows = table(report(cwd, monkeypatch, "out=yield"), "Model calls that yield a program")
    assert rows[0] == ["Variant", "Generator", "Programs per 100 model calls", "Per seed"]
    by_variant = {(row[0], row[1]): row[2:] for row in rows[1:]}
    assert by_variant[("no GFO", "all")] == ["75.0 ± 0.0", "75.0, 75.0"]
    assert by_variant[("oneplusone, budget 3", "all")] == ["50.0 ± 0.0", "50.0, 50.0"]
    assert by_variant[("oneplusone, budget 3", "mutate")] == ["33.3 ± 0.0", "33.3, 33.3"]


def test_each_runs_best_policy_has_its_readability_row(store, monkeypatch):
    cwd, _ = store
    rows = table(report(cwd, monkeypatch, "out=readable"), "Readability of each run's best policy")
    assert rows[0] == [
        "Run", "Variant", "Lines", "Parameters", "Simplified lines", "Simplified parameters", "Branches never taken", "Clips at a limit",
        "Divisions by zero", "Misleading names", "Comparisons decided",
    ]
    by_run = {row[0]: row[2:] for row in rows[1:]}
    assert by_run["opo-s1"] == ["9", "6", "4", "3", "1 of 2", "0", "2", "1", "3"]
    assert by_run["none-s0"] == ["—"] * 9  # a run that logged none (an older colmo's)


def test_every_run_is_accounted_for(store, monkeypatch):
    cwd, _ = store
    markdown = report(cwd, monkeypatch, "out=accounted")
    assert "6 search runs read from MLflow" in markdown and "4 count, 2 left out" in markdown
    runs = table(markdown, "Runs")
    assert sorted(r[0] for r in runs[1:]) == sorted(run.name for run in COUNTED)
    left_out = markdown.split("## Runs left out\n", 1)[1].split("## ")[0]
    assert "`opo-s0-older`" in left_out and "repeat of `opo-s0`" in left_out
    assert "`crashed`" in left_out and "status FAILED" in left_out
    assert "sweep parent" not in markdown and "tuned" not in markdown  # not searches
    # each variant's best policy, from its best run's artifact
    section = markdown.split("### pendulum, oneplusone, budget 3\n", 1)[1]
    assert "run `opo-s1`, score 420.0" in section and "return 420.0  # opo-s1" in section


def test_axes_use_the_logged_evaluations_and_seconds(store):
    _, client = store
    for axis, scale in (("samples", 1.0), ("evaluations", 10.0), ("seconds", 2.0)):
        curves = read_runs(client, ["pendulum"], axis).curves
        assert len(curves) == 4
        for curve in curves:
            assert curve.steps == [4, 8] and curve.x == [4 * scale, 8 * scale], axis
    assert set(AXES) == {"samples", "evaluations", "seconds"}


def test_a_run_without_the_axis_metric_is_left_out_of_that_axis_only(store):
    cwd, _ = store
    client, experiment_id = open_experiment(f"sqlite:///{cwd / 'mlruns.db'}", "old")  # an experiment of its own
    log_run(client, experiment_id, 0, Logged("old", "none", 0, [5.0, 6.0], None), seconds=False)
    assert len(read_runs(client, ["old"], "evaluations").curves) == 1
    reading = read_runs(client, ["old"], "seconds")
    assert reading.curves == [] and "no `seconds` metric" in reading.left_out[0][1]


def test_settings_that_differ_name_the_variants(store):
    cwd, _ = store
    client, experiment_id = open_experiment(f"sqlite:///{cwd / 'mlruns.db'}", "islands")
    log_run(client, experiment_id, 0, Logged("a", "oneplusone", 0, [5.0], None), "database.num_islands=5")
    log_run(client, experiment_id, 1, Logged("b", "oneplusone", 0, [6.0], None), "database.num_islands=10")
    log_run(client, experiment_id, 2, Logged("c", "oneplusone", 0, [7.0], None), "database.num_islands=10", "tracker.run_name=x", "executor.workers=1")
    curves = read_runs(client, ["islands"]).curves
    # "c" repeats "b": the tracker and executor settings do not change what a search finds
    assert sorted((c.run.info.run_name, c.variant) for c in curves) == [
        ("a", "oneplusone, budget 3, database.num_islands=5"), ("c", "oneplusone, budget 3, database.num_islands=10"),
    ]


def test_the_report_goes_to_a_new_directory_and_never_overwrites_one(store, monkeypatch):
    cwd, _ = store
    monkeypatch.chdir(cwd)
    path = make_report(compose("report", "experiment=pendulum", "axis=seconds"))
    assert path.parent.parent == Path("reports") and path.parent.name.startswith("pendulum_")
    assert "x: seconds of search (wall clock)" in path.read_text()
    with Image.open(cwd / path.parent / "best_so_far.png") as image:
        assert image.format == "PNG" and 600 <= image.size[0] <= 3000
    with pytest.raises(ConfigError, match="already holds a report"):
        make_report(compose("report", "experiment=pendulum", f"out={path.parent}"))
    assert default_out(["pendulum", "cheetah"]).name.startswith("pendulum+cheetah_")


def test_by_default_best_so_far_is_drawn_against_model_calls_and_against_seconds(store, monkeypatch):
    cwd, _ = store
    markdown = report(cwd, monkeypatch, "out=both")
    assert "x: model calls (programs sampled)." in markdown and "x: seconds of search (wall clock)." in markdown
    assert "(best_so_far.png)" in markdown and "(best_so_far_seconds.png)" in markdown
    for name in ("best_so_far.png", "best_so_far_seconds.png"):
        with Image.open(cwd / "both" / name) as image:
            assert image.format == "PNG"


def test_bad_command_lines_fail_in_one_line(store, tmp_path, monkeypatch):
    cwd, _ = store
    run = run_colmo("colmo.report", "experiment=nope", cwd=cwd)  # found out once the report runs
    errors = [line for line in run.stderr.splitlines() if line.startswith("colmo: error: ")]
    assert run.returncode == 2 and "Traceback" not in run.stderr, run.stderr
    assert len(errors) == 1 and "no MLflow experiment named 'nope'" in errors[0], run.stderr
    for where, args, message in (  # refused before Hydra starts: checked in process
        (cwd, ["experiment=pendulum", "axis=hours"], "axis must be one or more of samples, evaluations, seconds"),
        (tmp_path, ["experiment=pendulum"], "no tracking database"),
        (tmp_path, ["out=x"], "missing value for experiment"),
        (tmp_path, ["colour=red"], "Key 'colour' not in 'ReportConfig'"),
        (cwd, ["experiment=pendulum,cheetah"], "experiment=pendulum,cheetah is a sweep: add -m"),
    ):
        monkeypatch.chdir(where)
        code, line = refused(report_app, *args)
        assert code == 2 and message in line, (args, line)


def test_mean_std_is_the_sample_std_and_a_lone_mean():
    assert mean_std([1.0, 3.0]) == "2.0 ± 1.4"
    assert mean_std([591.0]) == "591.0"
    assert mean_std([12, 20], 0) == "16 ± 6"


def test_the_latest_sweep_is_compared_alone_with_a_legend_and_markers(store):
    """A 4-job sweep next to an unrelated run and an older sweep: only its 4 jobs count, by
    default and by name; the figure (the seam `figure`) names each variant in a legend, one
    colour each, and a run of one batch is a visible marker."""
    from colmo.report import group
    from colmo.report.figure import figure

    _, client = store
    experiment_id = client.create_experiment("swept")
    older = client.create_run(experiment_id, start_time=START, run_name="swept-sweep-1", tags={"colmo.sweep": "old"}).info.run_id
    log_run(client, experiment_id, 1, Logged("old-job", "none", 0, [5.0, 6.0], None), tags={"mlflow.parentRunId": older})
    parent = client.create_run(experiment_id, start_time=START + 120_000, run_name="swept-sweep-2", tags={"colmo.sweep": "new"}).info.run_id
    jobs = [Logged("n0", "none", 0, [1.0, 2.0], None), Logged("n1", "none", 1, [3.0, 4.0], None),
            Logged("o0", "oneplusone", 0, [5.0], None), Logged("o1", "oneplusone", 1, [6.0, 9.0], None)]
    for index, job in enumerate(jobs, start=3):
        log_run(client, experiment_id, index, job, tags={"mlflow.parentRunId": parent})
    log_run(client, experiment_id, 9, Logged("unrelated", "none", 5, [7.0, 8.0], None))
    for sweep in ("latest", "swept-sweep-2"):
        reading = read_runs(client, ["swept"], sweep=sweep)
        assert sorted(c.run.info.run_name for c in reading.curves) == ["n0", "n1", "o0", "o1"] and not reading.left_out
    assert [c.run.info.run_name for c in read_runs(client, ["swept"], sweep="swept-sweep-1").curves] == ["old-job"]
    every = read_runs(client, ["swept"], sweep="all")  # old-job repeats n0's settings and seed: left out
    assert len(every.curves) == 5 and [run.info.run_name for run, _ in every.left_out] == ["old-job"]
    with pytest.raises(ValueError, match="no sweep named 'nope'"):
        read_runs(client, ["swept"], sweep="nope")
    ax = figure(group(read_runs(client, ["swept"]).curves)).axes[0]
    legend = ax.get_legend()
    assert [text.get_text() for text in legend.get_texts()] == ["no GFO (2 seeds)", "oneplusone, budget 3 (2 seeds)", "target 400"]
    handles = legend.legend_handles
    assert handles[0].get_color() != handles[1].get_color()
    assert any(line.get_marker() == "o" and len(line.get_xdata()) == 1 for line in ax.get_lines())  # o0's single point
    assert len(ax.collections) == 2  # a band per variant of two seeds


def test_a_variant_mean_and_band_are_drawn_only_where_every_seed_has_data():
    from matplotlib.figure import Figure

    from colmo.report.figure import draw_seeds

    ax = Figure().subplots()
    # seed 0 starts late (at 10) and runs to 40; seed 1 runs from 0 to 20: the mean is defined on [10, 20] only
    draw_seeds(ax, "v", [([10.0, 30.0, 40.0], [180.0, 190.0, 200.0]), ([0.0, 5.0, 20.0], [50.0, 60.0, 70.0])], "tab:red")
    mean = next(line for line in ax.get_lines() if line.get_label() == "v (2 seeds)")
    assert list(mean.get_xdata()) == [10.0, 20.0] and list(mean.get_ydata()) == [120.0, 125.0]
    ax = Figure().subplots()
    draw_seeds(ax, "w", [([0.0, 1.0], [1.0, 2.0]), ([5.0, 6.0], [3.0, 4.0])], "tab:blue")  # no common range
    assert [line.get_label() for line in ax.get_lines()][-1] == "w (2 seeds), no common range" and not ax.collections


def test_the_caption_says_whether_budgets_were_equal_on_the_axis(store):
    from colmo.report import group
    from colmo.report.figure import budget_note

    _, client = store
    tasks = group(read_runs(client, ["pendulum"]).curves)
    assert budget_note(tasks, "samples") == "Equal budgets on this axis: every run ends at 8 model calls (programs sampled)."
    tasks["pendulum"][0].runs[0].x[-1] = 8.5
    assert budget_note(tasks, "samples").startswith("Equal budgets on this axis (within 10%): the runs end between 8 and 8.5 ")
    tasks["pendulum"][0].runs[0].x[-1] = 16.0
    assert budget_note(tasks, "samples").startswith("Unequal budgets on this axis: the runs end between 8 and 16 ")
    # Runs given the same time limit and stopped by it had equal budgets in seconds, wherever their curves end.
    experiment_id = client.create_experiment("timed")
    for index, (method, seed) in enumerate((("none", 0), ("oneplusone", 0))):
        log_run(client, experiment_id, index, Logged(f"t{index}", method, seed, [1.0, 2.0 + index], None), "search.max_seconds=90",
                tags={"colmo.stop_reason": "max_seconds"})
    timed = group(read_runs(client, ["timed"], axis="seconds").curves)
    timed["pendulum"][0].runs[0].x[-1] = 30.0
    assert budget_note(timed, "seconds") == "Equal budgets on this axis: every run was given search.max_seconds=90.0 and stopped by it."
    by_samples = group(read_runs(client, ["timed"]).curves)  # not stopped by max_samples: by where the curves end
    assert budget_note(by_samples, "samples").startswith("Equal budgets on this axis: every run ends at 8 ")


def test_a_run_that_evaluated_no_program_of_its_own_is_left_out(store):
    _, client = store
    experiment_id = client.create_experiment("nothing-evaluated")
    log_run(client, experiment_id, 1, Logged("searched", "none", 0, [1.0, 2.0], None))
    empty = log_run(client, experiment_id, 2, Logged("starter-only", "none", 1, [1.0], None))
    client.log_metric(empty, "programs_evaluated", 0.0, step=4)
    reading = read_runs(client, ["nothing-evaluated"])
    assert [c.run.info.run_name for c in reading.curves] == ["searched"]
    assert [(run.info.run_name, reason.split(":")[0]) for run, reason in reading.left_out] == [("starter-only", "no program of its own evaluated")]
