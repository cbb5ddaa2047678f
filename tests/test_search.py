"""The search end to end: outputs, determinism, crash safety and resume."""

import importlib.metadata
import json
import os
import random
import signal
import sqlite3
import time
from collections import Counter

import pytest
from conftest import compose, refused, run_colmo, start_colmo

from colmo import coverage
from colmo.__main__ import main as colmo
from colmo.generate import Generation, Generator, PromptForm
from colmo.record import SampleRecord
from colmo.search import Search
from colmo.store import ProgramStore

TINY = ("gfo.budget=4", "task.episodes=2", "tracker=none", "executor.workers=2", "search.progress=false", "heldout.episodes=2", "finish.render=false", "finish.simplify=false")


def store_rows(run_dir):
    with sqlite3.connect(run_dir / "programs.db") as connection:
        return connection.execute("SELECT sample, status, key, score FROM samples ORDER BY sample").fetchall()


def stored_model_calls(run_dir) -> int:
    """The model calls of the stored samples, the starter aside: a regenerated duplicate is one
    row of several calls."""
    with sqlite3.connect(run_dir / "programs.db") as connection:
        return connection.execute("SELECT SUM(model_calls) FROM samples WHERE sample >= 0").fetchone()[0]


def test_small_search_end_to_end(tmp_path):
    result = run_colmo("colmo", "search.max_samples=12", *TINY, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    run_dir = next(tmp_path.glob("outputs/pendulum/*"))
    summary = json.loads((run_dir / "summary.json").read_text())
    for field in ("best_score", "samples", "programs_evaluated", "duplicates_skipped", "failures", "seconds", "best_so_far"):
        assert field in summary
    assert summary["samples"] == 12  # model calls, duplicates generated again included
    assert summary["provenance"]["libraries"]["mujoco"] == importlib.metadata.version("mujoco")  # what made the numbers
    rows = store_rows(run_dir)
    assert summary["programs_evaluated"] + summary["duplicates_skipped"] + summary["failures"] == len(rows) - 1
    assert summary["best_so_far"][0][0] == 0 and summary["best_so_far"][-1][1] == summary["best_score"]
    best = (run_dir / "best_policy.py").read_text()
    assert "def policy(obs)" in best and f"{summary['best_score']:.2f}" in best
    assert summary["coverage"]["episodes"] == 4  # its 2 training and 2 held-out episodes
    for site in summary["coverage"]["sites"]:  # what each branch of the best policy did, as comments
        assert f"# coverage: {site['says']}\n" in best
    assert [r[0] for r in rows] == list(range(-1, len(rows) - 1))  # the starter, then every sample once
    # every program's branches, as its referee counted them, for the prompts that show it
    counted = [record for record in ProgramStore(run_dir / "programs.db").records() if record.status == "evaluated" and record.sample >= 0]
    assert counted and all(record.coverage is not None and len(record.coverage) == len(coverage.sites(record.code)) for record in counted)
    assert f"best score {summary['best_score']:.2f}" in result.stdout
    # the load it was measured under: the machine's mean load average, its own workers included
    assert summary["cpus"] == os.cpu_count() and summary["load"] >= 0.0
    assert f"(load {summary['load']:.1f} on {os.cpu_count()} CPUs)" in result.stdout



def test_programs_over_the_size_caps_are_refused_before_they_are_evaluated(tmp_path):
    simplifying = [option for option in TINY if option != "finish.simplify=false"]
    result = run_colmo("colmo", "llm=mutate", "search.max_samples=40", "database.max_constants=3", "database.max_nodes=40", *simplifying, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    run_dir = next(tmp_path.glob("outputs/pendulum/*"))
    records = [record for record in ProgramStore(run_dir / "programs.db").records() if record.sample >= 0]
    evaluated = [record for record in records if record.status == "evaluated"]
    assert evaluated and all(record.n_params <= 3 and record.nodes <= 40 for record in evaluated)
    refused = [record.failure for record in records if record.status == "failed"]
    assert any(f.startswith("too many constants: ") and f.endswith(" tunable constants (database.max_constants=3)") for f in refused), refused
    assert all(record.evaluations == 0 for record in records if record.status == "failed")
    # The finish's simplifier keeps the best policy within the search's budget of constants.
    simplified = json.loads((run_dir / "summary.json").read_text())["simplified"]
    assert simplified["max_constants"] == 3 and simplified["n_params"] <= 3 and simplified["within_budget"] is True


def test_same_seed_same_search(tmp_path):
    def run(directory):
        cfg = compose("search", "search.max_samples=8", "seed=5", *TINY)
        summary = Search(cfg, tmp_path / directory).run()
        return summary, store_rows(tmp_path / directory)

    first, second = run("a"), run("b")
    assert first[1] == second[1]
    assert first[0].best_score == second[0].best_score


def test_duplicates_are_not_evaluated_twice(tmp_path):
    cfg = compose("search", "search.max_samples=24", *TINY)
    summary = Search(cfg, tmp_path / "run").run()
    rows = store_rows(tmp_path / "run")
    evaluated = [key for _, status, key, _ in rows if status in ("evaluated", "failed")]
    assert len(evaluated) == len(set(evaluated))
    assert summary.duplicates_skipped == sum(status == "duplicate" for _, status, _, _ in rows)


def start_search(tmp_path, *overrides):
    return start_colmo("colmo", *TINY, *overrides, "hydra.run.dir=run", cwd=tmp_path, start_new_session=True)


def wait_for_samples(run_dir, at_least: int, timeout: float = 300) -> None:
    deadline = time.time() + timeout
    while time.time() < deadline:
        try:
            if len(store_rows(run_dir)) > at_least:
                return
        except sqlite3.Error:
            pass
        time.sleep(0.2)
    raise TimeoutError(f"no {at_least} samples in {run_dir} after {timeout} s")


def test_sigkill_at_random_moments_then_resume_loses_nothing(tmp_path):
    run_dir = tmp_path / "run"
    rng = random.Random(0)
    process = start_search(tmp_path, "search.max_samples=40")
    for kill in range(3):
        wait_for_samples(run_dir, at_least=1 + 4 * kill)
        time.sleep(rng.uniform(0.0, 2.0))
        os.killpg(process.pid, signal.SIGKILL)  # the coordinator and its sandbox workers
        process.wait()
        process = start_search(tmp_path, "search.max_samples=40", f"resume={run_dir}")
    assert process.wait(timeout=300) == 0, process.stderr.read()
    rows = store_rows(run_dir)
    samples = [r[0] for r in rows]
    assert len(samples) == len(set(samples))  # no sample counted twice
    evaluated = Counter(key for _, status, key, _ in rows if status == "evaluated")
    assert max(evaluated.values()) == 1  # no program evaluated twice
    summary = json.loads((run_dir / "summary.json").read_text())
    assert summary["samples"] == stored_model_calls(run_dir) == 40


@pytest.mark.slow
def test_sigint_stops_gracefully_and_says_how_to_resume(tmp_path):
    """tests/test_faults.py's stop-signal test checks all this, with programs caught in flight."""
    process = start_search(tmp_path, "search.max_samples=1000")
    wait_for_samples(tmp_path / "run", at_least=4)
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 130
    assert "resume with: colmo " in stderr and f"resume={tmp_path / 'run'}" in stderr
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    # The programs in flight finished with their best constants so far: summary and store agree.
    assert summary["stop_reason"] == "interrupted"
    assert 1 <= summary["samples"] == len(store_rows(tmp_path / "run")) - 1
    assert (tmp_path / "run" / "best_policy.py").is_file()
    assert "Traceback" not in stderr


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory):
    """The run directory of a finished 4-sample search (read, never written, by the tests)."""
    run_dir = tmp_path_factory.mktemp("finished") / "run"
    Search(compose("search", "search.max_samples=4", *TINY), run_dir).run()
    return run_dir


@pytest.mark.parametrize("finished, overrides, message", [
    (False, ["resume=/no/such/run"], "resume=/no/such/run is not a colmo run directory"),
    (True, ["task=cheetah"], "was made with task=pendulum; this command has task=cheetah"),
    (True, ["seed=1", "task.episodes=3"], "was made with seed=0, task.episodes=2; this command has seed=1, task.episodes=3"),
])
def test_bad_resume_directories_exit_2(request, tmp_path, monkeypatch, finished, overrides, message):
    if finished:
        overrides = [*overrides, f"resume={request.getfixturevalue('finished_run')}"]
    monkeypatch.chdir(tmp_path)
    code, line = refused(colmo, *TINY, *overrides)
    assert code == 2 and message in line, line


def test_children_of_the_starter_name_it_as_their_parent(finished_run):
    with sqlite3.connect(finished_run / "programs.db") as connection:
        starter_key = connection.execute("SELECT key FROM samples WHERE sample = -1").fetchone()[0]
        parents = [json.loads(p) for (p,) in connection.execute("SELECT parent_keys FROM samples WHERE sample >= 0")]
    assert starter_key and all(p == [starter_key] for p in parents)


@pytest.mark.slow
def test_default_search_swings_the_pendulum_up(tmp_path):
    """Search quality, end to end: the embedded generator without GFO passes the task's target
    score (400) within 600 samples (measured: first at sample 240 of a 10-minute run)."""
    cfg = compose("search", "gfo=none", "search.max_samples=600", "search.stop_at_score=400", "tracker=none", "search.progress=false", "finish.render=false", "finish.simplify=false")
    summary = Search(cfg, tmp_path).run()
    assert summary.best_score >= 400, summary.best_so_far
    assert summary.stop_reason == "stop_at_score"


STARTER_WITH = "import numpy as np\n\ndef policy(obs):\n    action = {}\n    return action\n"


class ScriptedGenerator(Generator):
    """Answers from a script, one per model call, whatever the prompt; counts the calls. `chat`:
    the answers carry the code their prompt showed, as a chat model's do."""

    def __init__(self, answers: list[str], chat: bool = False):
        super().__init__(cfg=None, seed=0)
        self.answers, self.prompts, self.chat = list(answers), [], chat
        self.follows_up = chat  # as a chat model's generator: a wasted answer is followed up

    def generate(self, prompt, n):
        self.prompts.append(prompt)
        form, context = (PromptForm.CHAT, prompt.shown_code) if self.chat else (PromptForm.CODE, "")
        return [
            Generation(self.answers.pop(0), "scripted", prompt_tokens=10, completion_tokens=5, seconds=0.5, form=form, context=context)
            for _ in range(n)
        ]


def scripted_search(tmp_path, answers, *overrides, chat=False):
    cfg = compose("search", f"search.max_samples={len(answers)}", "llm.batch_size=1", "search.queue_size=1", *TINY, *overrides)
    generator = ScriptedGenerator(answers, chat)
    summary = Search(cfg, tmp_path / "run", generator=generator).run()
    with sqlite3.connect(tmp_path / "run" / "programs.db") as connection:
        rows = connection.execute("SELECT status, model_calls, prompt_tokens, completion_tokens, generation_seconds FROM samples WHERE sample >= 0 ORDER BY sample").fetchall()
    return summary, rows, generator


def test_a_chat_answer_that_calls_a_shown_version_is_evaluated(tmp_path):
    # Before, such an answer failed: "NameError: name 'policy_v0' is not defined" (issue 19).
    answers = ["```python\ndef policy(obs):\n    return 0.5 * policy_v0(obs) - 0.2 * obs[2]\n```"]
    summary, rows, _ = scripted_search(tmp_path, answers, chat=True)
    assert [row[0] for row in rows] == ["evaluated"] and summary.failures == 0
    with sqlite3.connect(tmp_path / "run" / "programs.db") as connection:
        [(code, shown)] = connection.execute("SELECT code, prompt_shown FROM samples WHERE sample = 0").fetchall()
    assert "def policy_v0(obs):" in code and "policy_v0(obs)" in shown


def test_gfo_none_evaluates_a_program_that_differs_from_a_known_one_only_in_its_constants(tmp_path):
    """Without GFO, constants are all the search can change: the starter with another constant is a
    new program. With GFO it is the starter's structure, whose constants were tuned already."""
    answers = [STARTER_WITH.format(0.5)]
    none, rows, _ = scripted_search(tmp_path / "none", answers, "gfo=none", "search.duplicate_retries=0")
    assert [row[0] for row in rows] == ["evaluated"] and none.programs_evaluated == 1
    tuned, rows, _ = scripted_search(tmp_path / "gfo", answers, "gfo=oneplusone", "search.duplicate_retries=0")
    assert [row[0] for row in rows] == ["duplicate"] and tuned.programs_evaluated == 0


def test_a_duplicate_answer_is_generated_again_and_every_model_call_counts(tmp_path):
    answers = [STARTER_WITH.format(0.0), STARTER_WITH.format(0.0), STARTER_WITH.format("-np.sign(obs[2])")]
    summary, rows, generator = scripted_search(tmp_path, answers, "search.duplicate_retries=2")
    # One sample, made of three model calls: two copies of the starter thrown away, then a new program.
    assert rows == [("evaluated", 3, 30, 15, pytest.approx(1.5))]
    assert len(generator.prompts) == 3 and not generator.answers
    assert [prompt.retry for prompt in generator.prompts] == [0, 1, 2]  # a language model samples each retry hotter
    assert summary.samples == 3 and summary.programs_evaluated == 1 and summary.duplicates_skipped == 0
    assert summary.duplicate_rate == pytest.approx(2 / 3)
    assert all("constants" in prompt.text and "tuned" in prompt.text for prompt in generator.prompts)  # gfo=oneplusone


def test_a_search_with_longer_episodes_tells_the_model_their_length(tmp_path):
    _, rows, generator = scripted_search(tmp_path, [STARTER_WITH.format("-np.sign(obs[2])")], "+task.env.horizon=200")
    assert [row[0] for row in rows] == ["evaluated"]
    [prompt] = generator.prompts
    assert "Episodes in this search last 200 control steps (4 s); the task's default is 1000." in prompt.text


def test_duplicate_retries_are_bounded_then_the_duplicate_is_recorded(tmp_path):
    answers = [STARTER_WITH.format(0.0)] * 2 + [STARTER_WITH.format("-np.sign(obs[2])")]
    summary, rows, generator = scripted_search(tmp_path, answers, "search.duplicate_retries=1")
    assert rows == [("duplicate", 2, 20, 10, pytest.approx(1.0)), ("evaluated", 1, 10, 5, pytest.approx(0.5))]
    assert summary.samples == 3 and summary.duplicates_skipped == 1 and summary.duplicate_rate == pytest.approx(2 / 3)


def test_a_chat_model_is_told_what_its_answer_copied_and_why_one_cannot_be_used(tmp_path):
    """A chat model's wasted answer is answered in the same conversation: a copy of a shown
    version with other numbers (GFO tunes those), then a name it never defined (a NameError at
    the first step, before), then a new program; one sample of three model calls."""
    copy_of_starter = f"```python\n{STARTER_WITH.format(0.7)}```"
    undefined = "```python\ndef policy(obs):\n    return -2.0 * theta\n```"
    fixed = "```python\ndef policy(obs):\n    theta = np.arctan2(obs[1], obs[0])\n    return -2.0 * theta\n```"
    summary, rows, generator = scripted_search(tmp_path, [copy_of_starter, undefined, fixed], chat=True)
    assert rows == [("evaluated", 3, 30, 15, pytest.approx(1.5))] and summary.programs_evaluated == 1
    first, second, third = generator.prompts
    assert [m["role"] for m in first.messages] == ["system", "user"]
    assert [m["role"] for m in second.messages] == ["system", "user", "assistant", "user"]
    assert second.messages[:2] == first.messages and second.messages[2]["content"] == copy_of_starter
    assert "`policy_v0` with other numbers" in second.messages[3]["content"] and "another structure" in second.messages[3]["content"]
    assert third.messages[2]["content"] == undefined and "`theta` is used but never defined" in third.messages[3]["content"]
    assert [prompt.retry for prompt in generator.prompts] == [0, 1, 2]
    assert {prompt.island for prompt in generator.prompts} == {first.island} and third.parent_keys == first.parent_keys


def test_without_gfo_a_chat_model_is_told_it_repeated_a_program_and_other_generators_keep_unusable_answers(tmp_path):
    copy_of_starter = f"```python\n{STARTER_WITH.format(0.0)}```"
    summary, rows, generator = scripted_search(tmp_path / "none", [copy_of_starter, STARTER_WITH.format(0.3)], "gfo=none", chat=True)
    assert "Your `policy` is `policy_v0` again" in generator.prompts[1].messages[3]["content"]
    assert "numbers are tuned" not in generator.prompts[1].messages[3]["content"] and rows[0][:2] == ("evaluated", 2)
    # A completion-form generator is never followed up: an answer without a program is recorded as such.
    summary, rows, generator = scripted_search(tmp_path / "completion", ["def policy(obs):\n    return theta\n"] * 2)
    assert [row[:2] for row in rows] == [("unusable", 1), ("unusable", 1)] and len(generator.prompts) == 2


def test_a_store_written_before_model_calls_were_counted_opens_with_one_call_per_sample(tmp_path):
    store = ProgramStore(tmp_path / "programs.db")
    store.add(SampleRecord(sample=0, batch=0, status="duplicate", island=0, parent_keys=(), generator="old", raw="x"))
    for column in ("model_calls", "prompt_shown", "coverage"):  # the schema of older stores
        store.connection.execute(f"ALTER TABLE samples DROP COLUMN {column}")
    store.close()
    reopened = ProgramStore(tmp_path / "programs.db")
    reopened.add(SampleRecord(
        sample=1, batch=1, status="duplicate", island=0, parent_keys=(), generator="new", raw="y", model_calls=3, prompt_shown="z",
        coverage=((10, 0, 0), (10, 4, 0)),
    ))
    assert [(record.sample, record.model_calls, record.prompt_shown, record.coverage) for record in reopened.records()] == [
        (0, 1, "", None), (1, 3, "z", ((10, 0, 0), (10, 4, 0))),
    ]
    reopened.close()


def test_an_answer_holding_a_lone_surrogate_is_an_unusable_sample_and_the_search_goes_on(tmp_path):
    # The OpenAI client returns "\ud800" for a server's JSON "\ud800": it used to raise
    # UnicodeEncodeError out of the search (traceback, exit 1, no summary).
    answers = ["```python\ndef policy(obs):\n    return -0.5 * obs[2]  # \ud800\n```", "```python\ndef policy(obs):\n    return -0.4 * obs[2]\n```"]
    summary, rows, _ = scripted_search(tmp_path, answers, "gfo=none")
    assert [row[0] for row in rows] == ["unusable", "evaluated"] and summary.samples == 2
    with sqlite3.connect(tmp_path / "run" / "programs.db") as connection:
        [(raw, failure)] = connection.execute("SELECT raw, failure FROM samples WHERE sample = 0").fetchall()
    assert "# \ufffd" in raw and failure == "unusable output: the output holds a character that is not text at line 3 (an undecodable byte or a lone surrogate)"
    assert json.loads((tmp_path / "run" / "summary.json").read_text())["unusable_outputs"] == 1
