"""What the end of a search will cost, and how it is cut to fit a time limit.

With `search.max_seconds`, the whole run (from its job's start: `colmo.timelimit.job_start`)
must end by the limit, the finish (`colmo.finish`) included: `plan_finish` estimates what each of
its steps costs from what the referee costs (`RefereeCost`: per episode, and per lockstep batch
of episodes, measured on the starter and the search's programs) and, where the full work does not
fit in the time it is given, makes each step cheaper (fewer held-out episodes and programs, a
shorter simplification, a shorter re-tuning, a smaller video: down to 15 frames a second, then
only the episode's first seconds, never a slide show). The search stops early enough to leave that time
(`colmo.timelimit`), and the finish plans again with the time actually left.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from colmo.config import SearchConfig
from colmo.optimize.methods import racing_on
from colmo.robustness import grid_points
from colmo.sandbox.referee import LOCKSTEP

SAFETY = 1.5  # a loaded machine runs the finish this much slower than the calibration measured
FINISH_SHARE = 0.4  # of a time limit, at most, for the finish when the full work does not fit
# The plot and ffmpeg's start (matplotlib's import and the GL probe are warmed up in a thread
# during the held-out scores), beside the video's frames.
RENDER_FIXED_S = 5.0
VIDEO_S = 20.0  # seconds of frames for a full-size video at its full frame rate, at most
VIDEO_MIN_S = 2.0  # seconds of frames for a small, short video
SMALL = (320, 240)
# Of a candidate's episodes, those a re-tuning with racing runs, at most: 21-48% in the quadruped's
# and the A1's re-tunings at 1000 evaluations (docs/locomotion-search.md).
RACED_SHARE = 0.5


@dataclass(frozen=True)
class RefereeCost:
    """What the referee's evaluations cost a worker: each episode's simulator and policy
    (`episode`), and each lockstep batch of up to `LOCKSTEP` episodes its round trips, one per
    control step shared by the batch (`batch`). A 100-episode held-out score costs far less than
    ten 10-episode ones: on the pendulum it took a fifth of what their per-episode cost said."""

    episode: float
    batch: float

    @classmethod
    def of(cls, fast_seconds: float, referee_seconds: float, episodes: int) -> "RefereeCost":
        """From a fast-path and a referee evaluation of one program on the same `episodes` (one
        lockstep batch): the fast path's time is the episodes' own, the referee's excess the batch's."""
        return cls(fast_seconds / max(episodes, 1), max(referee_seconds - fast_seconds, 0.0))

    def scaled(self, factor: float) -> "RefereeCost":
        return RefereeCost(self.episode * factor, self.batch * factor)

    def seconds(self, episodes: int, workers: int) -> float:
        """`episodes` spread over `workers`, each worker's share in lockstep batches, with `SAFETY`."""
        share = math.ceil(episodes / max(workers, 1))
        return SAFETY * max(share * self.episode + math.ceil(share / LOCKSTEP) * self.batch, 0.01)


@dataclass(frozen=True)
class FinishPlan:
    """What the end of a run will do, and the seconds each step is given."""

    top: int  # programs that get a held-out score
    heldout_episodes: int
    heldout_seconds: float
    simplify_seconds: float
    render_seconds: float
    video_seconds: float
    size: tuple[int, int]  # of the video
    reduced: bool  # cheaper than configured, to fit the time limit
    robustness_seconds: float = 0.0  # the best program's robustness report; 0: none
    retune_seconds: float = 0.0  # the final policy's re-tuning and its held-out score; 0: none

    @property
    def seconds(self) -> float:
        return self.heldout_seconds + self.robustness_seconds + self.simplify_seconds + self.retune_seconds + self.render_seconds

    def describe(self, cfg: SearchConfig) -> str:
        parts = [f"held-out scores of {self.top} program(s) over {self.heldout_episodes} episodes"]
        if cfg.finish.robustness:
            parts.append("robustness report" if self.robustness_seconds else "no robustness report")
        if cfg.finish.simplify:
            parts.append(f"simplification {self.simplify_seconds:.0f} s")
        if cfg.finish.retune_budget:
            parts.append(f"re-tuning {self.retune_seconds:.0f} s")
        if cfg.finish.render:
            parts.append(f"video {self.size[0]}x{self.size[1]}")
        return ", ".join(parts) + (" (reduced to fit search.max_seconds)" if self.reduced else "")


def plan_finish(cfg: SearchConfig, referee: RefereeCost, workers: int, available: float = math.inf) -> FinishPlan:
    """The finish as configured if it fits in `available` seconds, else each step cheaper, in
    equal shares of it. `referee`: what its evaluations cost (measured on the search's programs)."""
    episode = referee.seconds(1, 1)  # one episode alone: the render's
    episodes, top, workers = cfg.heldout.episodes, cfg.finish.top, max(workers, 1)

    def heldout_cost(programs: int, n: int) -> float:
        return programs * referee.seconds(n, workers)

    # The simplifier measures the best program twice on both episode sets, then a few rounds; a
    # long run keeps a share of its time for it (a winner of 65 constants needs a minute of rounds).
    share = min(cfg.finish.simplify_share * cfg.search.max_seconds, cfg.simplify.max_seconds or math.inf)
    simplify = max(6 * (heldout_cost(1, episodes) + heldout_cost(1, cfg.task.episodes)), share) if cfg.finish.simplify else 0.0
    render = episode + RENDER_FIXED_S + VIDEO_S if cfg.finish.render else 0.0
    grid = grid_points(cfg.finish.robustness_magnitudes, cfg.finish.robustness_delays)
    robustness = heldout_cost(grid, cfg.finish.robustness_episodes) if cfg.finish.robustness else 0.0
    retune = retune_cost(cfg, referee, workers) if cfg.finish.retune_budget else 0.0
    full = FinishPlan(top, episodes, heldout_cost(top, episodes), simplify, render, VIDEO_S, (640, 480), False, robustness, retune)
    if full.seconds <= available:
        return full
    steps = 1 + cfg.finish.simplify + cfg.finish.render + cfg.finish.robustness + bool(retune)
    # The robustness report, already on few episodes, is whole or skipped: it keeps its cost if that fits in an equal share.
    if robustness > available / steps:
        robustness = 0.0
    # Simplifying measures the best program on the training and the held-out episodes, then scores
    # its candidates the same way: at least three such measurements, or it cannot start. So the
    # held-out episodes are as many as leave it that; further programs' held-out scores and a
    # longer simplification share what remains.
    measurements = 3 if cfg.finish.simplify else 0
    training = heldout_cost(1, cfg.task.episodes)
    least = (1 + measurements) * heldout_cost(1, min(workers, episodes)) + measurements * training
    # The render gets what it cannot do without (the episode, the plot, a few frames), and an
    # equal share up to its full video: what the full video would not use is the other steps'.
    least_render = episode + RENDER_FIXED_S + VIDEO_MIN_S if cfg.finish.render else 0.0
    whole_video = render <= available / steps
    render = render if whole_video else max(least_render, available / steps)
    # The re-tuning stops where its slot ends with the best constants so far: an equal share of
    # what the render leaves at most, and only what the other steps can spare of what they cannot do without.
    retune = min(retune, (available - render) / (steps - cfg.finish.render), max(available - robustness - render - least, 0.0))
    left = max(available - robustness - retune - render, 0.0)
    budget = max(left - measurements * training, 0.0) / (1 + measurements)  # for one held-out score
    held_out = next((n for n in range(episodes, workers, -workers) if heldout_cost(1, n) <= budget), min(workers, episodes))
    one = heldout_cost(1, held_out)  # a program's held-out score
    spare = left - one - measurements * (one + training)
    kept = min(top, 1 + max(int(spare / (1 + cfg.finish.simplify) // one), 0))
    # (The whole video's size is decided, not read back from its seconds: they lose the last bit.)
    video = VIDEO_S if whole_video else max(render - episode - RENDER_FIXED_S, VIDEO_MIN_S)
    return FinishPlan(
        kept, held_out, kept * one,
        max(left - kept * one, 0.0) if cfg.finish.simplify else 0.0, render, video, (640, 480) if whole_video else SMALL, True, robustness,
        retune,
    )


def retune_cost(cfg: SearchConfig, referee: RefereeCost, workers: int) -> float:
    """What re-tuning the final policy costs: `finish.retune_budget` fast-path evaluations on the
    training episodes, one candidate per worker at a time (`colmo.finish`), with racing
    `RACED_SHARE` of their episodes; then the referee's training and held-out scores."""
    workers = max(workers, 1)
    episodes = max(cfg.gfo.racing_min_episodes, RACED_SHARE * cfg.task.episodes) if racing_on(cfg.gfo) else cfg.task.episodes
    candidates = SAFETY * cfg.finish.retune_budget * episodes * referee.episode / workers
    return candidates + referee.seconds(cfg.task.episodes, workers) + referee.seconds(cfg.heldout.episodes, workers)
