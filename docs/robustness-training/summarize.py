"""Tables and curves of the nominal-vs-perturbed training comparison (issue 23 part 3).

Reads each run that `run.sh` saved under `runs/<task>_<variant>_s<seed>/` (the search's
`summary.json`, the winner's `colmo-evaluate robustness=true` JSON line as `robustness.json`)
and prints markdown tables: per variant the mean ± standard deviation over seeds, then every
seed; and writes `curves.png`: per task, the held-out score with every factor together against
the magnitude, one line per variant (mean, band: ± std), seeds as thin lines.

    python docs/robustness-training/summarize.py
"""

from __future__ import annotations

import json
import statistics
from pathlib import Path

HERE = Path(__file__).parent
VARIANTS = ("nominal", "perturbed")
FACTORS_SHOWN = ("mass", "damping", "friction", "gain", "obs_noise", "action_noise")  # frictionloss: none in these models


def load() -> dict[tuple[str, str], list[dict]]:
    runs: dict[tuple[str, str], list[dict]] = {}
    for folder in sorted((HERE / "runs").iterdir()):
        task, variant, seed = folder.name.rsplit("_", 2)
        evaluation = json.loads((folder / "robustness.json").read_text())
        summary = json.loads((folder / "summary.json").read_text())
        rows = {entry["magnitude"]: entry for entry in evaluation["robustness"]}
        delays = {entry["delay_steps"]: entry["score"] for entry in evaluation["delay"]}
        run = {
            "seed": int(seed.removeprefix("s")), "training": summary["best_score"], "samples": summary["samples"],
            "nominal": evaluation["score"], "grid_nominal": rows[0.0]["all"], "all_10": rows[0.1]["all"], "all_20": rows[0.2]["all"], "delay_1": delays[1],
            "curve": [(m, rows[m]["all"]) for m in sorted(rows)],
            **{f"{name}_20": rows[0.2][name] for name in FACTORS_SHOWN},
        }
        run["worst"] = min(v for entry in evaluation["robustness"] for k, v in entry.items() if k != "magnitude" and v is not None)
        runs.setdefault((task, variant), []).append(run)
    return runs


def spread(values: list[float]) -> str:
    if len(values) == 1:
        return f"{values[0]:.1f} (1 seed)"
    return f"{statistics.mean(values):.1f} ± {statistics.stdev(values):.1f}"


def tables(runs: dict[tuple[str, str], list[dict]]) -> str:
    headline = ("training", "nominal", "grid_nominal", "all_10", "all_20", "delay_1", "worst")
    lines = [
        "| task | training | seeds | training score | held-out nominal (20 ep.) | grid: nominal | all factors 10% | all factors 20% "
        "| delay 1 step | worst grid point |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for (task, variant), items in sorted(runs.items()):
        lines.append(f"| {task} | {variant} | {len(items)} | " + " | ".join(spread([r[k] for r in items]) for k in headline) + " |")
    lines += ["", "Each factor alone at 20% (held-out, 3 episodes per point), mean ± std over seeds:", ""]
    lines += ["| task | training | " + " | ".join(FACTORS_SHOWN) + " |", "|---|---|" + "---|" * len(FACTORS_SHOWN)]
    for (task, variant), items in sorted(runs.items()):
        lines.append(f"| {task} | {variant} | " + " | ".join(spread([r[f"{n}_20"] for r in items]) for n in FACTORS_SHOWN) + " |")
    lines += ["", "Every seed:", "", "| task | training | seed | samples | " + " | ".join(headline) + " |", "|---|---|---|---|" + "---|" * len(headline)]
    for (task, variant), items in sorted(runs.items()):
        for r in sorted(items, key=lambda r: r["seed"]):
            lines.append(f"| {task} | {variant} | {r['seed']} | {r['samples']} | " + " | ".join(f"{r[k]:.1f}" for k in headline) + " |")
    return "\n".join(lines)


def curves(runs: dict[tuple[str, str], list[dict]], path: Path) -> None:
    from matplotlib.figure import Figure

    tasks = sorted({task for task, _ in runs})
    figure = Figure(figsize=(4.2 * len(tasks), 3.2), layout="constrained")
    for axes, task in zip(figure.subplots(1, len(tasks), squeeze=False)[0], tasks):
        for variant, color in zip(VARIANTS, ("tab:blue", "tab:red")):
            items = runs.get((task, variant), [])
            if not items:
                continue
            x = [100 * m for m, _ in items[0]["curve"]]
            ys = [[score for _, score in r["curve"]] for r in items]
            for y in ys:
                axes.plot(x, y, color=color, linewidth=0.6, alpha=0.5)
            mean = [statistics.mean(column) for column in zip(*ys)]
            std = [statistics.stdev(column) if len(column) > 1 else 0.0 for column in zip(*ys)]
            axes.plot(x, mean, color=color, marker="o", linewidth=2, label=f"{variant} training ({len(items)} seeds)")
            axes.fill_between(x, [m - s for m, s in zip(mean, std)], [m + s for m, s in zip(mean, std)], color=color, alpha=0.15)
        axes.set(title=f"{task}: every factor together", xlabel="perturbation magnitude (%)", ylabel="held-out score")
        axes.legend(fontsize="small")
    figure.savefig(path, dpi=80)


if __name__ == "__main__":
    found = load()
    print(tables(found))
    curves(found, HERE / "curves.png")
    print(f"\nwrote {HERE / 'curves.png'}")
