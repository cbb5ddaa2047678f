"""`python -m colmo.optimize`: tuning one policy file end to end, and its user errors."""

import importlib.metadata
import json

import pytest
from conftest import last_json_line, refused, run_colmo

from colmo.optimize.__main__ import main as colmo_optimize

RAW_ANSWER = '''Sure! Here is an improved controller. It switches between energy pumping and a PD law:

```python
import numpy as np

def policy_v2(obs):
    """Improved version of policy_v1."""
    angle = np.arctan2(-obs[1], obs[0])
    if np.abs(angle) > np.pi / 6.512:
        return np.sign(obs[2])
    return 9.437 * np.sin(angle) - 2.746 * obs[2]
```

This should swing the pendulum up faster.
'''


def optimize(tmp_path, *overrides):
    return run_colmo("colmo.optimize", *overrides, "executor.workers=2", "heldout.episodes=10", cwd=tmp_path)


def test_mistuned_policy_gains_100_points_with_oneplusone(tmp_path, examples):
    # 3 training episodes: measured, +635 (+574 with the default 10, in twice the time)
    result = optimize(tmp_path, f"policy_file={examples / 'pendulum_mistuned.py'}", "gfo=oneplusone", "task.episodes=3")
    assert result.returncode == 0, result.stderr
    summary = last_json_line(result.stdout)
    assert summary["evaluations"] == 102  # budget 100, the readable 4-digit code, the referee's final score
    assert summary["n_params"] == 3 and summary["heldout_score"] is not None
    # Racing (on for the (1+1)-ES) stops candidates early: fewer steps than every episode of
    # every evaluation; the reported score is still over all the episodes.
    assert summary["raced_out"] > 0 and 0 < summary["steps"] < summary["evaluations"] * 3 * 1000
    assert len(summary["returns"]) == 3
    assert summary["score"] >= summary["score_initial"] + 100, summary
    assert "score with its own constants" in result.stdout
    written = json.loads(next(tmp_path.glob("outputs/optimize/*/*/result.json")).read_text())
    assert written["score"] == summary["score"] and written["provenance"]["libraries"]["nevergrad"] == importlib.metadata.version("nevergrad")
    tuned = next(tmp_path.glob("outputs/optimize/*/*/tuned_policy.py")).read_text()
    assert tuned.startswith("# tuned by colmo-optimize") and tuned.endswith(summary["code"] + "\n")


@pytest.mark.parametrize("method", ["bo", "cma"])
def test_bo_and_cma_also_improve_it(tmp_path, examples, method):
    result = optimize(tmp_path, f"policy_file={examples / 'pendulum_mistuned.py'}", f"gfo={method}", "gfo.budget=60", "gfo.workers=2", "task.episodes=3")
    assert result.returncode == 0, result.stderr
    summary = last_json_line(result.stdout)
    assert summary["score"] > summary["score_initial"] + 50, summary  # measured: bo +650, cma +191
    if method == "bo":  # no racing (BO models the values): every evaluation simulates every episode
        assert summary["steps"] == summary["evaluations"] * 3 * 1000 and summary["raced_out"] == 0


def test_raw_model_answer_is_extracted(tmp_path):
    answer = tmp_path / "answer.md"
    answer.write_text(RAW_ANSWER)
    result = optimize(tmp_path, f"policy_file={answer}", "gfo=none", "task.episodes=3")
    assert result.returncode == 0, result.stderr
    summary = last_json_line(result.stdout)
    assert summary["n_params"] == 3 and summary["evaluations"] == 1
    assert summary["score"] == summary["score_initial"] > 0
    assert summary["code"].startswith("import numpy as np\n\ndef policy(obs):")


def test_a_failing_policy_is_reported_not_crashed(tmp_path):
    broken = tmp_path / "broken.py"
    broken.write_text("def policy(obs):\n    return obs[0] / 0.0\n")
    result = optimize(tmp_path, f"policy_file={broken}", "gfo=none", "task.episodes=2")
    assert result.returncode == 1
    summary = last_json_line(result.stdout)
    assert summary["score"] is None and summary["failure"].startswith("non-finite action") or "exception" in summary["failure"]
    assert "Traceback" not in result.stderr


@pytest.mark.parametrize(
    "overrides, message",
    [
        (["gfo=foo"], "Could not find 'gfo/foo'"),
        (["gfo.budget=-5"], "gfo.budget must be >= 1, got -5"),
        (["gfo.budget=abc"], "gfo.budget"),
        (["gfo.nonsense=1"], "nonsense"),
        (["task=nope"], "Could not find 'task/nope'"),
        (["task.episodes=0"], "task.episodes must be >= 1"),
        ([], "missing value for policy_file"),
        (["policy_file=/no/such/file.py"], "policy_file not found: /no/such/file.py"),
        (["task.spec=/no/such/spec.py"], "spec file not found"),
    ],
)
def test_user_errors_end_in_one_line_and_exit_2(tmp_path, monkeypatch, examples, overrides, message):
    """Checked in process; tests/test_cli.py runs `colmo-optimize` on a bad policy_file."""
    if not any(o.startswith("policy_file") for o in overrides) and overrides:
        overrides = [*overrides, f"policy_file={examples / 'paper_pendulum.py'}"]
    monkeypatch.chdir(tmp_path)
    code, line = refused(colmo_optimize, *overrides)
    assert code == 2 and message in line, line


@pytest.mark.parametrize(
    "content, message",
    [
        ("Sorry, I cannot help with that.", "no usable policy in"),
        ("def policy(obs):\n    return (obs[0] +\n", "no usable policy in"),
        ("import os\ndef policy(obs):\n    return os.getpid()\n", "forbidden: import os"),
    ],
)
def test_unusable_policy_files_exit_2(tmp_path, monkeypatch, content, message):
    path = tmp_path / "policy.py"
    path.write_text(content)
    monkeypatch.chdir(tmp_path)
    code, line = refused(colmo_optimize, f"policy_file={path}")
    assert code == 2 and message in line, line
