"""`search.max_seconds` is a wall-clock limit of the whole run, from the process's start (each job
of a `-m` sweep has the whole limit from its own start): the search stops in time for the finish
(how close the whole run ends to its limit on a loaded machine is measured by
`benchmarks/deadline.py`, not asserted here), with the held-out score, simplified policy, video and plot it promises, says
before the first batch how long it will take, and the programs whose tuning the deadline cut
short are stored with their best constants so far (`cut_short`), rounded to 4 significant
digits like every other program's, not thrown away."""

from __future__ import annotations

import ast
import contextlib
import json
import logging
import re
import sqlite3
import time
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

import pytest
from conftest import compose, limit_for_load, run_colmo

from colmo.finish_plan import RACED_SHARE, SAFETY, RefereeCost, plan_finish
from colmo.render import PLOT_FILE, VIDEO_FILE
from colmo.store import BEST_POLICY_FILE, SIMPLIFIED_POLICY_FILE, STORE_FILE, SUMMARY_FILE
from colmo.timelimit import TimeBudget, duration, job_start, process_seconds


@dataclass
class Run:
    summary: dict
    samples: list[dict]  # the stored samples
    run_dir: Path
    stderr: str


def search(tmp_path, task: str, *overrides: str, timeout: float) -> Run:
    """Run `python -m colmo task=<task> ...` in `tmp_path` (killed after `timeout` seconds)."""
    result = run_colmo("colmo", f"task={task}", "tracker=none", *overrides, cwd=tmp_path, timeout=timeout)
    assert result.returncode == 0, result.stderr[-3000:]
    run_dir = next(tmp_path.glob(f"outputs/{task}/*/"))
    summary = json.loads((run_dir / SUMMARY_FILE).read_text())
    with contextlib.closing(sqlite3.connect(run_dir / STORE_FILE)) as store:
        store.row_factory = sqlite3.Row
        samples = [dict(row) for row in store.execute("SELECT sample, status, score, cut_short, code FROM samples ORDER BY sample")]
    return Run(summary, samples, run_dir, result.stderr)


def constants(code: str) -> list[float]:
    return [node.value for node in ast.walk(ast.parse(code)) if isinstance(node, ast.Constant) and isinstance(node.value, float)]


@pytest.mark.parametrize("drawing", ["search.steady_state=false", "search.steady_state=true", "search.steady_state=true search.steady_queue=1"])
def test_a_time_limit_stops_tuning_in_flight_and_keeps_its_programs(tmp_path, drawing):
    # Each program would take hours to tune with this budget: only the deadline ends the run. At a
    # load of 4.8 (the suite in two processes on 2 cores) the start-up took 26 s of a 36 s limit.
    limit = limit_for_load(45)
    run = search(
        tmp_path, "pendulum", "gfo.budget=100000", f"search.max_seconds={limit}", "executor.workers=2", "heldout.episodes=5", "finish.top=1",
        *drawing.split(), timeout=4 * limit,
    )
    assert run.summary["stop_reason"] == "max_seconds"
    cut_short = [s for s in run.samples if s["cut_short"]]
    assert cut_short, run.samples
    assert all(s["status"] == "evaluated" and s["score"] is not None for s in cut_short)
    assert run.summary["best_score"] is not None
    # Readable like any other program: every constant at 4 significant digits at most.
    for sample in cut_short:
        assert all(float(f"{value:.4g}") == value for value in constants(sample["code"])), sample["code"]


def test_a_short_run_stops_searching_in_time_for_everything_it_promises(tmp_path):
    limit = limit_for_load(60)  # under load, the start of the process and the starter's calibration take half of it
    run = search(tmp_path, "pendulum", f"search.max_seconds={limit}", "gfo.budget=10", "executor.workers=2", "simplify.max_constants=0", timeout=10 * limit)
    # The search left the finish its time: start-up and search ended before the limit.
    assert run.summary["stop_reason"] == "max_seconds"
    assert run.summary["startup_seconds"] + run.summary["search_seconds"] < limit, run.summary
    assert re.search(rf"estimated duration: search \S+ .* limit that binds: max_seconds={limit}", run.stderr), run.stderr[-3000:]
    for name in (BEST_POLICY_FILE, SIMPLIFIED_POLICY_FILE, PLOT_FILE, VIDEO_FILE):
        assert (run.run_dir / name).is_file(), (name, run.stderr[-3000:])
    assert run.summary["best_heldout_score"] is not None
    assert run.summary["media"]["video"] == VIDEO_FILE
    # The video shows the best program as found, so it is made before the simplification, which
    # then has what the video's slot did not use.
    assert (run.run_dir / VIDEO_FILE).stat().st_mtime <= (run.run_dir / SIMPLIFIED_POLICY_FILE).stat().st_mtime
    # A simplification the deadline stopped says so, with the command that goes on from the best policy.
    header = (run.run_dir / SIMPLIFIED_POLICY_FILE).read_text().split("\nimport", 1)[0]
    go_on = f"to go on: colmo-simplify task=pendulum seed=0 policy_file={run.run_dir / BEST_POLICY_FILE}"
    assert (go_on in header) is run.summary["simplified"]["cut_short"], (header, run.summary["simplified"])
    # ... and one that kept more constants than simplify.max_constants allows says that too.
    assert run.summary["simplified"]["max_constants"] == 0
    over = "over the constant budget" in header
    assert over is (not run.summary["simplified"]["within_budget"]) is (run.summary["simplified"]["n_params"] > 0), header


def test_each_job_of_a_sweep_searches_for_its_whole_limit(tmp_path):
    """The jobs of a basic-launcher sweep share one process: the second job's limit counts from
    its own start, not the process's (it used to find no time left and search 0 samples)."""
    result = run_colmo(
        "colmo", "-m", "seed=0,1", f"search.max_seconds={limit_for_load(30)}", "tracker=none", "search.progress=false", "task.episodes=1",
        "heldout.episodes=2", "finish.render=false", "finish.simplify=false", "executor.workers=1", "hydra.sweep.dir=sweep",
        cwd=tmp_path, timeout=600,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    summaries = [json.loads(next((tmp_path / "sweep").glob(f"{job}_*/{SUMMARY_FILE}")).read_text()) for job in (0, 1)]
    for summary in summaries:
        assert summary["stop_reason"] == "max_seconds"
        assert summary["samples"] > 0 and summary["programs_evaluated"] > 0, summary
        assert 0 < summary["startup_seconds"] < summary["seconds"] and 0 < summary["search_seconds"] < summary["seconds"]


def test_a_sweep_job_counts_its_limit_from_its_own_start_a_single_run_from_the_process_start():
    before = time.perf_counter()
    assert before <= job_start(sweep_job=True) <= time.perf_counter()
    # A single run's start is the process's: now less the process's age, whenever it is asked.
    # Generous, as every read of the two clocks is a moment apart (ms under load; /proc counts in 10 ms ticks).
    assert job_start(sweep_job=False) == pytest.approx(time.perf_counter() - process_seconds(), abs=0.5)
    assert process_seconds() > 0.5  # this process has run for longer than that: the two starts differ
    budget = TimeBudget(60.0, started=time.perf_counter() - 20.0)
    assert budget.limit_seconds == pytest.approx(40.0, abs=0.5)  # the start-up spent is not the search's
    assert TimeBudget(60.0).limit_seconds == pytest.approx(60.0)


@pytest.mark.slow
def test_the_quadruped_search_stops_in_time_for_its_finish(tmp_path):
    limit = limit_for_load(60)
    run = search(tmp_path, "quadruped", f"search.max_seconds={limit}", timeout=10 * limit)
    assert run.summary["stop_reason"] == "max_seconds"
    assert run.summary["startup_seconds"] + run.summary["search_seconds"] < limit, run.summary



@dataclass
class IdleWorkers:
    """An executor's speed counters as `TimeBudget` reads them, with nothing running."""

    n_workers: int = 2
    evaluations_done: int = 2
    busy_seconds: float = 2.0


def planned_budget(max_seconds: float, programs: list[int], calibration: float = 2.0) -> TimeBudget:
    """A budget planned at its start, its programs in flight read from `programs[0]`."""
    budget = TimeBudget(max_seconds, lambda: programs[0])
    cfg = compose("search", "task=pendulum", f"search.max_seconds={max_seconds}", "finish.render=false", "finish.simplify=false")
    budget.plan(cfg, (calibration / 2, calibration / 2), program_seconds=1.0, executor=IdleWorkers())
    return budget


def test_the_reserve_for_programs_in_flight_follows_how_many_there_are():
    programs = [0]
    budget = planned_budget(600, programs)
    deadlines = {}
    for count in (0, 1, 2, 4, 6, 8):
        programs[0] = count
        deadlines[count] = budget.deadline
    assert deadlines[0] > deadlines[1] == deadlines[2] > deadlines[4] > deadlines[8]  # two workers: a round per two programs
    assert deadlines[2] - deadlines[4] == pytest.approx(deadlines[4] - deadlines[6]) == pytest.approx(deadlines[6] - deadlines[8])
    programs[0] = 2
    assert budget.deadline_with(6) == deadlines[8]
    assert budget.deadline == deadlines[2]  # programs that are in leave their time to the others


def test_a_batch_starts_only_while_the_run_can_still_drain_it():
    programs = [0]
    roomy = planned_budget(600, programs)
    assert roomy.can_start(4) and not roomy.past_deadline()
    # 10 s of final scores per program and worker: 4 programs (2 rounds) do not fit in a 60 s run, 1 does.
    tight = planned_budget(60, programs, calibration=10.0)
    assert not tight.can_start(4) and tight.can_start(1)
    programs[0] = 2  # two in flight: one more would need a second round
    assert not tight.can_start(1) and not tight.past_deadline()


@pytest.mark.parametrize("retune", [0, 1000])
@pytest.mark.parametrize("available", [12.0, 15.0, 22.0, 40.0])
def test_a_finish_cut_to_fit_still_leaves_the_simplification_room_to_start(available, retune):
    cfg = compose("search", "task=pendulum", f"finish.retune_budget={retune}")
    referee, workers = RefereeCost(episode=0.03, batch=0.3), 2
    assert not plan_finish(cfg, referee, workers).reduced  # about a minute, as configured
    plan = plan_finish(cfg, referee, workers, available)
    assert plan.reduced and plan.seconds <= available + 1e-9 and plan.top >= 1
    # What finish() requires before it simplifies: two measurements of the best program (its
    # training and held-out episodes), and a round of candidates after them.
    best_measured = referee.seconds(plan.heldout_episodes, workers) + referee.seconds(cfg.task.episodes, workers)
    assert plan.simplify_seconds >= 3 * best_measured - 1e-9
    assert plan.render_seconds >= referee.seconds(1, 1) + 2.0  # the episode it films and a few frames


def test_the_finish_plans_the_re_tuning_in_full_where_it_fits_and_cuts_it_to_a_share_where_not():
    referee, workers = RefereeCost(episode=0.03, batch=0.3), 2
    plain = plan_finish(compose("search", "task=pendulum"), referee, workers)
    cfg = compose("search", "task=pendulum", "finish.retune_budget=1000")
    full = plan_finish(cfg, referee, workers)
    assert plain.retune_seconds == 0 and not full.reduced
    # 1000 candidates, one per worker at a time, racing through at most half their training episodes;
    # then the referee's training and held-out scores.
    assert cfg.gfo.method == "oneplusone" and RACED_SHARE == 0.5
    candidates = SAFETY * 1000 * cfg.task.episodes / 2 * referee.episode / workers
    assert full.retune_seconds == pytest.approx(candidates + referee.seconds(cfg.task.episodes, workers) + referee.seconds(cfg.heldout.episodes, workers))
    assert full.seconds == pytest.approx(plain.seconds + full.retune_seconds) and "re-tuning" in full.describe(cfg)
    unraced = plan_finish(compose("search", "task=pendulum", "finish.retune_budget=1000", "gfo.racing=false"), referee, workers)
    assert unraced.retune_seconds - full.retune_seconds == pytest.approx(candidates)  # every candidate runs all its episodes
    available = plain.seconds + full.retune_seconds / 2  # everything else fits, the re-tuning does not
    cut = plan_finish(cfg, referee, workers, available)
    assert cut.reduced and cut.seconds <= available + 1e-9
    # An equal share, with the held-out scores and the simplification, of what the video leaves.
    assert 0 < cut.retune_seconds <= (available - cut.render_seconds) / 3 + 1e-9


# Quadruped-like costs; at 0.09 s an episode, the video's seconds computed back from its slot
# came out a hair under the full video's, which gave it the small size.
@pytest.mark.parametrize("episode", [0.5, 0.09])
def test_a_finish_cut_to_fit_gives_the_video_no_more_than_its_full_length_and_the_other_steps_the_rest(episode):
    # The full finish (held-out scores, simplification, re-tuning) does not fit, but an equal
    # share of the time is far more than the full video needs.
    referee, workers = RefereeCost(episode=episode, batch=0.0), 2
    cfg = compose("search", "task=quadruped", "search.max_seconds=1800", "finish.retune_budget=1000")
    full = plan_finish(cfg, referee, workers)
    available = 0.6 * full.seconds
    assert full.render_seconds < available / 4
    cut = plan_finish(cfg, referee, workers, available)
    assert cut.reduced and cut.render_seconds == pytest.approx(full.render_seconds)
    assert (cut.size, cut.video_seconds) == (full.size, full.video_seconds)  # the full video
    assert cut.seconds == pytest.approx(available)  # no step's slot is more than it can use
    assert cut.retune_seconds == pytest.approx((available - cut.render_seconds) / 3)


def test_a_long_run_keeps_a_share_of_its_time_for_the_simplification():
    referee, workers = RefereeCost(episode=0.03, batch=0.3), 2
    least = plan_finish(compose("search", "task=cheetah", "search.max_seconds=60"), referee, workers).simplify_seconds
    assert least > 0.03 * 60  # a short run: what the simplifier's first measurements need
    assert plan_finish(compose("search", "task=cheetah", "search.max_seconds=1800"), referee, workers).simplify_seconds == pytest.approx(54.0)
    assert plan_finish(compose("search", "task=cheetah", "search.max_seconds=36000"), referee, workers).simplify_seconds == 600.0  # simplify.max_seconds
    off = compose("search", "task=cheetah", "search.max_seconds=1800", "finish.simplify_share=0")
    assert plan_finish(off, referee, workers).simplify_seconds == pytest.approx(least)
    assert plan_finish(compose("search", "task=cheetah", "search.max_seconds=0"), referee, workers).simplify_seconds == pytest.approx(least)  # no limit


def test_the_referee_cost_counts_lockstep_batches_not_episodes():
    # Calibrated on 10 episodes: 0.1 s on the fast path, 0.4 s by the referee (0.3 s of round trips).
    referee = RefereeCost.of(0.1, 0.4, 10)
    assert referee.seconds(10, 1) == pytest.approx(SAFETY * 0.4)
    assert referee.seconds(16, 1) == pytest.approx(SAFETY * (16 * 0.01 + 0.3))  # one batch
    assert referee.seconds(100, 2) == pytest.approx(SAFETY * (50 * 0.01 + 4 * 0.3))  # 50 a worker: 4 batches
    assert referee.scaled(2).seconds(100, 2) == pytest.approx(2 * referee.seconds(100, 2))


def said_estimates(budget: TimeBudget, settles, caplog) -> list[str]:
    """The estimate lines `budget` says for `settles`: (seconds after the search's start, samples
    settled, the batch settling (its samples, seconds after the start its generation began), the
    batches in flight likewise, tokens/s)."""
    budget.search_starts()
    start = time.perf_counter()
    with caplog.at_level(logging.INFO, logger="colmo.search"):
        for at, samples, (size, began), flying, tokens in settles:
            totals = SimpleNamespace(samples=samples, tokens_per_second=tokens, generator_busy=0.5, seconds=at)
            budget.follow_samples(totals, 0, 16, (size, start + began), [(n, start + b) for n, b in flying], now=start + at)
    return [m.split("estimated duration after ", 1)[1] for m in caplog.messages if m.startswith("estimated duration after")]


def test_the_pace_counts_the_samples_that_started_beside_the_first_batch(caplog):
    """The quadruped's measured run: two batches of 4 started together and settled at 164 s. The
    first batch's 164 s in the pipeline held 8 samples: 20.5 s a sample, 8
    samples not started yet, 2m44s more (the run took 2m30s more; counting the first batch
    alone said 8m12s). The same pace later says nothing new; an end that moves by more than 30%
    is said again."""
    settles = [
        (164.0, 4, (4, 0.0), [(4, 0.1)], 0.0),
        (164.2, 8, (4, 0.1), [(4, 164.0), (4, 164.1)], 0.0),  # the next two batches began as the first settled
        (500.0, 12, (4, 164.0), [(4, 164.1)], 0.0),  # slower: 336 s in the pipeline; the last batch began beside it
    ]
    assert said_estimates(planned_budget(3600, [0]), settles, caplog) == [
        "4 samples: search 2m44s more (20.5 s a sample); limit that binds: max_samples",
        "12 samples: search 0m00s more (42.0 s a sample); limit that binds: max_samples",
    ]


def test_a_model_bound_estimate_says_what_the_calls_take_and_when_the_time_limit_binds(caplog):
    # Generated one batch at a time: 4 samples 110 s after their generation began, none in flight.
    settles = [(110.0, 4, (4, 0.0), [], 12.0)]
    [said] = said_estimates(planned_budget(300, [0]), settles, caplog)
    assert said.startswith("4 samples: search ")
    assert said.endswith(" more (27.5 s a sample, model calls 14 s each at 12.0 tokens/s); limit that binds: max_seconds=300 (16 samples would take 5m30s)")
    left = said.removeprefix("4 samples: search ").split(" more")[0]  # what is left of the 300 s, not the samples' 5m30s
    minutes, seconds = left.removesuffix("s").split("m")
    assert 0 < 60 * int(minutes) + int(seconds) < 300 - 110


def test_a_starter_with_nothing_to_tune_leaves_the_first_estimate_to_the_samples(caplog):
    cfg = compose("search", "task=quadruped", "finish.render=false")
    budget = TimeBudget(0.0)
    with caplog.at_level(logging.INFO, logger="colmo.search"):
        budget.plan(cfg, (1.0, 1.0), program_seconds=0.0, executor=IdleWorkers())
    assert budget.estimated_seconds is None
    assert "estimated duration: search estimated once the first samples are in (the starter has no constants to tune" in caplog.text


def test_a_language_models_first_estimate_says_what_it_leaves_out(caplog):
    cfg = compose("search", "task=pendulum", "llm=openai", "search.max_samples=12", "finish.render=false")
    budget = TimeBudget(0.0)
    with caplog.at_level(logging.INFO, logger="colmo.search"):
        budget.plan(cfg, (1.0, 1.0), program_seconds=6.9, executor=IdleWorkers())
    assert re.search(
        r"estimated duration: search \S+ \(12 samples x 6\.9 s of tuning, \d+ at a time, if every answer is a new program; "
        r"the model's calls come on top: measured on the first samples\)", caplog.text,
    ), caplog.text


def model_budget(max_seconds: float, *overrides: str) -> TimeBudget:
    """A language model's run of 12 samples planned with a program's tuning of 6.9 s."""
    budget = TimeBudget(max_seconds)
    cfg = compose("search", "task=pendulum", "llm=openai", "search.max_samples=12", f"search.max_seconds={max_seconds}", "finish.render=false", *overrides)
    budget.plan(cfg, (1.0, 1.0), program_seconds=6.9, executor=IdleWorkers())
    return budget


def test_the_models_first_answers_say_what_its_calls_take(caplog):
    """The 1.5B model's measured run: its first line said 41 s of tuning where the run took
    126 s, its calls 10-18 s each. Once the first batch is generated (4 calls in 48 s, 3 of
    their answers new programs) the line counts the calls: 12 s a sample (a sample is a call),
    the longer of the call and its share of tuning (which overlap: batches queue), for the 8
    samples not started, and the batch's tuning."""
    budget = model_budget(0)
    budget.search_starts()
    with caplog.at_level(logging.INFO, logger="colmo.search"):
        budget.follow_generation(8, 4, 48.0, 3, now=budget.start + 50.0)
        budget.follow_generation(4, 4, 10.0, 4, now=budget.start + 60.0)  # said once: the samples' pace takes over
    lines = [m for m in caplog.messages if m.startswith("estimated duration after the model")]
    in_parallel = re.search(r"(\d+) at a time", lines[0]).group(1)
    tuning = 6.9 * 3 / 4 / int(in_parallel)
    left = 8 * max(12.0, tuning) + 4 * tuning
    assert lines == [
        f"estimated duration after the model's first 4 calls: search {duration(left)} more (12.0 s a sample: a call 12.0 s, "
        f"3 new programs of 4 calls tuned, 6.9 s each, {in_parallel} at a time); limit that binds: max_samples",
    ]
    assert budget.estimated_seconds == pytest.approx(50.0 + left)


def test_without_a_queue_a_sample_takes_its_generation_and_its_tuning(caplog):
    budget = model_budget(0, "search.queue_size=1")
    with caplog.at_level(logging.INFO, logger="colmo.search"):
        budget.follow_generation(8, 4, 8.0, 4, now=budget.start + 10.0)
    in_parallel = int(re.search(r"(\d+) at a time", caplog.text).group(1))
    assert f"({2.0 + 6.9 / in_parallel:.1f} s a sample: a call 2.0 s, 4 new programs of 4 calls" in caplog.text


def test_the_models_first_answers_say_when_the_time_limit_binds(caplog):
    budget = model_budget(120)
    with caplog.at_level(logging.INFO, logger="colmo.search"):
        budget.follow_generation(8, 4, 80.0, 4, now=budget.start + 30.0)
    # 8 samples of 20 s (their generation) and the batch's tuning, 6.9 s each for 4 programs, 2 at a time
    assert "limit that binds: max_seconds=120 (12 samples would take 2m53s)" in caplog.text
    assert budget.estimated_seconds == pytest.approx(30.0 + 8 * 20.0 + 4 * 6.9 / 2)


def test_embedded_generation_leaves_the_estimate_to_the_plan_and_the_samples(caplog):
    budget = planned_budget(600, [0])  # llm=mutate: the plan's line holds from the start
    with caplog.at_level(logging.INFO, logger="colmo.search"):
        budget.follow_generation(8, 4, 0.1, 4)
    assert "estimated duration after" not in caplog.text


def test_a_resumed_run_has_what_its_earlier_processes_left_of_the_limit():
    """`search.max_seconds` is the whole run's, as `search.max_samples` is: a run stopped after
    40 s of a 100 s limit and resumed searches 60 s more, not 100 (equal budgets in a sweep)."""
    assert 59.0 < TimeBudget(100.0, spent=40.0).limit_seconds <= 60.0
    assert TimeBudget(100.0, spent=250.0).limit_seconds <= 1.0  # resumed past its limit: it ends at once
    assert TimeBudget(0.0, spent=40.0).limit_seconds == 0.0  # no limit stays none


def test_an_estimate_the_time_limit_ends_is_not_said_again_when_only_the_pace_moves(caplog):
    """With the time limit binding, the end the line gives is the limit's: a pace that moves by
    half (the samples' end by far more than 30%) says nothing new."""
    settles = [(110.0, 4, (4, 0.0), [], 0.0), (180.0, 8, (4, 110.0), [], 0.0), (260.0, 12, (4, 180.0), [], 0.0)]
    said = said_estimates(planned_budget(300, [0]), settles, caplog)
    assert len(said) == 1 and "limit that binds: max_seconds=300" in said[0]
