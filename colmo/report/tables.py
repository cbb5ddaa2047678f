"""The report's Markdown: Table I (the paper's, with held-out scores beside training ones; a
score bold only where its difference to the other is significant), each variant against the
task's baseline with the difference's interval and the cost of each, one line per run, the
runs left out, and each variant's best policy."""

from __future__ import annotations

import functools
import tempfile
from pathlib import Path
from typing import Callable, Optional, Sequence

from mlflow import MlflowClient
from mlflow.entities import Run

from colmo.comparison import difference, mean_std
from colmo.report.selection import RunCurves, Variant
from colmo.store import BEST_POLICY_FILE


def reward_cell(variant: Optional[Variant]) -> str:
    return mean_std([run.final for run in variant.runs]) if variant else "—"


def heldout_cell(variant: Optional[Variant]) -> str:
    """Mean ± std of the best programs' held-out scores, over the seeds that have one."""
    if variant is None:
        return "—"
    scores = [run.heldout for run in variant.runs if run.heldout is not None]
    if not scores:
        return "—"
    return mean_std(scores) + ("" if len(scores) == len(variant.runs) else f" ({len(scores)}/{len(variant.runs)} seeds)")


def target_cell(variant: Optional[Variant]) -> str:
    """Mean ± std over the seeds that reached the target, and how many did."""
    if variant is None or variant.runs[0].target is None:
        return "—"
    reached = [run.samples_to_target for run in variant.runs if run.samples_to_target is not None]
    count = f"({len(reached)}/{len(variant.runs)} seeds)"
    return f"{mean_std(reached, 0)} {count}" if reached else f"not reached {count}"


def _values(variant: Variant, value: Callable[[RunCurves], Optional[float]]) -> list[float]:
    return [value(run) for run in variant.runs if value(run) is not None]


def _bold_better(cells: list[str], variants: Sequence[Optional[Variant]], value: Callable[[RunCurves], Optional[float]]) -> list[str]:
    """Bold the better of the two, as the paper does, but only where the difference of their
    means is significant (its bootstrap interval leaves out 0)."""
    if None in variants:
        return cells
    baseline, other = (_values(variant, value) for variant in variants)
    if not baseline or not other:
        return cells
    change = difference(baseline, other)
    if not change.significant:
        return cells
    better = 1 if change.mean > 0 else 0
    return [f"**{cell}**" if index == better else cell for index, cell in enumerate(cells)]


def dims(variants: list[Variant]) -> tuple[str, str]:
    params = next((run.run.data.params for v in variants for run in v.runs if "spec.observation_size" in run.run.data.params), {})
    return params.get("spec.observation_size", "—"), params.get("spec.action_size", "—")


def table_one(tasks: dict[str, list[Variant]]) -> list[str]:
    """Table I: one row per task and GFO variant, against the task's no-GFO runs (the first
    no-GFO variant, when settings other than GFO differ too)."""
    lines = [
        "| Task | State dim | Action dim | GFO | Reward, no GFO | Reward, GFO | Held-out, no GFO | Held-out, GFO "
        "| Target | Samples to target, no GFO | Samples to target, GFO |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for task, variants in tasks.items():
        baseline = next((v for v in variants if not v.gfo), None)
        tuned = [v for v in variants if v.gfo] or [None]
        observation_size, action_size = dims(variants)
        target = variants[0].runs[0].target
        for variant in tuned:
            pair = (baseline, variant)
            rewards = _bold_better([reward_cell(v) for v in pair], pair, lambda run: run.final)
            heldouts = _bold_better([heldout_cell(v) for v in pair], pair, lambda run: run.heldout)
            lines.append(
                f"| {task} | {observation_size} | {action_size} | {variant.name if variant else '—'} | "
                f"{' | '.join(rewards)} | {' | '.join(heldouts)} | "
                f"{'—' if target is None else f'{target:g}'} | {target_cell(baseline)} | {target_cell(variant)} |"
            )
    return lines


def baseline_of(variants: list[Variant]) -> Variant:
    """What a task's variants are compared with: its first variant without GFO, else its first."""
    return next((v for v in variants if not v.gfo), variants[0])


def _seconds(run: RunCurves) -> float:
    info = run.run.info
    return run.run.data.metrics.get("seconds", (info.end_time - info.start_time) / 1000)


def _mean_cell(values: list[float], digits: int = 0) -> str:
    return mean_std(values, digits) if values else "—"


def comparison_table(tasks: dict[str, list[Variant]]) -> list[str]:
    """Each variant against its task's baseline: the difference of the mean best score and of
    the mean held-out score with their bootstrap intervals (`colmo.comparison`), and what each
    variant cost, mean ± std over its seeds: wall seconds, the workers' busy seconds, model
    calls and candidate evaluations."""
    lines = [
        "| Task | Variant | Seeds | Best score | Difference to the baseline | Held-out | Difference to the baseline "
        "| Wall s | Worker s | Model calls | Evaluations |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for task, variants in tasks.items():
        baseline = baseline_of(variants)
        for variant in variants:
            cells = []
            for value in (lambda run: run.final, lambda run: run.heldout):
                mine, theirs = _values(variant, value), _values(baseline, value)
                change = "baseline" if variant is baseline else (difference(theirs, mine).text() if mine and theirs else "—")
                cells += [_mean_cell(mine, 1), change]
            cost = [
                _mean_cell([_seconds(run) for run in variant.runs]), _mean_cell(_values(variant, lambda run: run.run.data.metrics.get("worker_seconds"))),
                _mean_cell([float(run.steps[-1]) for run in variant.runs]),
                _mean_cell(_values(variant, lambda run: run.run.data.metrics.get("evaluations"))),
            ]
            lines.append(f"| {task} | {variant.name} | {len(variant.runs)} | {' | '.join(cells)} | {' | '.join(cost)} |")
    return lines


def runs_table(tasks: dict[str, list[Variant]]) -> list[str]:
    lines = [
        "| Run | Variant | Seed | Best score | Held-out | Samples | Evaluations | Samples to target | Seconds | Overrides |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for variants in tasks.values():
        for variant in variants:
            for run in variant.runs:
                info, metrics = run.run.info, run.run.data.metrics
                reached = run.samples_to_target
                evaluations = metrics.get("evaluations")
                seconds = _seconds(run)
                lines.append(
                    f"| {info.run_name} | {variant.name} | {run.seed} | {run.final:.1f} | "
                    f"{'—' if run.heldout is None else f'{run.heldout:.1f}'} | {run.steps[-1]} | "
                    f"{'—' if evaluations is None else f'{evaluations:.0f}'} | {'—' if reached is None else reached} | "
                    f"{seconds:.0f} | `{run.run.data.tags.get('overrides', '')}` |"
                )
    return lines


def generation_table(tasks: dict[str, list[Variant]]) -> list[str]:
    """Per run, where the samples and the time went: the share of samples that were valid
    programs (of those not skipped as duplicates) and that were duplicates, the generator's
    tokens per second, and how busy the generator and the evaluation workers were."""
    lines = [
        "| Run | Variant | Valid programs | Duplicates | Tokens/s | Generator busy | Evaluator busy |",
        "|---|---|---|---|---|---|---|",
    ]
    percent = lambda value: "—" if value is None else f"{100 * value:.0f}%"  # noqa: E731
    for variants in tasks.values():
        for variant in variants:
            for run in variant.runs:
                metrics = run.run.data.metrics
                tokens = metrics.get("tokens_per_second")
                lines.append(
                    f"| {run.run.info.run_name} | {variant.name} | {percent(metrics.get('valid_program_rate'))} | "
                    f"{percent(metrics.get('duplicate_rate'))} | {'—' if not tokens else f'{tokens:.1f}'} | "
                    f"{percent(metrics.get('generator_busy'))} | {percent(metrics.get('evaluator_busy'))} |"
                )
    return lines


def readability_table(tasks: dict[str, list[Variant]]) -> list[str]:
    """Per run, its best policy's readability report (`colmo.readability`, the
    `readability_*` metrics): lines and parameters as found and as simplified, branches decided
    the same way at every test, clips that return a limit for every value, divisions by zero,
    misleading names, comparisons the code decides."""
    lines = [
        "| Run | Variant | Lines | Parameters | Simplified lines | Simplified parameters | Branches never taken | Clips at a limit "
        "| Divisions by zero | Misleading names | Comparisons decided |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for variants in tasks.values():
        for variant in variants:
            for run in variant.runs:
                metrics = run.run.data.metrics
                cell = functools.partial(_readability_cell, metrics)
                never = cell("branches_never_taken") + ("" if metrics.get("readability_branches") is None else f" of {cell('branches')}")
                lines.append(
                    f"| {run.run.info.run_name} | {variant.name} | {cell('lines')} | {cell('parameters')} | {cell('simplified_lines')} | "
                    f"{cell('simplified_parameters')} | {never} | {cell('clips_at_a_limit')} | {cell('divisions_by_zero')} | {cell('misleading_names')} | "
                    f"{cell('comparisons_decided')} |"
                )
    return lines


def _readability_cell(metrics: dict[str, float], name: str) -> str:
    value = metrics.get(f"readability_{name}")
    return "—" if value is None else f"{value:.0f}"


def _per_100_calls(run: RunCurves, generator: str = "") -> Optional[float]:
    """Programs evaluated per 100 model calls (of `generator`'s, in a search of several)."""
    metrics, suffix = run.run.data.metrics, f"_{generator}" if generator else ""
    calls, programs = metrics.get(f"samples{suffix}"), metrics.get(f"programs_evaluated{suffix}")
    return None if not calls or programs is None else 100.0 * programs / calls


def yield_table(tasks: dict[str, list[Variant]]) -> list[str]:
    """Per variant, the model calls that yield an evaluated program: per 100 calls, mean ± std
    over its seeds and each seed; for a search of several generators (`search.fill`), each one's."""
    lines = ["| Variant | Generator | Programs per 100 model calls | Per seed |", "|---|---|---|---|"]
    for variants in tasks.values():
        for variant in variants:
            generators = sorted({name[len("samples_"):] for run in variant.runs for name in run.run.data.metrics if name.startswith("samples_")})
            for generator in ["", *generators]:
                values = [_per_100_calls(run, generator) for run in variant.runs]
                known = [value for value in values if value is not None]
                seeds = ", ".join("—" if value is None else f"{value:.1f}" for value in values)
                lines.append(f"| {variant.name} | {generator or 'all'} | {mean_std(known) if known else '—'} | {seeds} |")
    return lines


def left_out_lines(left_out: list[tuple[Run, str]]) -> list[str]:
    if not left_out:
        return ["None: every search run of the experiment(s) counts."]
    return [f"- `{run.info.run_name}` ({run.info.run_id[:8]}): {reason}" for run, reason in left_out]


def best_policies(client: MlflowClient, tasks: dict[str, list[Variant]]) -> list[str]:
    """Each variant's best run's `best_policy.py` artifact, as a code block."""
    lines = []
    with tempfile.TemporaryDirectory() as scratch:
        for task, variants in tasks.items():
            for variant in variants:
                best = max(variant.runs, key=lambda run: run.final)
                path = client.download_artifacts(best.run.info.run_id, BEST_POLICY_FILE, scratch)
                code = Path(path).read_text().rstrip()
                lines += [
                    f"### {task}, {variant.name}",
                    "",
                    f"Best of {len(variant.runs)} seed(s): run `{best.run.info.run_name}`, score {best.final:.1f}.",
                    "",
                    "```python",
                    code,
                    "```",
                    "",
                ]
    return lines
