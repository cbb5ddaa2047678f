"""The end of a `-m` sweep: its jobs side by side, one line each, and the command for the report.

`CompareJobs` is a Hydra callback (`hydra.callbacks` in colmo/conf/search.yaml); when every job
of a sweep has ended (`on_multirun_end`) it reads what each job wrote in the sweep directory, its
`summary.json` and the overrides Hydra saved, whatever launcher ran it, and prints::

    sweep multirun/2026-12-02_18-20-00: 4 jobs
      job  variant          best  held-out  samples  seconds  searched
        0  gfo=oneplusone  186.50   179.00       12     88.1      55.3
        1  gfo=none        failed: no sample searched: search.max_seconds left no time after the start-up
        ...
      best score by setting, mean ± std over seeds (each seed), difference to the first:
        gfo=oneplusone  372.10 ± 141.41 (392.50, 221.60, 502.20)
        gfo=none        186.77 ± 10.06 (187.40, 196.50, 176.40)  -185.33, 95% interval [-312.40, -37.90]
    report: colmo-report experiment=pendulum sweep=3f2a...

`variant` is what sets a job apart: its overrides less those every job shares; `seconds`, its
wall time, and `searched`, the seconds from its first batch to the search's stop. A job with
no result to compare is a line saying why and never a score: it wrote no summary (it failed or
was killed), stopped before its limits, or evaluated no program of its own
(`colmo.record.shortfall`); the sweep then ends with one line naming them and exit code 1.
Where the sweep compares settings, not only seeds, each setting's scores follow, and its
difference to the first setting with a bootstrap interval (`colmo.comparison`): "no
significant difference" where the interval holds 0. Where the jobs with a result ran on
different code or libraries (their `summary.json`'s `provenance` differs: a sweep resumed after
an upgrade), lines name what differed and which jobs ran which; where a task's time-limited
jobs simulated at speeds far apart (`steps_per_worker_second`: jobs side by side on a loaded
machine, or on machines of different speeds), a line gives each job's.
The report line appears when the jobs were tracked in MLflow (`colmo.track`), naming the sweep
by its id (`sweep_id`).
"""

from __future__ import annotations

import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional

from hydra.experimental.callback import Callback
from omegaconf import DictConfig, OmegaConf

from colmo.comparison import difference, mean_std
from colmo.errors import EXIT_RUNTIME, one_line
from colmo.record import summary_failure
from colmo.store import read_summary

# Of a task's time-limited jobs, the fastest simulation over the slowest that the comparison points out.
SPEED_SPREAD = 1.5


@dataclass(frozen=True)
class JobOutcome:
    """What one job of a sweep wrote: its number, overrides, and summary (None if it wrote none)."""

    number: int
    overrides: tuple[str, ...]
    summary: Optional[dict]
    tracking: Optional[dict]  # the job's `tracker` config, if it was tracked in MLflow
    task: str

    @property
    def failure(self) -> Optional[str]:
        """Why this job has no result to compare, or None."""
        return summary_failure(self.summary)


def read_jobs(sweep_dir: Path) -> list[JobOutcome]:
    """The jobs Hydra ran into `sweep_dir`, in job order: every subdirectory with a `.hydra`
    config (`hydra.job.num` from its `hydra.yaml`)."""
    jobs = []
    for hydra_dir in sweep_dir.glob("*/.hydra"):
        job_dir = hydra_dir.parent
        try:
            hydra = OmegaConf.load(hydra_dir / "hydra.yaml").hydra
            config = OmegaConf.load(hydra_dir / "config.yaml")
            overrides = tuple(OmegaConf.load(hydra_dir / "overrides.yaml"))
        except (OSError, ValueError, AttributeError):  # not a job of this sweep, or one cut off while starting
            continue
        summary = read_summary(job_dir)
        tracker = config.get("tracker", {})
        tracking = OmegaConf.to_container(tracker) if tracker.get("name") == "mlflow" else None
        jobs.append(JobOutcome(int(hydra.job.num), overrides, summary, tracking, str(config.task.name)))
    return sorted(jobs, key=lambda job: job.number)


def _score(value: Optional[float]) -> str:
    return "-" if value is None else f"{value:.2f}"


def comparison_lines(sweep_dir: Path, jobs: list[JobOutcome], shown_dir: Optional[Path] = None) -> list[str]:
    """The comparison `CompareJobs` prints: a heading, one line per job, the report's command."""
    # A setting every job shares is not a variant; a sweep of one job shows all of its own.
    shared = set.intersection(*(set(job.overrides) for job in jobs)) if len(jobs) > 1 else set()
    variants = [" ".join(o for o in job.overrides if o not in shared) or "(all alike)" for job in jobs]
    width = max([len("variant"), *map(len, variants)])
    lines = [f"sweep {shown_dir or sweep_dir}: {len(jobs)} job{'s' * (len(jobs) != 1)}"]
    lines.append(f"  {'job':>3}  {'variant':<{width}}  {'best':>8}  {'held-out':>8}  {'samples':>7}  {'seconds':>7}  {'searched':>8}")
    for job, variant in zip(jobs, variants):
        if job.failure is not None:
            lines.append(f"  {job.number:>3}  {variant:<{width}}  failed: {job.failure}")
            continue
        best, heldout = _score(job.summary.get("best_score")), _score(job.summary.get("best_heldout_score"))
        samples, seconds, searched = (job.summary.get(key, 0) for key in ("samples", "seconds", "search_seconds"))
        lines.append(f"  {job.number:>3}  {variant:<{width}}  {best:>8}  {heldout:>8}  {samples:>7}  {seconds:>7.1f}  {searched:>8.1f}")
    lines += variant_lines(jobs, variants)
    lines += provenance_lines(jobs)
    lines += speed_lines(jobs)
    tracked = [job for job in jobs if job.tracking is not None]
    if tracked:
        from colmo.track.sweep import sweep_id  # MLflow only for a tracked sweep
        names = list(dict.fromkeys(job.tracking.get("experiment") or job.task for job in tracked))
        experiments = names[0] if len(names) == 1 else f"[{','.join(names)}]"  # a Hydra list: a,b would be a sweep
        uri = tracked[0].tracking.get("tracking_uri")
        lines.append(f"report: colmo-report experiment={experiments} sweep={sweep_id(sweep_dir)}" + (f" tracking_uri={uri}" if uri else ""))
    return lines


def failure_line(jobs: list[JobOutcome]) -> Optional[str]:
    """The line a sweep with failed jobs ends with (None if every job has a result)."""
    failed = [job.number for job in jobs if job.failure is not None]
    if not failed:
        return None
    numbers = ", ".join(map(str, failed))
    return f"colmo: error: {len(failed)} of {len(jobs)} jobs failed (job{'s' * (len(failed) > 1)} {numbers}): no result to compare"


def _is_seed(override: str) -> bool:
    return override.split("=", 1)[0].lstrip("+~") == "seed"


def variant_lines(jobs: list[JobOutcome], variants: list[str]) -> list[str]:
    """When the sweep compares settings (not only seeds): each setting's best scores over its
    seeds (the jobs with a result), mean ± std and each seed's, and its difference to the first
    setting with a bootstrap interval (`colmo.comparison`)."""
    settings: dict[str, list[float]] = {}
    for job, variant in zip(jobs, variants):
        setting = " ".join(o for o in variant.split(" ") if not _is_seed(o)) or "(all alike)"
        scores = settings.setdefault(setting, [])
        if job.failure is None and job.summary.get("best_score") is not None:
            scores.append(job.summary["best_score"])
    if len(settings) < 2:
        return []
    width = max(map(len, settings))
    lines = ["  best score by setting, mean ± std over seeds (each seed), difference to the first:"]
    baseline = next(iter(settings.values()))
    for index, (setting, scores) in enumerate(settings.items()):
        if not scores:
            lines.append(f"    {setting:<{width}}  no job with a result")
            continue
        seeds = ", ".join(f"{score:.2f}" for score in scores)
        change = "" if index == 0 or not baseline else f"  {difference(baseline, scores).text(2)}"
        lines.append(f"    {setting:<{width}}  {mean_std(scores, 2)} ({seeds}){change}")
    return lines


def _code(record: dict[str, Any]) -> str:
    if record.get("commit"):
        return record["commit"][:12] + (" with uncommitted changes" if record.get("uncommitted_changes") else "")
    return f"colmo {record.get('colmo')}" + (f" from {record['source']}" if record.get("source") else "")


def _facets(record: Optional[dict[str, Any]]) -> dict[str, str]:
    """A job's provenance as the values compared across jobs: its code, Python, CPUs, libraries."""
    if not record:
        return {}
    return {"code": _code(record), "python": str(record.get("python")), "cpus": str(record.get("cpus")), **record.get("libraries", {})}


def provenance_lines(jobs: list[JobOutcome]) -> list[str]:
    """Where the jobs with a result ran on different code, libraries, Python or CPU counts (a
    sweep resumed after an upgrade, or spread over machines): what differed, each value with its
    jobs (`colmo.provenance`). Nothing when they agree or none recorded it."""
    facets = {job.number: _facets(job.summary.get("provenance")) for job in jobs if job.failure is None}
    if not any(facets.values()):
        return []
    differing: dict[str, dict[str, list[int]]] = {}
    for name in dict.fromkeys(name for values in facets.values() for name in values):
        jobs_by_value: dict[str, list[int]] = {}
        for number, values in facets.items():
            jobs_by_value.setdefault(values.get(name, "not installed") if values else "not recorded", []).append(number)
        if len(jobs_by_value) > 1:
            differing[name] = jobs_by_value
    if not differing:
        return []
    lines = ["  the jobs ran on different code or libraries (scores may differ for that alone):"]
    for facet, values in differing.items():
        shown = ", ".join(f"{value} (job{'s' * (len(numbers) > 1)} {', '.join(map(str, numbers))})" for value, numbers in values.items())
        lines.append(f"    {facet}: {shown}")
    return lines


def speed_lines(jobs: list[JobOutcome]) -> list[str]:
    """Where a task's time-limited jobs simulated at speeds `SPEED_SPREAD` apart or more (control
    steps per busy worker-second: the machine's speed and load, and the programs' cost), each job's:
    a time limit bought them different numbers of samples."""
    by_task: dict[str, list[tuple[int, float]]] = {}
    for job in jobs:
        speed = job.summary.get("steps_per_worker_second") if job.failure is None else None
        if speed and job.summary.get("stop_reason") == "max_seconds":
            by_task.setdefault(job.task, []).append((job.number, speed))
    lines = []
    for task, speeds in by_task.items():
        if max(speed for _, speed in speeds) >= SPEED_SPREAD * min(speed for _, speed in speeds):
            shown = ", ".join(f"{speed / 1000:.1f}k (job {number})" for number, speed in speeds)
            lines.append(f"  {task}: the time-limited jobs simulated at different speeds, control steps per worker-second: {shown}")
    return lines


def sweep_report(uri: Optional[str], launch_dir: Path, experiments: list[str], sweep_dir: Path, out: Path, command: str) -> Optional[Path]:
    """colmo-report's report of the sweep (`colmo.report.write_report`) written into `out`, as
    `command` (the report line) would write it; None when the sweep has no run to report."""
    from colmo.report import write_report
    from colmo.track import connect, default_tracking_uri
    from colmo.track.sweep import sweep_id

    client = connect(uri or default_tracking_uri(launch_dir))
    try:
        write_report(client, experiments, out, command=command.removeprefix("report: "), sweep=sweep_id(sweep_dir))
    except ValueError:  # no finished run with metrics: the failed jobs' lines say why
        return None
    return out


class CompareJobs(Callback):
    """Prints `comparison_lines` of a sweep once all its jobs have ended, and for a tracked sweep
    records them and its report (`sweep_report`) in its MLflow parent run
    (`colmo.track.sweep.record_comparison`); a sweep with a failed
    job then ends with `failure_line` and exit code 1 (Hydra notifies callbacks of a sweep's end
    last one first, so this one, declared first in colmo/conf/search.yaml, comes after a user's)."""

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        shown = Path(config.hydra.sweep.dir)
        sweep_dir = (Path(config.hydra.runtime.cwd) / shown).resolve()
        jobs = read_jobs(sweep_dir)
        lines = comparison_lines(sweep_dir, jobs, shown)
        print("\n".join(lines), flush=True)
        tracked = [job for job in jobs if job.tracking is not None]
        if tracked:
            from colmo.track.sweep import record_comparison

            uri = tracked[0].tracking.get("tracking_uri") or None
            experiments = sorted({job.tracking.get("experiment") or job.task for job in tracked})
            launch_dir = Path(config.hydra.runtime.cwd)
            try:
                with tempfile.TemporaryDirectory(prefix="colmo-report-") as scratch:
                    report = sweep_report(uri, launch_dir, experiments, sweep_dir, Path(scratch) / "report", lines[-1])
                    record_comparison(uri, launch_dir, experiments, sweep_dir, lines, report)
            except Exception as error:  # MLflow's errors are many; the table is printed and the exit code must follow
                print(f"colmo: the comparison was not recorded in MLflow: {one_line(error)}", file=sys.stderr, flush=True)
        failed = failure_line(jobs)
        if failed is not None:
            print(failed, file=sys.stderr, flush=True)
            sys.exit(EXIT_RUNTIME)
