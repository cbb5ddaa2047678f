"""How busy the workers are: batches of `llm.batch_size` against steady state, with and without programs
queued beyond the workers (`search.steady_queue`), side by side.

Each variant is a real search of colmo's embedded mutation (`llm=mutate`) for a fixed number of samples,
from the same seed, with no finish (no held-out scoring, simplification or video). In steady state
with exactly one program per worker, a worker idles each time its program's optimizer takes a
candidate's score and asks for the next; a queued program's candidate fills that gap. The variants
run back to back in alternating order each round (machines are noisy), and the medians are
reported, with each variant's evaluations per second relative to steady state without a queue,
both measured from each search's first batch report to its last (not its start-up, starter or finish).

    python benchmarks/steady_queue.py                                  # pendulum, 24 samples, 2 rounds
    python benchmarks/steady_queue.py --tasks pendulum cheetah --samples 24 --rounds 3
"""

from __future__ import annotations

import os
import statistics
import tempfile
from pathlib import Path

from common import argument_parser, parse_arguments

from colmo.cli import compose
from colmo.record import BatchReport, SampleRecord, Summary
from colmo.search import Search

VARIANTS = {
    "batches of 4": [],
    "steady": ["search.steady_state=true"],
    "steady, queue 1": ["search.steady_state=true", "search.steady_queue=1"],
}
QUIET = ["llm=mutate", "tracker=none", "search.progress=false", "heldout.episodes=1", "finish.top=1", "finish.render=false", "finish.simplify=false"]


class Window:
    """The first and the last batch report of a search: the search at full speed, without the
    start-up, the starter's tuning (one program, alone on the workers) and the finish."""

    def __init__(self) -> None:
        self.reports: list[BatchReport] = []

    def on_batch(self, report: BatchReport, records: list[SampleRecord]) -> None:
        self.reports[1:] = [report]  # keeps the first and the latest

    def on_finish(self, summary: Summary) -> None:
        pass

    def rates(self, workers: int) -> tuple[float, float]:
        """Evaluations per second and the workers' busy fraction between the two reports."""
        first, last = self.reports
        seconds = last.seconds - first.seconds
        return (last.evaluations - first.evaluations) / seconds, (last.worker_seconds - first.worker_seconds) / (seconds * workers)


def searched(task: str, samples: int, workers: int, overrides: list[str], run_dir: Path) -> tuple[float, float]:
    """Evaluations per second and the workers' busy fraction of one search, from its first batch to its last."""
    cfg = compose("search", [f"task={task}", f"search.max_samples={samples}", f"executor.workers={workers}", *QUIET, *overrides])
    window = Window()
    summary = Search(cfg, run_dir, observers=(window,)).run()
    assert summary.samples == samples and len(window.reports) == 2, (summary.stop_reason, summary.samples)
    return window.rates(workers)


def main() -> None:
    parser = argument_parser(__doc__, rounds=2)
    parser.set_defaults(tasks=["pendulum"])
    parser.add_argument("--samples", type=int, default=24, help="samples a search (model calls)")
    parser.add_argument("--workers", type=int, default=2, help="evaluation workers")
    args = parse_arguments(parser)
    for task in args.tasks:
        rates: dict[str, list[float]] = {name: [] for name in VARIANTS}
        busy: dict[str, list[float]] = {name: [] for name in VARIANTS}
        with tempfile.TemporaryDirectory() as scratch:
            for index in range(args.rounds):
                order = list(VARIANTS) if index % 2 == 0 else list(reversed(VARIANTS))
                for name in order:
                    rate, fraction = searched(task, args.samples, args.workers, VARIANTS[name], Path(scratch) / f"{index}-{len(rates[name])}-{name}")
                    rates[name].append(rate)
                    busy[name].append(fraction)
                print(f"{task} round {index + 1}: " + ", ".join(f"{name} {rates[name][-1]:.1f}" for name in VARIANTS) + " evaluations/s", flush=True)
        # Each round's variants ran back to back, under the same load: their ratios are the fair comparison.
        print(f"\n{task}: {args.samples} samples, {args.workers} workers, {args.rounds} rounds, load average {os.getloadavg()[0]:.1f} (medians):")
        for name in VARIANTS:
            ratio = statistics.median(mine / base for mine, base in zip(rates[name], rates["steady"]))
            print(
                f"  {name:<16} {statistics.median(rates[name]):6.1f} evaluations/s ({ratio:.2f}x steady), "
                f"workers busy {statistics.median(busy[name]):.1%} of the time"
            )


if __name__ == "__main__":
    main()
