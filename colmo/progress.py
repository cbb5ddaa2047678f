"""Progress a person can read while a search runs.

On a terminal: a live display on stderr, redrawn twice a second from the search's counters, so
it moves with every evaluation, not every batch: model calls (samples, duplicates and their
regenerations included) and the programs evaluated of them, evaluations and evaluations/s,
control steps, the best training score, generator and evaluator busy (with how long the model's
call in flight has run, from its first second, and the tokens it has written where the generator
tells: the in-process llama.cpp model), and the time left
against the limit that binds (samples, seconds, or a target score), from the first seconds on
(the search's own estimate: the starter's calibration until samples settle, then each batch's). Log lines print above it
(rich's logging handler on the display's console), never into it. Without a terminal: the
same numbers as one plain log line every `search.progress_every_s` seconds.
"""

from __future__ import annotations

import contextlib
import logging
import math
import threading
from dataclasses import dataclass
from typing import TYPE_CHECKING, Iterator, Optional

from rich.console import Console
from rich.live import Live
from rich.logging import RichHandler
from rich.progress_bar import ProgressBar
from rich.table import Table

from colmo.timelimit import duration

if TYPE_CHECKING:
    from colmo.search import Search

log = logging.getLogger("colmo.search")


@dataclass(frozen=True)
class Snapshot:
    """The numbers a progress display shows, read from a running search."""

    samples: int  # model calls settled
    max_samples: int
    in_flight: int  # model calls whose samples are being evaluated
    programs_evaluated: int  # new programs that were evaluated (not duplicates, not failures)
    evaluations: int
    steps: int
    elapsed: float
    best: Optional[float]
    generator_busy: float
    evaluator_busy: float
    max_seconds: float  # the run's time limit, counted from the search's start
    stop_at_score: Optional[float]
    estimated_seconds: Optional[float] = None  # when the search ends by max_samples (`TimeBudget.estimated_seconds`)
    resumed_samples: int = 0  # model calls an earlier process of a resumed run settled: not in this one's rate
    call_seconds: Optional[float] = None  # how long the generator's call in flight has run (None: no call in flight)
    call_tokens: Optional[int] = None  # what that call has generated so far (None: its generator does not say; 0: reading the prompt)

    @property
    def evaluations_per_second(self) -> float:
        return self.evaluations / self.elapsed if self.elapsed else 0.0

    def time_left(self) -> tuple[Optional[float], str]:
        """Seconds left against the limit that binds first, and its name: `stop_at_score` (0 s:
        the target is reached, the search is finishing), else whichever of `max_seconds` and
        `max_samples` ends the run sooner; `max_samples` by the search's own estimate (the
        starter's, then re-made as each batch settles: the one its log lines say) while it has
        not run out, else at the rate samples have settled so far. None when nothing tells yet
        (no estimate left, no sample settled and no time limit)."""
        if self.stop_at_score is not None and self.best is not None and self.best >= self.stop_at_score:
            return 0.0, "stop_at_score"
        settled_here = self.samples - self.resumed_samples
        rate = settled_here / self.elapsed if self.elapsed and settled_here else 0.0
        by_samples = max(self.max_samples - self.samples, 0) / rate if rate else None
        if self.estimated_seconds is not None and self.estimated_seconds > self.elapsed:
            by_samples = self.estimated_seconds - self.elapsed  # an estimate that has run out tells nothing
        by_seconds = max(self.max_seconds - self.elapsed, 0.0) if self.max_seconds else None
        if by_seconds is not None and (by_samples is None or by_seconds <= by_samples):
            return by_seconds, "max_seconds"
        return by_samples, "max_samples"

    def fraction_done(self) -> float:
        """How far the run is towards the limit that binds, in [0, 1]."""
        _, limit = self.time_left()
        if limit == "stop_at_score":
            return 1.0
        if limit == "max_seconds":
            return min(self.elapsed / self.max_seconds, 1.0)
        return min(self.samples / self.max_samples, 1.0)

    def _best(self) -> str:
        best = "—" if self.best is None or not math.isfinite(self.best) else f"{self.best:.1f}"
        return best + (f" (target {self.stop_at_score:g})" if self.stop_at_score is not None else "")

    def _left(self) -> str:
        left, limit = self.time_left()
        return f"{duration(left)} left ({limit})"

    def _counts(self) -> str:
        return (
            f"model calls {self.samples}/{self.max_samples} (+{self.in_flight} in flight) | "
            f"programs evaluated {self.programs_evaluated:,} | evals {self.evaluations:,}"
        )

    def _scores(self) -> str:
        return f"best {self._best()} | {self.evaluations_per_second:.1f} evals/s | steps {self.steps:,}"

    def _busy(self) -> str:
        calling = ""
        if self.call_seconds is not None and self.call_seconds >= 1:
            tokens = "" if self.call_tokens is None else ", reading the prompt" if not self.call_tokens else f", {self.call_tokens:,} tokens"
            calling = f" (call {duration(self.call_seconds)}{tokens})"
        return f"generator busy {self.generator_busy:.0%}{calling} | evaluators busy {self.evaluator_busy:.0%}"

    def line(self) -> str:
        """All the numbers on one line (the plain progress line)."""
        return f"{self._counts()} | {self._scores()} | {self._busy()} | {self._left()}"

    def lines(self) -> tuple[str, str, str, str]:
        """The numbers in four short lines (the live display, under 100 columns)."""
        return f"{self.fraction_done():4.0%} | {self._left()}", self._counts(), self._scores(), self._busy()


def snapshot(search: "Search") -> Snapshot:
    """What `search` has done so far."""
    totals, executor, limits = search.totals(), search.executor, search.cfg.search
    return Snapshot(
        samples=totals.samples, max_samples=limits.max_samples, in_flight=search.in_flight_samples,
        programs_evaluated=totals.programs_evaluated,
        # The executor's counts move with every evaluation; the totals' with every integrated batch.
        evaluations=executor.evaluations_done, steps=executor.steps_done, elapsed=search.budget.elapsed(),
        best=search.database.best.score if search.database else None,
        generator_busy=totals.generator_busy, evaluator_busy=totals.evaluator_busy,
        max_seconds=search.budget.limit_seconds, stop_at_score=limits.stop_at_score,
        estimated_seconds=search.budget.estimated_seconds, resumed_samples=search.resumed_samples,
        call_seconds=search.sampler.call_seconds(), call_tokens=search.sampler.call_tokens(),
    )


def render(state: Snapshot, width: int = 100) -> Table:
    """The live display: a bar of the binding limit with the time left beside it, and the
    numbers in three lines under it (each under 100 columns; cut with an ellipsis on a narrower terminal)."""
    head, *numbers = state.lines()
    top = Table.grid(padding=(0, 1))
    top.add_row(ProgressBar(total=1.0, completed=state.fraction_done(), width=max(10, min(60, width - len(head) - 1))), head)
    table = Table.grid()
    table.add_column(no_wrap=True, overflow="ellipsis")
    for row in (top, *numbers):
        table.add_row(row)
    return table


@contextlib.contextmanager
def live_display(search: "Search", console: Console) -> Iterator[None]:
    """The terminal display (module docstring) while the block runs."""
    live = Live(get_renderable=lambda: render(snapshot(search), console.width), console=console, refresh_per_second=2, transient=True)
    root = logging.getLogger()
    # Hydra's console handler writes to the real stderr: the display's console takes over.
    replaced = [h for h in root.handlers if type(h) is logging.StreamHandler]
    handler = RichHandler(console=console, show_path=False)
    for old in replaced:
        root.removeHandler(old)
    root.addHandler(handler)
    # The first frame is drawn here, before the search logs anything. Rich works out what a
    # printed line erases of the display before it renders the line, and writes later: a first
    # frame that its refresh thread drew in between (the search's first log line comes within
    # its first half second) stayed on screen, under or mixed with that line.
    live.start(refresh=True)
    try:
        yield
    finally:
        live.stop()
        root.removeHandler(handler)
        for old in replaced:
            root.addHandler(old)


@contextlib.contextmanager
def plain_lines(search: "Search", every_s: float) -> Iterator[None]:
    """A progress line in the log every `every_s` seconds while the block runs."""
    done = threading.Event()

    def report() -> None:
        while not done.wait(every_s):
            log.info("progress: %s", snapshot(search).line())

    thread = threading.Thread(target=report, daemon=True, name="colmo-progress")
    thread.start()
    try:
        yield
    finally:
        done.set()


def progress(search: "Search", console: Optional[Console] = None) -> contextlib.AbstractContextManager:
    """The live display on a terminal, plain lines otherwise, nothing when `search.progress` is off."""
    limits = search.cfg.search
    if not limits.progress:
        return contextlib.nullcontext()
    console = console or Console(stderr=True)
    if console.is_terminal:
        return live_display(search, console)
    return plain_lines(search, limits.progress_every_s)
