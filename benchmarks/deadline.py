"""How close a run ends to `search.max_seconds`: the promise that a run, start-up and finish
included, ends within 5 s of its limit.

Runs `python -m colmo task=T search.max_seconds=L` (no tracking, 2 workers, the finish as
configured: held-out scores, simplifier, video) `--rounds` times per limit, and prints each run's
wall seconds from the process's start to its exit beside the limit, the ratio of the two and the
overrun, with the run's own accounting (start-up, search, and what is left: the finish) and the
machine's load. The tests check what the run decides (its search stops in time for its finish);
whether the finish's estimate holds on a loaded machine is measured here.

    python benchmarks/deadline.py                                   # pendulum, 60 s, 2 rounds
    python benchmarks/deadline.py --tasks pendulum cheetah --limits 60 120 --rounds 3
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import argument_parser, parse_arguments

PROMISE = 5.0  # seconds past the limit a run may end


def run_once(task: str, limit: int, workers: int) -> dict:
    """One run in a fresh directory: its wall seconds and its summary's accounting."""
    with tempfile.TemporaryDirectory() as directory:
        command = [
            sys.executable, "-m", "colmo", f"task={task}", f"search.max_seconds={limit}", "search.max_samples=1000000",
            "tracker=none", "search.progress=false", f"executor.workers={workers}", "hydra.run.dir=run",
        ]
        start = time.monotonic()
        done = subprocess.run(command, cwd=directory, capture_output=True, text=True)
        wall = time.monotonic() - start
        if done.returncode != 0:
            raise SystemExit(f"{task} {limit} s: exit {done.returncode}\n{done.stderr[-2000:]}")
        summary = json.loads((Path(directory) / "run" / "summary.json").read_text())
    return {"wall": wall, "startup": summary["startup_seconds"], "search": summary["search_seconds"], "samples": summary["samples"], "load": os.getloadavg()[0]}


def main() -> None:
    parser = argument_parser(__doc__, rounds=2)
    parser.set_defaults(tasks=["pendulum"])
    parser.add_argument("--limits", type=int, nargs="+", default=[60], help="search.max_seconds values (default: 60)")
    parser.add_argument("--workers", type=int, default=2, help="executor.workers (default: 2)")
    arguments = parse_arguments(parser)
    print(f"{'task':<10} {'limit':>5} {'wall':>7} {'wall/limit':>10} {'overrun':>8} {'start-up':>8} {'search':>7} {'finish':>7} {'samples':>7} {'load':>5}")
    overruns: list[float] = []
    for _ in range(arguments.rounds):
        for task in arguments.tasks:
            for limit in arguments.limits:
                run = run_once(task, limit, arguments.workers)
                overrun = run["wall"] - limit
                overruns.append(overrun)
                finish = run["wall"] - run["startup"] - run["search"]
                print(
                    f"{task:<10} {limit:>5} {run['wall']:>7.1f} {run['wall'] / limit:>10.3f} {overrun:>+8.1f} {run['startup']:>8.1f} "
                    f"{run['search']:>7.1f} {finish:>7.1f} {run['samples']:>7} {run['load']:>5.1f}",
                    flush=True,
                )
    worst = max(overruns)
    verdict = "held" if worst <= PROMISE else "failed"
    print(f"median overrun {statistics.median(overruns):+.1f} s, worst {worst:+.1f} s: the promise (at most {PROMISE:g} s past the limit) {verdict}")


if __name__ == "__main__":
    main()
