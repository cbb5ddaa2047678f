"""The machine's load over a run (`LoadMeter`), which every timed result states: on 2 cores a
process beside a search takes a share of its samples, so a comparison at equal wall clock says
the load it was measured under."""

from __future__ import annotations

import bisect
import os
import threading
from typing import Callable

# The windows of the machine's load averages (1, 5 and 15 minutes), and up to how long a gap
# between two readings each stands for: the average whose window is nearest the gap.
_LOAD_GAPS_S = (150.0, 600.0)


def load_averages() -> tuple[float, float, float]:
    """The machine's 1-, 5- and 15-minute load averages; zeros where the platform has none."""
    try:
        return os.getloadavg()
    except (AttributeError, OSError):
        return (0.0, 0.0, 0.0)


class LoadMeter:
    """The machine's load average (`os.getloadavg`: the run's own processes included) integrated
    over a run's wall-clock seconds, read whenever the run reports its time. Each reading stands
    for the seconds since the one before, with the average whose window (1, 5 or 15 minutes) fits
    that gap: a locomotion search reports every few minutes. 0 where the platform has no load
    average."""

    def __init__(self, read: Callable[[], tuple[float, float, float]] = load_averages) -> None:
        self._read = read
        self._lock = threading.Lock()  # the progress display reads the run's time from its own thread
        self._at = 0.0
        self._load_seconds = 0.0

    def load_seconds(self, seconds: float) -> float:
        """Load-seconds up to `seconds` into the run."""
        with self._lock:
            gap = seconds - self._at
            if gap > 0:
                self._load_seconds += self._read()[bisect.bisect_left(_LOAD_GAPS_S, gap)] * gap
                self._at = seconds
            return self._load_seconds
