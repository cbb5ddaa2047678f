"""The model's share of the wall clock beside the filler (`search.model_share`, with `search.fill`).

With `always` a search calls its model back to back, as it does without a filler. With
`by_yield` it measures, as it goes, what each generator's samples yield for what they cost:
the island bests they set (a sample scoring above every program of its island so far) per
CPU-second (their programs' evaluation, and for the model its calls times the cores of this
machine they keep busy, `Generator.cores`). After each call the model pauses so that its calls,
since the first began, take a share of the time equal to its yield's part of the two yields,
never less than `search.min_model_share`: a long call, or calls made while its share was higher,
are paid for by a longer pause. While it pauses the filler has the workers and the cores. A model
that pays on this machine is called often; one that does not costs little, and is still asked
now and then, since its programs and what it makes of mutation's change as the search goes.
This is probability matching over two arms whose pulls are shares of time, each rate starting
from one island best in `PRIOR_CPU_S` so that neither is judged on its first few samples.
"""

from __future__ import annotations

import logging
import time
from typing import TYPE_CHECKING, Any, Callable, Mapping, Optional

if TYPE_CHECKING:
    from colmo.generate import Generator

log = logging.getLogger("colmo.search")
PRIOR_CPU_S = 100.0  # one pseudo island best in this many CPU-seconds, for each generator


def cpu_seconds(entry: Mapping[str, Any], cores: int) -> float:
    """What one generator's samples cost (`Counters.by_generator`'s entry): their evaluation, and
    their generation times the cores it keeps busy."""
    return entry.get("evaluation_seconds", 0.0) + entry.get("generation_seconds", 0.0) * cores


def island_bests_per_cpu_second(entry: Mapping[str, Any], cores: int) -> float:
    """One generator's yield so far, with one pseudo island best in `PRIOR_CPU_S`."""
    return (entry.get("island_bests", 0) + 1) / (cpu_seconds(entry, cores) + PRIOR_CPU_S)


def model_share(model: Mapping[str, Any], model_cores: int, filler: Mapping[str, Any], filler_cores: int, floor: float) -> float:
    """The share of the wall clock the model calls for: its yield's part of the two, at least
    `floor`; each generator's `Counters.by_generator` entry and `Generator.cores`."""
    model_yield = island_bests_per_cpu_second(model, model_cores)
    filler_yield = island_bests_per_cpu_second(filler, filler_cores)
    return max(floor, model_yield / (model_yield + filler_yield))


def next_call_at(first_call_began: float, calling_seconds: float, share: float) -> float:
    """When the model may call again so that its calls since the first began, `calling_seconds`
    in all, have taken `share` of the time."""
    return first_call_began + calling_seconds / share


class ModelShare:
    """When a search's model may call next: at once with `always`; with `by_yield`, after the
    pause its share says, measured on the generators' samples settled by the end of each call."""

    def __init__(self, mode: str, floor: float, clock: Callable[[], float] = time.perf_counter):
        self.by_yield = mode == "by_yield"
        self.floor = floor
        self.clock = clock
        self.pauses_until = 0.0  # `clock()` before which the model is not called
        self.filler_label = ""  # the label of the filler's samples (`Counters.by_generator`), once it has made some
        self.first_call_began: Optional[float] = None
        self.calling_seconds = 0.0  # the model's calls so far, in all

    def called(
        self, model: "Generator", label: str, seconds: float, filler: Optional["Generator"], by_generator: Mapping[str, Mapping[str, Any]],
    ) -> None:
        """The model, whose samples are `label`'s, has answered a call of `seconds`."""
        if not self.by_yield or filler is None:
            return
        mine, filler_entry = by_generator.get(label, {}), by_generator.get(self.filler_label, {})
        share = model_share(mine, model.cores(), filler_entry, filler.cores(), self.floor)
        now = self.clock()
        if self.first_call_began is None:
            self.first_call_began = now - seconds
        self.calling_seconds += seconds
        self.pauses_until = next_call_at(self.first_call_began, self.calling_seconds, share)
        pause = max(0.0, self.pauses_until - now)
        log.info(
            "model share %.2f (island bests per 1000 CPU-seconds: %s %.2f, %s %.2f): its next call in %.1f s",
            share, label, 1000 * island_bests_per_cpu_second(mine, model.cores()),
            self.filler_label or "filler", 1000 * island_bests_per_cpu_second(filler_entry, filler.cores()), pause,
        )

    def paused(self) -> bool:
        return self.clock() < self.pauses_until
