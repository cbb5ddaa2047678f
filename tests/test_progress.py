"""The progress display (`colmo.progress`): what it renders, the time left against each limit,
plain lines without a terminal, and a recorded terminal session of `python -m colmo` under a
pseudo-terminal: the display moves within a batch, and log lines print whole, above it."""

from __future__ import annotations

import collections
import fcntl
import io
import logging
import os
import pty
import re
import struct
import subprocess
import sys
import termios
import time
from types import SimpleNamespace

import pytest
from rich.console import Console

from colmo.progress import Snapshot, progress, render
from colmo.record import DUPLICATE, EVALUATED, Counters, Elapsed


def state(**fields) -> Snapshot:
    values = dict(
        samples=40, max_samples=100, in_flight=4, programs_evaluated=12, evaluations=1234, steps=12_340_000, elapsed=120.0, best=512.345,
        generator_busy=0.25, evaluator_busy=0.93, max_seconds=0.0, stop_at_score=None,
    )
    return Snapshot(**(values | fields))


def test_rendered_display_snapshot():
    console = Console(file=io.StringIO(), record=True, width=100)
    console.print(render(state(max_seconds=600.0, stop_at_score=900.0), console.width))
    assert console.export_text() == (
        "━━━━━━━━━━━━━━━━━━━━━━━━                                      40% | 3m00s left (max_samples)\n"
        "model calls 40/100 (+4 in flight) | programs evaluated 12 | evals 1,234                     \n"
        "best 512.3 (target 900) | 10.3 evals/s | steps 12,340,000                                   \n"
        "generator busy 25% | evaluators busy 93%                                                    \n"
    )


def test_every_line_of_the_display_fits_in_100_columns():
    big = state(
        samples=123_456, max_samples=1_000_000, in_flight=64, programs_evaluated=99_999, evaluations=123_456_789, steps=98_765_432_100, elapsed=86_000.0,
        best=-12345.678, max_seconds=90_000.0, stop_at_score=-100.0,
    )
    console = Console(file=io.StringIO(), record=True, width=100)
    console.print(render(big, console.width))
    assert "…" not in console.export_text()


@pytest.mark.parametrize(
    "fields, left, limit, fraction",
    [
        # 40 samples in 120 s: the other 60 take 180 s, before the 600 s limit.
        ({"max_seconds": 600.0}, 180.0, "max_samples", 0.4),
        # 10 samples in 120 s: the other 90 would take 1080 s; the 600 s limit comes first.
        ({"samples": 10, "max_seconds": 600.0}, 480.0, "max_seconds", 0.2),
        ({"samples": 10}, 1080.0, "max_samples", 0.1),  # no time limit
        ({"samples": 0, "max_seconds": 600.0}, 480.0, "max_seconds", 0.2),  # no rate yet: the time limit tells
        ({"samples": 0}, None, "max_samples", 0.0),  # nothing tells yet
        ({"elapsed": 700.0, "max_seconds": 600.0}, 0.0, "max_seconds", 1.0),  # past the deadline: finishing
        ({"best": 950.0, "stop_at_score": 900.0, "max_seconds": 600.0}, 0.0, "stop_at_score", 1.0),  # target reached
        ({"best": 850.0, "stop_at_score": 900.0}, 180.0, "max_samples", 0.4),  # target not reached: the others bind
        ({"best": None, "stop_at_score": 900.0}, 180.0, "max_samples", 0.4),  # no score yet
        # A resumed run: 30 of its 40 samples were settled before; 10 in this process's 120 s.
        ({"resumed_samples": 30}, 720.0, "max_samples", 0.4),
    ],
)
def test_time_left_against_the_binding_limit(fields, left, limit, fraction):
    snapshot = state(**fields)
    assert snapshot.time_left() == (pytest.approx(left) if left is not None else None, limit)
    assert snapshot.fraction_done() == pytest.approx(fraction)
    assert f"left ({limit})" in snapshot.line()


def test_before_the_first_sample_the_calibration_estimate_tells_the_time_left():
    # The starter's calibration estimated 1000 s for the samples; 120 s have passed.
    snapshot = state(samples=0, estimated_seconds=1000.0)
    assert snapshot.time_left() == (pytest.approx(880.0), "max_samples")
    assert "14m40s left (max_samples)" in snapshot.line()
    # A 600 s limit binds before the estimate.
    assert state(samples=0, estimated_seconds=1000.0, max_seconds=600.0).time_left() == (pytest.approx(480.0), "max_seconds")


def test_once_samples_settle_the_searchs_own_estimate_tells_the_time_left():
    # 40 samples in 120 s would say 180 s more at that rate; the search's estimate (the one its
    # log lines say, made as each batch settles) says 600 s from the start: 480 s more.
    assert state(estimated_seconds=600.0).time_left() == (pytest.approx(480.0), "max_samples")
    assert state(estimated_seconds=100.0).time_left() == (pytest.approx(180.0), "max_samples")  # run out: the rate


def test_unknown_time_left_reads_as_a_question_mark():
    assert "? left (max_samples)" in state(samples=0).line()


def test_an_estimate_that_has_run_out_tells_nothing():
    # 1000 s estimated, 1200 s passed, no sample in yet: not "0m00s left" while a model still thinks.
    assert state(samples=0, estimated_seconds=1000.0, elapsed=1200.0).time_left() == (None, "max_samples")


def test_the_models_call_in_flight_shows_from_its_first_second():
    assert "generator busy 25% (call 1m03s) | evaluators busy 93%" in state(call_seconds=63.4).line()
    assert "generator busy 25% | evaluators" in state(call_seconds=0.2).line()  # mutate answers at once: no flicker
    assert "(call" not in state().line()
    assert "generator busy 25% (call 1m03s, 212 tokens) |" in state(call_seconds=63.4, call_tokens=212).line()
    assert "(call 2m00s, reading the prompt) |" in state(call_seconds=120.0, call_tokens=0).line()


def fake_search(max_samples: int = 10, progress_every_s: float = 0.05) -> SimpleNamespace:
    """What `colmo.progress.snapshot` reads from a search (no search runs)."""
    executor = SimpleNamespace(evaluations_done=7, steps_done=70_000)
    limits = SimpleNamespace(max_samples=max_samples, max_seconds=0.0, stop_at_score=None, progress=True, progress_every_s=progress_every_s)
    # 3 model calls, one program evaluated; in 10 s the generator was busy 0.5 s, the 2 workers 1 s together.
    counters = Counters(samples=3, records=3, by_status=collections.Counter({EVALUATED: 1, DUPLICATE: 2}))
    return SimpleNamespace(
        totals=lambda: counters.totals(Elapsed(10.0, 0.5, 1.0), 2),
        budget=SimpleNamespace(limit_seconds=0.0, estimated_seconds=None, elapsed=lambda: 10.0),
        executor=executor, in_flight_samples=2, resumed_samples=0, database=None, cfg=SimpleNamespace(search=limits),
        sampler=SimpleNamespace(call_seconds=lambda: None, call_tokens=lambda: None),
    )


def test_without_a_terminal_a_plain_line_every_few_seconds(caplog):
    search = fake_search()
    console = Console(file=io.StringIO())  # not a terminal
    with caplog.at_level(logging.INFO, logger="colmo.search"):
        with progress(search, console):
            deadline = time.monotonic() + 60
            while sum("progress: model calls 3/10 (+2 in flight) | programs evaluated 1 | evals 7" in m for m in caplog.messages) < 2 and time.monotonic() < deadline:
                time.sleep(0.05)
    lines = [m for m in caplog.messages if m.startswith("progress: ")]
    assert len(lines) >= 2, caplog.messages
    assert "steps 70,000" in lines[0] and "best —" in lines[0] and "generator busy 5% | evaluators busy 5%" in lines[0]
    assert console.file.getvalue() == ""  # no live display


def test_progress_off_shows_nothing(caplog):
    search = fake_search()
    search.cfg.search.progress = False
    console = Console(file=io.StringIO(), force_terminal=True)
    with caplog.at_level(logging.INFO, logger="colmo.search"), progress(search, console):
        time.sleep(0.3)
    assert console.file.getvalue() == "" and not [m for m in caplog.messages if m.startswith("progress: ")]


# -- a recorded terminal session ------------------------------------------------------------------

COLUMNS = 200
_CONTROL = re.compile(r"\x1b\[([?0-9;]*)([A-Za-z])|\r|\n|[^\x1b\r\n]")


class Terminal:
    """The screen a person would see: a minimal terminal for what rich writes (text, carriage
    return, line feed, cursor up and down, erase in line; colours and cursor visibility
    ignored), without scrolling, so every line ever shown stays in `lines`."""

    def __init__(self, width: int):
        self.width = width
        self.rows: list[list[str]] = [[]]
        self.row = self.col = 0

    def feed(self, text: str) -> None:
        for token in _CONTROL.finditer(text):
            if token.group(2):
                self._control(token.group(1), token.group(2))
            elif token.group() == "\r":
                self.col = 0
            elif token.group() == "\n":
                self._move(self.row + 1)
            else:
                if self.col >= self.width:  # a full line wraps when the next character comes
                    self._move(self.row + 1)
                    self.col = 0
                line = self.rows[self.row]
                line.extend(" " * (self.col + 1 - len(line)))
                line[self.col] = token.group()
                self.col += 1

    def _control(self, params: str, command: str) -> None:
        count = int(params) if params.isdigit() else 1
        if command == "A":
            self.row = max(self.row - count, 0)
        elif command == "B":
            self._move(self.row + count)
        elif command == "K":
            line = self.rows[self.row]
            if params == "2":
                line.clear()
            elif params in ("", "0"):
                del line[self.col :]
        elif command == "G":
            self.col = count - 1

    def _move(self, row: int) -> None:
        self.row = row
        while len(self.rows) <= row:
            self.rows.append([])

    @property
    def lines(self) -> list[str]:
        return ["".join(row).rstrip() for row in self.rows]


class SlowLine:
    """A line that takes a second to render: printed on the display's console, it is between
    rich's choice of what to erase and its write while the display redraws (twice a second)."""

    text = "a line printed as the display starts"

    def __rich_console__(self, console, options):
        time.sleep(1.0)
        yield self.text


def test_a_line_printed_as_the_display_starts_stands_above_it():
    # A log line printed just as the display starts (the search's first one comes within half a
    # second) while its first frame is drawn: the line stands alone, the display leaves nothing.
    console = Console(file=io.StringIO(), force_terminal=True, width=COLUMNS, height=50)
    with progress(fake_search(), console):
        console.print(SlowLine())
    screen = Terminal(COLUMNS)
    screen.feed(console.file.getvalue().replace("\n", "\r\n"))  # a terminal's line discipline adds the \r
    assert [line for line in screen.lines if line] == [SlowLine.text], screen.lines


def record_session(args: list[str], cwd, timeout: float = 600) -> str:
    """Run `python -m colmo <args>` with a pseudo-terminal as its stdin, stdout and stderr (as a
    person in a terminal would), and return everything it wrote there."""
    controller, terminal = pty.openpty()
    fcntl.ioctl(terminal, termios.TIOCSWINSZ, struct.pack("HHHH", 50, COLUMNS, 0, 0))
    env = {k: v for k, v in os.environ.items() if k not in ("COLUMNS", "LINES", "NO_COLOR")} | {"TERM": "xterm-256color"}
    process = subprocess.Popen(
        [sys.executable, "-m", "colmo", *args], cwd=cwd, stdin=terminal, stdout=terminal, stderr=terminal, env=env, start_new_session=True
    )
    os.close(terminal)
    output = bytearray()
    deadline = time.monotonic() + timeout
    try:
        while time.monotonic() < deadline:
            try:
                chunk = os.read(controller, 65536)
            except OSError:  # EIO: the session ended, every writer closed its side
                break
            if not chunk:
                break
            output += chunk
        process.wait(timeout=max(deadline - time.monotonic(), 1))
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
        os.close(controller)
    assert process.returncode == 0, output.decode(errors="replace")[-3000:]
    return output.decode(errors="replace")


DISPLAY = re.compile(r"model calls (\d+)/\d+ \(\+\d+ in flight\) \| programs evaluated [\d,]+ \| evals ([\d,]+) ")
DISPLAY_PART = re.compile(r"in flight\) \| programs evaluated|evaluators busy \d+%|left \((max_samples|max_seconds|stop_at_score)\)|━")
LOG_LEVEL = re.compile(r"\b(INFO|WARNING|ERROR)\b")
BATCH_LOG = re.compile(r"batch (\d+): samples")


def test_recorded_terminal_session(tmp_path):
    # Batches of 2 programs, one batch at a time, each program tuned with 20 candidates: a
    # batch takes seconds, the display redraws twice a second. The finish logs its held-out
    # scores under the display (no video or simplification: they log the same way, slower).
    args = [
        "task=pendulum", "tracker=none", "seed=0", "gfo.budget=20", "search.max_samples=6", "llm.batch_size=2",
        "search.queue_size=1", "executor.workers=2", "heldout.episodes=5", "finish.top=1",
        "finish.render=false", "finish.simplify=false",
    ]
    session = record_session(args, tmp_path)

    # (a) The display moves within a batch: before the first batch's log line, and between
    # two batches' log lines, the evaluations counter shown takes several increasing values
    # while the model calls counter stays.
    plain = re.sub(r"\x1b\[[0-9;]*m", "", session)  # colours off: rich's log handler colours numbers
    batch_logs = [m.start() for m in BATCH_LOG.finditer(plain)]
    assert [int(m.group(1)) for m in BATCH_LOG.finditer(plain)] == [0, 1, 2], plain[-3000:]
    moved = []
    for start, end in zip([0, *batch_logs], batch_logs):
        shown: dict[int, list[int]] = {}  # evaluations shown, by samples shown
        for m in DISPLAY.finditer(plain, start, end):
            shown.setdefault(int(m.group(1)), []).append(int(m.group(2).replace(",", "")))
        moved.append(any(len(set(counts)) >= 2 and counts == sorted(counts) for counts in shown.values()))
    assert moved[0] and any(moved[1:]), moved

    # (b) Log lines print whole, above the display: replaying the session on a terminal, no
    # line ever mixes a log line with the display, and at the end (the display is transient)
    # every logged message stands whole on a line of its own, in order, and nothing of the
    # display is left.
    screen = Terminal(COLUMNS)
    frames = session.split("\r\x1b[2K")  # each redraw of the display starts so
    for index, frame in enumerate(frames):
        screen.feed(frame if index == 0 else "\r\x1b[2K" + frame)
        for line in screen.lines:
            assert not (DISPLAY_PART.search(line) and LOG_LEVEL.search(line)), line
    logged = [line.split("] ", 1)[1] for line in next(tmp_path.glob("outputs/pendulum/*/colmo.log")).read_text().splitlines() if line.startswith("[")]
    shown = [line for line in screen.lines if LOG_LEVEL.search(line)]
    assert len(shown) == len(logged), (shown, logged)
    for line, message in zip(shown, logged):
        assert line.endswith(message), (line, message)
    assert not [line for line in screen.lines if DISPLAY_PART.search(line)]
    assert "stopped: max_samples" in session
