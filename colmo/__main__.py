"""`python -m colmo task=... llm=... gfo=...`: run a policy search (single run or `-m` sweep)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

from hydra.core.hydra_config import HydraConfig
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from colmo.config import SearchConfig, hydra_app
from colmo.spec import load_task_spec
from colmo.store import SampleRecord, open_for_resume


class ProgressLine:
    """A live line on stderr: samples, best score, evaluations per second."""

    def __init__(self, total: int):
        self.progress = Progress(
            TextColumn("[bold]colmo"), BarColumn(), MofNCompleteColumn(), TextColumn("{task.fields[status]}"),
            TimeElapsedColumn(), console=Console(stderr=True), transient=True,
        )
        self.task = self.progress.add_task("search", total=total, status="starting")
        self.progress.start()

    def on_batch(self, report: dict[str, Any], records: list[SampleRecord]) -> None:
        status = f"best {report['best_score']:.1f} | {report['evaluations_per_second']:.1f} evals/s | dup {report['duplicates']} fail {report['failures']}"
        self.progress.update(self.task, completed=report["samples"], status=status)

    def on_finish(self, summary: dict[str, Any]) -> None:
        self.progress.stop()


def check_inputs(cfg: SearchConfig) -> None:
    """The spec file loads and `resume=` names a run of the same task."""
    load_task_spec(cfg.task.spec)
    if cfg.resume:
        open_for_resume(Path(cfg.resume).expanduser(), cfg.task.name).close()


@hydra_app("search", check=check_inputs)
def main(cfg: SearchConfig) -> None:
    from colmo.search import Search  # heavy imports only once the config is valid

    run_dir = Path(HydraConfig.get().runtime.output_dir)
    observers = (ProgressLine(cfg.search.max_samples),) if cfg.search.progress and sys.stderr.isatty() else ()
    if cfg.tracker.name == "mlflow":
        from colmo.track import make_tracker

        observers += (make_tracker(cfg, run_dir),)
    summary = Search(cfg, run_dir, observers).run()
    print(summary["best_code"] or "")
    print(
        f"best score {summary['best_score']:.2f} after {summary['samples']} samples "
        f"({summary['programs_evaluated']} evaluated, {summary['duplicates_skipped']} duplicates, "
        f"{summary['failures']} failures) in {summary['seconds']:.0f} s; stopped: {summary['stop_reason']}"
    )
    print(f"run directory: {summary['run_dir']}")
    if summary["stop_reason"] == "interrupted" or summary["stop_reason"].startswith("generator failed"):
        print(f"resume with: python -m colmo task={cfg.task.name} resume={summary['run_dir']}", file=sys.stderr)
        sys.exit(130 if summary["stop_reason"] == "interrupted" else 1)


if __name__ == "__main__":
    main()
