"""The report that compares search variants, read back from MLflow: the paper's Table I, its
Fig. 4 best-so-far curves, and the best policy of each variant.

    colmo-report experiment=pendulum [experiment=cheetah ...] [sweep=latest|all|NAME]
                 [axis=samples|evaluations|seconds] [out=DIR] [tracking_uri=URI]

`experiment` (repeatable, or comma-separated) names MLflow experiments (colmo names them after
the task); `tracking_uri` defaults to the tracker's `sqlite:///mlruns.db` in the working
directory. `out` is a new directory (default `reports/<experiments>_<date>_<time>`); one that
already holds a report is refused, so a report never overwrites another (or a tracked file).

Which runs count. One sweep is compared: `sweep=latest` (default) the latest `-m` sweep (its
parent run, and one per experiment when it spans tasks), `sweep=NAME` the sweep whose parent
run is named NAME (`pendulum-sweep-121503`), `sweep=all` every run of the experiments (also
the default when they hold no sweep). Its FINISHED search runs are read (sweep parents and
`colmo-optimize` runs are not searches); runs that did not finish are counted and named, not
used. Runs are grouped by task and variant: the GFO method, its budget when tuning, and any
other setting that differs between the task's runs (`database.num_islands=5`); settings that
do not change results (tracker, executor, display) are ignored. A run repeated with the same
variant and seed is a repeat: the latest counts, and the report names the older ones.
Seeds are aggregated as mean ± sample std.

`out/` receives
- `report.md`: Table I (state and action dims, best training reward and held-out reward of the
  best program, without and with GFO, samples to reach the task's `task.target_score`), one
  line per run, where each run's samples and time went (valid programs, duplicates, tokens/s,
  generator and evaluator busy), the runs left out and why, and each variant's best policy;
- `best_so_far.png`: one panel per task, x = model calls (programs sampled), candidate
  evaluations or seconds of search (`axis`, so GFO and no GFO compare per sample or per unit
  of compute); one colour per variant, named in the legend: its mean over seeds (thick), the
  band from its lowest to its highest seed, each seed thin; a curve of one point is a marker;
  dotted: the target.
"""

from __future__ import annotations

import argparse
import datetime
import os
import re
import sys
from pathlib import Path
from typing import Optional, Sequence

from mlflow import MlflowClient

from colmo.report.figure import figure
from colmo.report.selection import AXES, LATEST, group, read_runs
from colmo.report.tables import best_policies, generation_table, left_out_lines, mean_std, runs_table, table_one
from colmo.store import BEST_SO_FAR_PLOT
from colmo.track import connect, default_tracking_uri, sqlite_path

__all__ = ["AXES", "default_out", "main", "mean_std", "read_runs", "write_report"]

REPORT_FILE = "report.md"


def default_out(experiments: Sequence[str], now: Optional[datetime.datetime] = None) -> Path:
    stamp = (now or datetime.datetime.now()).strftime("%Y-%m-%d_%H-%M-%S")
    name = re.sub(r"[^\w.+-]+", "_", "+".join(experiments))
    return Path("reports") / f"{name}_{stamp}"


def write_report(
    client: MlflowClient, experiments: Sequence[str], out: Path, axis: str = "samples", command: str = "", sweep: str = LATEST
) -> Path:
    """Write `report.md` and `best_so_far.png` of one sweep (`sweep`: latest, all or a parent
    run's name) into the new directory `out`; return the Markdown file. `ValueError` if `out`
    already holds a report, the sweep does not exist or no run can be used."""
    if (out / REPORT_FILE).exists():
        raise ValueError(f"{out} already holds a report: choose another out= (a report never overwrites one)")
    reading = read_runs(client, experiments, axis, sweep)
    tasks = group(reading.curves)
    if not tasks:
        raise ValueError(f"no finished runs with metrics in experiment(s) {', '.join(experiments)}")
    out.mkdir(parents=True, exist_ok=True)
    figure(tasks, axis).savefig(out / BEST_SO_FAR_PLOT, dpi=130)
    count = len(reading.curves)
    lines = [
        f"# colmo report: {', '.join(experiments)}",
        "",
        f"Compared: {reading.sweep}.",
        "",
        f"{count + len(reading.left_out)} search runs read from MLflow on {datetime.date.today().isoformat()} "
        f"with `{command or 'colmo-report'}`; {count} count, {len(reading.left_out)} left out (listed below: "
        "runs that did not finish, and repeats: of runs with the same settings and seed, the latest counts).",
        "Rewards are each run's best search score (the mean return over `task.episodes` training episodes);",
        "held-out: that best program's mean return over `evaluation.episodes` fresh episodes. Both are",
        "mean ± sample std over seeds. Samples to target: programs sampled when the best score first",
        "reached `task.target_score`, over the seeds that reached it, at batch resolution.",
        "",
        "## Table I",
        "",
        *table_one(tasks),
        "",
        "## Best so far",
        "",
        f"![best-so-far curves]({BEST_SO_FAR_PLOT})",
        "",
        f"x: {AXES[axis][1]}. One colour per variant (legend): thick, the mean over seeds; band, lowest to highest seed; "
        "thin, each seed; a marker, a run of one batch.",
        "",
        "## Runs",
        "",
        *runs_table(tasks),
        "",
        "## Generation and evaluation",
        "",
        *generation_table(tasks),
        "",
        "## Runs left out",
        "",
        *left_out_lines(reading.left_out),
        "",
        "## Best policy per variant",
        "",
        *best_policies(client, tasks),
    ]
    path = out / REPORT_FILE
    path.write_text("\n".join(lines).rstrip() + "\n")
    return path


_KEYS = ("experiment", "sweep", "axis", "out", "tracking_uri")


def _setting(text: str) -> tuple[str, str]:
    key, sep, value = text.partition("=")
    if not sep or key not in _KEYS or not value:
        raise argparse.ArgumentTypeError(f"expected one of {', '.join(k + '=...' for k in _KEYS)}, got {text!r}")
    return key, value


def main(argv: Optional[Sequence[str]] = None) -> None:
    invoked = Path(sys.argv[0]).name
    prog = invoked if invoked == "colmo-report" else "python -m colmo.report"
    parser = argparse.ArgumentParser(
        prog=prog, description=__doc__.split("\n\n")[0],
        epilog=f"example: {prog} experiment=pendulum axis=seconds",
    )
    parser.add_argument(
        "settings", nargs="+", type=_setting, metavar="key=value",
        help="experiment=NAME[,NAME] (required, repeatable); sweep=latest|all|NAME (which sweep: the latest, every run, "
        "or the one whose parent run is NAME; default latest); axis=samples|evaluations|seconds (x of the figure, "
        "default samples); out=DIR (a new directory; default reports/<experiments>_<date>_<time>); "
        "tracking_uri=URI (default sqlite:///mlruns.db in the working directory)",
    )
    args = list(sys.argv[1:] if argv is None else argv)
    settings = parser.parse_args(args).settings
    experiments = [name for key, value in settings if key == "experiment" for name in value.split(",") if name]
    if not experiments:
        parser.error("experiment=NAME is required")
    options = dict(settings)
    axis = options.get("axis", "samples")
    if axis not in AXES:
        parser.error(f"axis must be one of {', '.join(AXES)}, got {axis!r}")
    os.environ.setdefault("MLFLOW_ENABLE_ARTIFACTS_PROGRESS_BAR", "false")  # one bar per policy file is noise
    uri = options.get("tracking_uri") or default_tracking_uri(Path.cwd())
    database = sqlite_path(uri)
    if database is not None and not database.is_file():
        parser.error(f"no tracking database at {database}: run a search first, or pass tracking_uri=")
    out = Path(options["out"]) if "out" in options else default_out(experiments)
    try:
        path = write_report(connect(uri), experiments, out, axis, f"{prog} {' '.join(args)}", options.get("sweep", LATEST))
    except ValueError as error:
        print(f"{prog}: error: {error}", file=sys.stderr)
        sys.exit(2)
    print(path)
