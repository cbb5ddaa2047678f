"""`finish.retune_budget`: the search's final policy re-tuned at a large budget (`colmo.finish`),
run end to end as a user runs it, and its held-out score checked against `colmo-evaluate`'s."""

import ast
import json

import pytest
from conftest import run_colmo
from mlflow import MlflowClient

from colmo.program import parametrize
from colmo.store import RETUNED_POLICY_FILE, SIMPLIFIED_POLICY_FILE, SUMMARY_FILE


def test_the_finish_re_tunes_the_simplified_policy_and_scores_it_on_the_held_out_episodes(tmp_path):
    result = run_colmo(
        "colmo", "task=pendulum", "tracker=mlflow", "search.progress=false", "search.max_samples=4", "gfo.budget=5", "finish.retune_budget=40",
        # No deletions: the simplified policy keeps its constants (a pendulum's winner can lose them all).
        "simplify.max_rounds=0", "heldout.episodes=5", "finish.render=false", "executor.workers=2", cwd=tmp_path, timeout=600,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    run_dir = next(tmp_path.glob("outputs/pendulum/*/"))
    summary = json.loads((run_dir / SUMMARY_FILE).read_text())
    retuned, simplified = summary["retuned"], summary["simplified"]
    assert retuned["from"] == "simplified" and retuned["gfo"] == "oneplusone" and retuned["file"] == RETUNED_POLICY_FILE
    # The whole budget, from the simplified policy's own constants and scores.
    assert retuned["evaluations"] >= 40 and not retuned["cut_short"]
    assert retuned["score_initial"] == pytest.approx(simplified["score"], rel=1e-9) and retuned["heldout_score_initial"] == simplified["heldout_score"]
    assert retuned["score"] >= retuned["score_initial"] and retuned["heldout_score"] is not None
    assert retuned["n_params"] == parametrize((run_dir / SIMPLIFIED_POLICY_FILE).read_text()).n_params > 0
    written = (run_dir / RETUNED_POLICY_FILE).read_text()
    assert written.startswith("# colmo: the simplified policy of pendulum re-tuned (gfo=oneplusone") and written.endswith(retuned["code"] + "\n")
    ast.parse(written)
    assert "re-tuning" in (run_dir / "colmo.log").read_text()
    # MLflow: both scores as metrics, the policy as a file of the run.
    client = MlflowClient(f"sqlite:///{tmp_path / 'mlruns.db'}")
    (run,) = client.search_runs([client.get_experiment_by_name("pendulum").experiment_id])
    assert run.data.metrics["retuned_score"] == pytest.approx(retuned["score"], rel=5e-4)
    assert run.data.metrics["retuned_heldout_score"] == pytest.approx(retuned["heldout_score"], rel=5e-4)
    assert RETUNED_POLICY_FILE in {f.path for f in client.list_artifacts(run.info.run_id)}
    # The same held-out episodes as every tool's with this seed: colmo-evaluate measures what the summary says.
    evaluated = run_colmo(
        "colmo.heldout", "task=pendulum", f"policy_file={run_dir / RETUNED_POLICY_FILE}", "seed=0", "episodes=5", cwd=tmp_path, timeout=300,
    )
    assert evaluated.returncode == 0, evaluated.stderr[-3000:]
    assert json.loads(evaluated.stdout.strip().splitlines()[-1])["score"] == pytest.approx(retuned["heldout_score"], rel=1e-9)
