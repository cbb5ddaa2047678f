"""How long `build_prompt` takes for two good controllers that share a chain of helpers, each
helper naming the previous one (issue 33: the renaming that keeps a shown helper apart from
another program's helper of the same name renamed one helper per pass, copying and unparsing
every helper each pass: 100 helpers 1.5 s, 400 20.8 s, in the coordinator's loop for every
prompt that shows them). Prints, per chain length, the seconds of one `build_prompt` (the
median of `--rounds`) and the ratio to the shortest chain's, beside the helpers' count ratio:
linear rendering keeps the two ratios alike.

    python benchmarks/prompt_helpers.py [--helpers 100 400 2600] [--rounds 3]
"""

from __future__ import annotations

import statistics
import time

from common import argument_parser

from colmo.database import Selection, StoredProgram
from colmo.prompt import build_prompt


def chained(helpers: int, gain: float) -> str:
    """A controller whose `policy` calls the first of `helpers` helpers, each calling the one
    defined after it; only the last holds `gain`, which makes the two programs' last helpers
    differ: every helper is then renamed, the last first (the order that took one pass each)."""
    lines = ["import numpy as np"]
    for index in range(helpers - 1):
        lines += ["", f"def h{index}(obs):", f"    return h{index + 1}(obs) + obs[{index % 3}]"]
    lines += ["", f"def h{helpers - 1}(obs):", f"    return {gain} * obs[0]", "", "def policy(obs):", "    return -h0(obs)"]
    return "\n".join(lines)


def main() -> None:
    parser = argument_parser(__doc__, tasks=False, rounds=3)
    parser.add_argument("--helpers", nargs="+", type=int, default=[100, 400, 2600], help="chain lengths (default: 100 400 2600)")
    args = parser.parse_args()
    first = None
    print(f"{'helpers':>8}  {'seconds':>8}  {'x time':>7}  {'x helpers':>9}")
    for helpers in args.helpers:
        programs = [StoredProgram("a", chained(helpers, 1.0), 100.0, 0, 0), StoredProgram("b", chained(helpers, 2.0), 200.0, 0, 1)]
        times = []
        for _ in range(args.rounds):
            start = time.perf_counter()
            build_prompt("Swing the pole up.", Selection(0, programs))
            times.append(time.perf_counter() - start)
        seconds = statistics.median(times)
        first = first or (helpers, seconds)
        print(f"{helpers:>8}  {seconds:>8.3f}  {seconds / first[1]:>7.1f}  {helpers / first[0]:>9.1f}")


if __name__ == "__main__":
    main()
