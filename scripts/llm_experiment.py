"""Long language-model experiments: variants x seeds of `python -m colmo`, each run in a fixed
directory of its own and resumable, and their report, read from those directories.

    python scripts/llm_experiment.py run OUT --variant gfo=none --variant gfo=oneplusone --seeds 0 1 2 -- \\
        task=pendulum llm=llamacpp llm.model_path=M.gguf search.max_samples=200
    python scripts/llm_experiment.py report OUT [--out OUT/report.md]

`run` starts the runs one after another, seed by seed (each variant of seed 0, then of seed 1, ...),
`OUT/<variant>/s<seed>` each (`gfo=none` in `OUT/gfo-none/`): a run whose
`summary.json` says it reached its limits is skipped, one that stopped before (killed, the
machine restarted, Ctrl-C) is resumed (`resume=`), so the same command, run again, finishes
what is left. Overrides after `--` apply to every run; a variant is one or more overrides
(`--variant "gfo=oneplusone gfo.budget=50"`).

`report` reads every `OUT/*/s*/summary.json` (and the run's `.hydra/config.yaml`) and writes
Markdown beside a figure (`best_so_far.png`): per variant, best score so far against model
calls and against seconds of generation (mean over seeds, band from the lowest to the highest
seed, each seed thin; the seconds are the model's, summed over the calls from the store, which
count the time of every process of a resumed run and leave out the time between them; with one
model thread the model is busy most of a run, and the report gives each run's share); model calls
to the task's `target_score`; final best and held-out score, mean ± std and per seed; programs
evaluated, per 100 model calls, duplicate and valid-program rates; and, for two variants, a
bootstrap interval of the difference of their mean final bests (seeds resampled with
replacement within each variant; with 3 seeds a variant it is coarse, and it says so).
Runs still going, or stopped, are listed and left out of the figures; the share of model calls
that yield an evaluated program is read from every run's store, finished or not, over its first
`--first` (48) model calls and over all it has settled.
"""

from __future__ import annotations

import argparse
import json
import re
import shlex
import sqlite3
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Sequence

import numpy as np
import yaml
from matplotlib.figure import Figure

from colmo.record import EVALUATED, FINISHED, PENDING
from colmo.report.figure import COLORS, draw_seeds
from colmo.report.tables import mean_std
from colmo.store import STORE_FILE, SUMMARY_FILE, recorded_elapsed

REPORT_FILE = "report.md"
PLOT_FILE = "best_so_far.png"
BOOTSTRAP_DRAWS = 10_000


def variant_dir(variant: str) -> str:
    """A directory name for a variant's overrides that Hydra takes in `hydra.run.dir=` (no `=`
    or `,`): `gfo=none` -> `gfo-none`, `gfo=oneplusone gfo.budget=20` -> `gfo-oneplusone_gfo.budget-20`."""
    return re.sub(r"[^\w.+-]+", "_", "_".join(variant.split()).replace("=", "-"))


def summary_of(run_dir: Path) -> Optional[dict]:
    try:
        return json.loads((run_dir / SUMMARY_FILE).read_text())
    except (OSError, ValueError):
        return None


def run_all(out: Path, variants: Sequence[str], seeds: Sequence[int], overrides: Sequence[str]) -> int:
    """Each (variant, seed) run in turn, seed by seed (every variant of a seed before the next
    seed, so that an experiment cut short leaves paired runs), skipping finished ones and
    resuming stopped ones; the exit status of the first run that fails, else 0."""
    for seed in seeds:
        for variant in variants:
            run_dir = out / variant_dir(variant) / f"s{seed}"
            summary = summary_of(run_dir)
            if summary is not None and summary["stop_reason"] in FINISHED:
                print(f"{run_dir}: finished ({summary['stop_reason']}), skipped", flush=True)
                continue
            resume = [f"resume={run_dir}"] if (run_dir / "programs.db").is_file() else []
            command = [
                sys.executable, "-m", "colmo", *overrides, *variant.split(), f"seed={seed}", f"hydra.run.dir={run_dir}", *resume,
            ]
            print(("resuming " if resume else "starting ") + shlex.join(command), flush=True)
            status = subprocess.call(command)
            if status != 0:
                print(f"{run_dir}: exit status {status}; run the same command again to resume it", file=sys.stderr)
                return status
    return 0


@dataclass
class Run:
    variant: str
    seed: int
    summary: dict
    target: Optional[float]
    processes: int = 1  # the colmo processes that ran it (a run stopped and resumed: more than one)
    whole_time: bool = True  # its summary's seconds count every process (colmo records them since 53131fe)
    clock: Optional["GenerationClock"] = None  # seconds of generation by model calls, from its store

    @property
    def seconds(self) -> str:
        """The run's seconds, said to be the last process's alone where the code that ran it
        counted only that one."""
        seconds = f"{self.summary['seconds']:.0f}"
        return seconds if self.whole_time or self.processes == 1 else f"{seconds} (the last of {self.processes} processes)"

    @property
    def calls(self) -> int:
        return self.summary["samples"]

    @property
    def evaluated(self) -> int:
        return self.summary["programs_evaluated"]

    @property
    def duplicate_answers(self) -> int:
        return round(self.summary["duplicate_rate"] * self.calls)

    @property
    def failed(self) -> int:
        return self.summary["failures"] + self.summary["unusable_outputs"]

    @property
    def per_100_calls(self) -> float:
        return 100 * self.evaluated / self.calls if self.calls else 0.0

    @property
    def best(self) -> float:
        return self.summary["best_score"]

    @property
    def heldout(self) -> Optional[float]:
        return self.summary["best_heldout_score"]

    @property
    def curve(self) -> tuple[list[float], list[float]]:
        """Best score so far against model calls, held to the last call."""
        points = [tuple(point) for point in self.summary["best_so_far"]]
        x, best = [float(calls) for calls, _ in points], [score for _, score in points]
        if x[-1] < self.calls:
            x, best = [*x, float(self.calls)], [*best, best[-1]]
        return x, best

    @property
    def seconds_curve(self) -> Optional[tuple[list[float], list[float]]]:
        """Best score so far against seconds of generation, where the store says them."""
        if self.clock is None:
            return None
        x, best = self.curve
        return [self.clock.seconds_at(calls) for calls in x], best

    @property
    def calls_to_target(self) -> Optional[int]:
        if self.target is None:
            return None
        return next((int(calls) for calls, score in self.summary["best_so_far"] if score >= self.target), None)


def read_runs(out: Path) -> tuple[dict[str, list[Run]], list[str]]:
    """The finished runs under `out` by variant directory, in seed order, and a line for each
    run that has not finished."""
    variants: dict[str, list[Run]] = {}
    unfinished = []
    for run_dir in sorted(out.glob("*/s*"), key=lambda d: (d.parent.name, int(d.name[1:]) if d.name[1:].isdigit() else 0)):
        summary = summary_of(run_dir)
        if summary is None or summary["stop_reason"] not in FINISHED:
            unfinished.append(f"- `{run_dir}`: " + (f"stopped ({summary['stop_reason']})" if summary else "no summary yet (running, or killed)"))
            continue
        config = yaml.safe_load((run_dir / ".hydra" / "config.yaml").read_text())
        target = config.get("task", {}).get("target_score")
        seed = int(config["seed"])
        run = Run(run_dir.parent.name, seed, summary, target, *processes_of(run_dir), GenerationClock.of(run_dir / STORE_FILE))
        variants.setdefault(run_dir.parent.name, []).append(run)
    return variants, unfinished


@dataclass(frozen=True)
class GenerationClock:
    """A run's seconds of generation after each stored sample, by the model calls made so far."""

    calls: np.ndarray  # cumulative model calls after each sample, the starter's 0 first
    seconds: np.ndarray  # cumulative seconds of generation after each sample

    @classmethod
    def of(cls, store: Path) -> Optional["GenerationClock"]:
        rows = stored_samples(store, "model_calls, generation_seconds")
        if not rows:
            return None
        calls, seconds = np.array(rows, dtype=float).T
        return cls(np.concatenate([[0.0], np.cumsum(calls)]), np.concatenate([[0.0], np.cumsum(seconds)]))

    def seconds_at(self, calls: float) -> float:
        """The seconds of generation when the run had made `calls` model calls."""
        return float(self.seconds[min(np.searchsorted(self.calls, calls), len(self.seconds) - 1)])


def processes_of(run_dir: Path) -> tuple[int, bool]:
    """How many colmo processes ran the run (its log's "resumed" lines, plus the first), and
    whether its store records the time of all of them."""
    try:
        resumes = (run_dir / "colmo.log").read_text(errors="replace").count("[colmo.search][INFO] resumed ")
    except OSError:
        resumes = 0
    try:
        whole_time = recorded_elapsed(run_dir / STORE_FILE) is not None
    except sqlite3.DatabaseError:
        whole_time = False
    return 1 + resumes, whole_time


@dataclass(frozen=True)
class CallYield:
    """What a run's model calls yielded, from its store: over its first `first` calls (None if it
    has not settled that many yet) and over every call settled so far."""

    variant: str
    seed: int
    calls: int
    evaluated: int
    first_evaluated: Optional[int]
    # Of the first calls: the answers (each had a first call; `evaluated`: at that call), and the
    # calls that generated an answer again (a duplicate or unusable one thrown away), with the
    # programs evaluated they led to.
    first_answers: tuple[int, int] = (0, 0)  # (answers, evaluated at their first call)
    regenerations: tuple[int, int] = (0, 0)  # (calls, evaluated)

    @property
    def per_100(self) -> float:
        return 100 * self.evaluated / self.calls if self.calls else 0.0


def stored_samples(store: Path, columns: str) -> Optional[list[tuple]]:
    """`columns` of a run's samples in order, the starter left out, read without writing (the
    run may still be going); None where there is no store yet, or the file is not one."""
    if not store.is_file():
        return None
    try:
        connection = sqlite3.connect(f"file:{store}?mode=ro", uri=True)
    except sqlite3.DatabaseError:
        return None
    try:
        return connection.execute(f"SELECT {columns} FROM samples WHERE sample >= 0 ORDER BY sample").fetchall()
    except sqlite3.DatabaseError:  # not a store (yet): a run that has just started, a test's empty file
        return None
    finally:
        connection.close()


def call_yield(run_dir: Path, first: int) -> Optional[CallYield]:
    """The model-call yield of a run (finished or still running: its store is read, not written)."""
    rows = stored_samples(run_dir / STORE_FILE, "status, model_calls")
    if rows is None:
        return None
    calls = evaluated = 0
    first_evaluated = None
    answers = answered_at_once = regeneration_calls = evaluated_after_regeneration = 0
    for status, model_calls in rows:
        if status == PENDING:  # generated, not settled yet: neither counted nor anything after it
            break
        if calls + model_calls > first and first_evaluated is None:
            first_evaluated = evaluated
        if first_evaluated is None:  # every answer had a first call; model_calls - 1 generated it again
            answers += 1
            answered_at_once += status == EVALUATED and model_calls == 1
            regeneration_calls += model_calls - 1
            evaluated_after_regeneration += status == EVALUATED and model_calls > 1
        calls, evaluated = calls + model_calls, evaluated + (status == EVALUATED)
    if calls >= first and first_evaluated is None:
        first_evaluated = evaluated
    return CallYield(
        run_dir.parent.name, int(run_dir.name[1:]), calls, evaluated, first_evaluated,
        (answers, answered_at_once), (regeneration_calls, evaluated_after_regeneration),
    )


def yield_lines(out: Path, first: int) -> list[str]:
    """The report's section on model calls that yield an evaluated program, per run and per variant."""
    runs = [y for d in sorted(out.glob("*/s*")) if d.name[1:].isdigit() and (y := call_yield(d, first)) is not None]
    if not runs:
        return []
    lines = [
        "", "## Model calls that yield an evaluated program (each run's store, finished or not)", "",
        f"A call's answer is evaluated unless it is a duplicate (thrown away and generated again, or stored as one), "
        f"unusable or failed. First {first} calls: the programs evaluated among the answers to a run's first {first} model calls; "
        "of them, the answers evaluated at their first call (of all answers), and the calls that generated an answer again "
        "(after a duplicate or an unusable answer, thrown away) with the programs evaluated they led to.", "",
        f"| Variant | Seed | Calls settled | Programs evaluated | per 100 calls | First {first} calls: evaluated | per 100 "
        "| evaluated at the first call | generated again: calls, evaluated |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for y in sorted(runs, key=lambda y: (y.variant, y.seed)):
        head = "— | — | — | —" if y.first_evaluated is None else (
            f"{y.first_evaluated} | {100 * y.first_evaluated / first:.1f} | {y.first_answers[1]} of {y.first_answers[0]} "
            f"| {y.regenerations[0]}, {y.regenerations[1]}"
        )
        lines.append(f"| {y.variant} | {y.seed} | {y.calls} | {y.evaluated} | {y.per_100:.1f} | {head} |")
    lines += ["", f"Per variant, over the runs with at least {first} calls settled (mean ± sample std, each seed):", ""]
    for variant in sorted({y.variant for y in runs}):
        shares = [(y.seed, 100 * y.first_evaluated / first) for y in runs if y.variant == variant and y.first_evaluated is not None]
        if shares:
            each = ", ".join(f"s{seed} {share:.1f}" for seed, share in shares)
            lines.append(f"- {variant}: {mean_std([share for _, share in shares], 1)} per 100 of the first {first} calls over {len(shares)} seeds ({each})")
    return lines


def bootstrap_difference(first: Sequence[float], second: Sequence[float], draws: int = BOOTSTRAP_DRAWS, seed: int = 0) -> tuple[float, float, float]:
    """The difference of means `second - first` and its 95% percentile bootstrap interval
    (seeds resampled with replacement within each group)."""
    rng = np.random.default_rng(seed)
    a, b = np.asarray(first, dtype=float), np.asarray(second, dtype=float)
    resampled = rng.choice(b, (draws, len(b))).mean(axis=1) - rng.choice(a, (draws, len(a))).mean(axis=1)
    low, high = np.percentile(resampled, [2.5, 97.5])
    return float(b.mean() - a.mean()), float(low), float(high)


def _cell(values: Sequence[Optional[float]], digits: int = 1) -> str:
    present = [v for v in values if v is not None]
    if not present:
        return "—"
    return mean_std(present, digits) + ("" if len(present) == len(values) else f" ({len(present)}/{len(values)} seeds)")


def report_lines(variants: dict[str, list[Run]], unfinished: list[str], command: str, call_yields: Sequence[str] = ()) -> list[str]:
    lines = [
        "# Language-model experiment", "", f"Made with `{command}` from each run's `summary.json`.", "",
        "Model calls count every answer of the model (duplicates thrown away and generated again included);",
        "programs evaluated: new programs that were scored (not duplicates, not failures). Mean ± sample std over seeds.",
        "", "## Per variant", "",
        "| Variant | Seeds | Model calls | Programs evaluated | per 100 calls | Duplicate answers | Valid programs | Best | Held-out | Calls to target |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, runs in variants.items():
        target = runs[0].target
        reached = [r.calls_to_target for r in runs if r.calls_to_target is not None]
        if target is None:
            to_target = "—"
        else:
            to_target = f"{mean_std(reached, 0)} ({len(reached)}/{len(runs)} seeds)" if reached else f"not reached (0/{len(runs)} seeds)"
        lines.append(
            f"| {name} | {len(runs)} | {_cell([r.calls for r in runs], 0)} | {_cell([r.evaluated for r in runs], 1)} | "
            f"{_cell([r.per_100_calls for r in runs])} | {_cell([100 * r.summary['duplicate_rate'] for r in runs])}% | "
            f"{_cell([100 * r.summary['valid_program_rate'] for r in runs])}% | {_cell([r.best for r in runs])} | "
            f"{_cell([r.heldout for r in runs])} | {to_target} |"
        )
    lines += [
        "", "## Per run", "",
        "| Variant | Seed | Model calls | Programs evaluated | Duplicate answers | Failed or unusable | Evaluated per 100 calls "
        "| Best | Held-out | Calls to target | Seconds |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, runs in variants.items():
        for r in runs:
            heldout = "—" if r.heldout is None else f"{r.heldout:.1f}"
            lines.append(
                f"| {name} | {r.seed} | {r.calls} | {r.evaluated} | {r.duplicate_answers} | {r.failed} | {r.per_100_calls:.1f} | "
                f"{r.best:.1f} | {heldout} | {r.calls_to_target if r.calls_to_target is not None else '—'} | {r.seconds} |"
            )
    names = list(variants)
    if len(names) == 2 and min(len(runs) for runs in variants.values()) < 2:
        first, second = (variants[name] for name in names)
        difference = np.mean([r.best for r in second]) - np.mean([r.best for r in first])
        lines += [
            "", "## Difference of final bests", "",
            f"{names[1]} − {names[0]}: {difference:+.1f}; no interval: a variant has one finished seed, and one seed says nothing of the spread.",
        ]
    elif len(names) == 2:
        first, second = (variants[name] for name in names)
        difference, low, high = bootstrap_difference([r.best for r in first], [r.best for r in second])
        coarse = " (coarse: few seeds a variant)" if min(len(first), len(second)) < 5 else ""
        verdict = "excludes 0" if low > 0 or high < 0 else "includes 0: no significant difference at this number of seeds"
        lines += [
            "", "## Difference of final bests", "",
            f"{names[1]} − {names[0]}: {difference:+.1f}, 95% bootstrap interval [{low:+.1f}, {high:+.1f}] "
            f"({BOOTSTRAP_DRAWS:,} resamples of the seeds within each variant){coarse}; the interval {verdict}.",
        ]
    lines += [*call_yields, ""]
    if variants:
        lines += ["## Best so far", "", f"![best so far against model calls and seconds of generation]({PLOT_FILE})", ""]
        busy = [f"{r.variant} s{r.seed} {100 * r.summary['generator_busy']:.0f}%" for runs in variants.values() for r in runs if "generator_busy" in r.summary]
        if busy:
            lines += [
                "Seconds of generation: the model's time, summed over its calls (every process of a resumed run, not the time "
                f"between them). The share of each run's wall-clock time the model was busy: {', '.join(busy)}.", "",
            ]
    if unfinished:
        lines += ["## Not counted (not finished)", "", *unfinished, ""]
    return lines


def best_so_far_figure(variants: dict[str, list[Run]]) -> Figure:
    """Best so far against model calls, and beside it against seconds of generation (the runs
    whose stores say them)."""
    timed = all(run.clock is not None for runs in variants.values() for run in runs)
    figure = Figure(figsize=(13 if timed else 7, 4.8), layout="constrained")
    axes = figure.subplots(1, 2 if timed else 1, squeeze=False)[0]
    target = next(iter(variants.values()))[0].target
    for ax, xlabel, curve in zip(axes, ["model calls", "seconds of generation"], [lambda r: r.curve, lambda r: r.seconds_curve]):
        for index, (name, runs) in enumerate(variants.items()):
            draw_seeds(ax, name, [curve(r) for r in runs], COLORS[index % len(COLORS)])
        if target is not None:
            ax.axhline(target, color="0.4", linestyle=":", linewidth=1.2, label=f"target {target:g}")
        ax.set(xlabel=xlabel, ylabel="best score so far")
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncols=2, frameon=False)
    return figure


def write_report(out: Path, report: Path, command: str, first: int = 48) -> Path:
    variants, unfinished = read_runs(out)
    call_yields = yield_lines(out, first)
    if not variants and not call_yields:
        raise SystemExit(f"llm_experiment: error: no run under {out}")
    report.parent.mkdir(parents=True, exist_ok=True)
    if variants:  # the figure and the difference are of finished runs
        best_so_far_figure(variants).savefig(report.parent / PLOT_FILE, dpi=130)
    report.write_text("\n".join(report_lines(variants, unfinished, command, call_yields)).rstrip() + "\n")
    return report


def main(argv: Optional[Sequence[str]] = None) -> None:
    parser = argparse.ArgumentParser(prog="scripts/llm_experiment.py", description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("run", help="run (or resume) every (variant, seed) into OUT/<variant>/s<seed>")
    run.add_argument("out", type=Path)
    run.add_argument("--variant", action="append", required=True, help="overrides of one variant, e.g. gfo=none (repeat)")
    run.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    report = commands.add_parser("report", help="report.md and best_so_far.png from the runs under OUT")
    report.add_argument("out", type=Path)
    report.add_argument("--out", dest="report", type=Path, help="the Markdown file (default OUT/report.md)")
    report.add_argument("--first", type=int, default=48, help="the model-call yield over each run's first this many calls (default 48)")
    argv = list(sys.argv[1:] if argv is None else argv)
    # The overrides after `--`, split off here: argparse's subcommands do not take `--` well.
    ours, overrides = (argv[: argv.index("--")], argv[argv.index("--") + 1 :]) if "--" in argv else (argv, [])
    args = parser.parse_args(ours)
    if args.command == "run":
        sys.exit(run_all(args.out, args.variant, args.seeds, overrides))
    command = "python scripts/llm_experiment.py " + shlex.join(argv)
    print(write_report(args.out, args.report or args.out / REPORT_FILE, command, args.first))


if __name__ == "__main__":
    main()
