"""The table of `scripts/shown_as_run_experiment.sh`: per job, its variant (`database.shown_as_run`),
seed, best and held-out scores, model calls, programs evaluated (per 100 calls: the yield), and how
much showing programs as they ran could change: the evaluated programs with a branch never taken
(`colmo.coverage.prune` finds one) and the samples whose prompt showed such a program (counted
only where shown_as_run counted the branches); then each
variant's mean ± std over seeds and the difference with its bootstrap interval (`colmo.comparison`).

    python scripts/shown_as_run_summary.py runs/shown-as-run/sweep
"""

from __future__ import annotations

import json
import sqlite3
import sys
from pathlib import Path

from omegaconf import OmegaConf

from colmo.comparison import difference, mean_std
from colmo.coverage import prune


def job_row(job: Path) -> dict:
    overrides = dict(o.split("=", 1) for o in OmegaConf.load(job / ".hydra" / "overrides.yaml"))
    summary = json.loads((job / "summary.json").read_text())
    with sqlite3.connect(f"file:{job / 'programs.db'}?mode=ro", uri=True) as db:
        rows = db.execute("SELECT key, code, coverage, parent_keys, status FROM samples ORDER BY sample").fetchall()
    pruned = {key for key, code, coverage, _, status in rows if status == "evaluated" and coverage and prune(code, json.loads(coverage))}
    shown_pruned = sum(1 for *_, parents, _ in rows if parents and pruned & set(json.loads(parents)))
    return {
        "shown_as_run": overrides["database.shown_as_run"], "seed": int(overrides["seed"]),
        "best": summary["best_score"], "heldout": summary.get("best_heldout_score"), "samples": summary["samples"],
        "evaluated": summary["programs_evaluated"], "pruned": len(pruned), "prompts": shown_pruned,
    }


def main() -> None:
    jobs = sorted(p.parent for p in Path(sys.argv[1]).glob("*/summary.json"))
    rows = sorted((job_row(job) for job in jobs), key=lambda r: (r["shown_as_run"] != "True", r["seed"]))
    print("| shown as run | seed | best | held-out | model calls | programs evaluated | with a branch never taken | prompts showing one |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        # Without shown_as_run the branches are not counted while a program is scored: nothing to say.
        pruned, prompts = (r["pruned"], r["prompts"]) if r["shown_as_run"] == "True" else ("—", "—")
        print(f"| {r['shown_as_run']} | {r['seed']} | {r['best']:.2f} | {r['heldout']:.2f} | {r['samples']} | {r['evaluated']} | {pruned} | {prompts} |")
    variants = {v: [r for r in rows if r["shown_as_run"] == v] for v in ("False", "True")}
    if all(variants.values()):
        for metric in ("best", "heldout", "evaluated"):
            stored, shown = ([r[metric] for r in variants[v]] for v in ("False", "True"))
            print(f"\n{metric}: as stored {mean_std(stored)}, as run {mean_std(shown)}; as run less as stored: {difference(stored, shown).text()}")


if __name__ == "__main__":
    main()
