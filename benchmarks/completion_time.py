"""Shell completion's time per Tab, measured beside the interpreter's own start.

After `eval "$(colmo -sc install=bash)"`, every Tab runs `colmo -sc query=bash` with the line
typed so far in `COMP_LINE` (Hydra's bash completion, hydra/_internal/core_plugins/
bash_completion.py). This runs that command for each line, and `python -c pass` beside it, in
alternating rounds, and prints the median wall and CPU seconds of each and the completions the
last round offered (machines are noisy and shared: CPU seconds and the ratio to the bare
interpreter say more than wall seconds under load). `--compare DIR` runs each line a second
time with another colmo source tree first on PYTHONPATH, in the same rounds: before and after.

    python benchmarks/completion_time.py                       # the default lines, 5 rounds
    python benchmarks/completion_time.py --rounds 9 --line 'colmo gfo=' --line 'colmo llm.'
    git worktree add /tmp/colmo-before HEAD~3 && python benchmarks/completion_time.py --compare /tmp/colmo-before
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import time

LINES = ("colmo ", "colmo gfo=", "colmo task=p", "colmo gfo.", "colmo hydra/launcher=")


def run_once(command: list[str], env: dict[str, str]) -> tuple[float, float, str]:
    """Wall seconds, CPU seconds (user + system, the child's) and stdout of one run of `command`."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, text=True, check=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), done.stdout


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--line", action="append", help=f"a command line typed so far (default: {', '.join(map(repr, LINES))})")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--colmo", default=shutil.which("colmo") or "colmo", help="the colmo executable")
    parser.add_argument("--compare", help="another colmo source tree (its directory holding colmo/), run beside this one")
    args = parser.parse_args()
    lines = args.line or list(LINES)
    commands = {"python -c pass": ([sys.executable, "-c", "pass"], dict(os.environ))}
    for line in lines:
        env = {**os.environ, "COMP_LINE": line, "COMP_POINT": str(len(line))}
        commands[f"Tab after {line!r}"] = ([args.colmo, "-sc", "query=bash"], env)
        if args.compare:
            commands[f"  compared: {line!r}"] = ([args.colmo, "-sc", "query=bash"], {**env, "PYTHONPATH": args.compare})
    walls: dict[str, list[float]] = {name: [] for name in commands}
    cpus: dict[str, list[float]] = {name: [] for name in commands}
    offered: dict[str, str] = {}
    for _ in range(args.rounds):
        for name, (command, env) in commands.items():
            wall, cpu, out = run_once(command, env)
            walls[name].append(wall)
            cpus[name].append(cpu)
            offered[name] = out.strip()
    base = statistics.median(walls["python -c pass"])
    print(f"{args.rounds} rounds, load average {os.getloadavg()[0]:.1f}; medians")
    for name in commands:
        wall, cpu = statistics.median(walls[name]), statistics.median(cpus[name])
        print(f"  {name:<38} wall {wall:5.2f} s ({wall / base:4.1f}x python -c pass)   cpu {cpu:5.2f} s")
    for name, out in offered.items():
        if name != "python -c pass":
            print(f"  {name}: {' '.join(out.split())}")


if __name__ == "__main__":
    main()
