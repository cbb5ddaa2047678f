"""What a finished search does with its best programs: the held-out scores of the top ones, the
simplified best policy, and a video and plot of it in action.

A search selects programs by their training score, which therefore flatters the winner; the
top `evaluation.top` structures get a held-out score from the referee on `evaluation.episodes`
fresh episodes (`colmo.evaluate`). The best one is then simplified (`colmo.simplify`) and
rendered (`colmo.render`) on its first held-out episode, into the run directory. Each step is
optional, and none can fail the search: a missing OpenGL or a simplification that finds
nothing to remove is a line in the log and in the summary.

With `search.max_seconds`, this work must end by `until` (the search's deadline plus a grace
period): each step gets the time that is left, and one that does not fit is skipped and logged.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

from colmo.config import SearchConfig
from colmo.errors import RunError
from colmo.evaluate import heldout_evaluator, heldout_score
from colmo.evaluation import CANCELLED, Evaluator, Executor
from colmo.record import EVALUATED, SampleRecord
from colmo.store import SIMPLIFIED_POLICY_FILE, ProgramStore

log = logging.getLogger("colmo.search")

_RENDER_SECONDS = 60.0  # what a 1000-step video and its plot take on a loaded laptop core, at most


@dataclass
class BestPrograms:
    """The results of `finish`, for the summary: held-out scores of the top programs, and the
    files made for the best one (paths relative to the run directory)."""

    heldout: list[dict] = field(default_factory=list)
    media: dict = field(default_factory=dict)
    simplified: dict = field(default_factory=dict)


def top_records(store: ProgramStore, count: int) -> list[SampleRecord]:
    """The `count` best evaluated programs of a run, best first (earliest first among equals)."""
    records = sorted((r for r in store.records() if r.status == EVALUATED and r.sample >= 0), key=lambda r: (-r.score, r.sample))
    return records[:count]


def _left(until: float) -> float:
    return until - time.monotonic()


def finish(cfg: SearchConfig, store: ProgramStore, executor: Executor, evaluator: Evaluator, run_dir: Path, until: float = math.inf) -> BestPrograms:
    """Held-out scores of the top programs (stored with them), then the best one rendered, all
    by `until` (`time.monotonic()` seconds)."""
    best = BestPrograms()
    top = top_records(store, cfg.evaluation.top)
    heldout = heldout_evaluator(evaluator, cfg.seed, cfg.evaluation.episodes)
    best_took = 0.0  # seconds the best program's held-out score took: what simplifying costs per measurement
    for record in top:
        limit, started = min(_left(until), heldout.referee_timeout_s), time.monotonic()
        evaluation = heldout_score(executor, heldout, record.skeleton, record.params, timeout_s=limit) if limit > 0 else None
        if evaluation is not None and evaluation.failure == CANCELLED:  # the search is stopping at once
            return best
        # No time was left, or the time limit cut the evaluation short (it did not fail on its own).
        if evaluation is None or (evaluation.failure and limit < heldout.referee_timeout_s and _left(until) <= 0):
            log.warning("no time left for %d held-out scores (search.max_seconds)", len(top) - len(best.heldout))
            break
        best_took = best_took or time.monotonic() - started
        score: Optional[float] = None if evaluation.failure else evaluation.score
        store.set_heldout(record.sample, score)
        best.heldout.append({"sample": record.sample, "key": record.key, "score": record.score, "heldout_score": score, "heldout_failure": evaluation.failure})
        shown = "failed" if score is None else f"{score:.2f}"
        log.info("sample %d: training score %.2f, held-out %s over %d episodes", record.sample, record.score, shown, len(heldout.seeds))
    if not top:
        return best
    if cfg.evaluation.simplify:
        # Simplifying first measures the best program on the training and the held-out episodes.
        if not best.heldout or _left(until) < 2 * best_took:
            log.warning("no time left to simplify the best policy (search.max_seconds)")
        else:
            best.simplified = _simplify(cfg, executor, evaluator, heldout, top[0], run_dir, until)
    if cfg.evaluation.render:
        if _left(until) < _RENDER_SECONDS:
            log.warning("no time left for the video and plot of the best policy (search.max_seconds)")
            return best
        from colmo.render import render_policy  # matplotlib and the renderer: only when asked for

        title = f"{cfg.task.name}: best policy (sample {top[0].sample}, training score {top[0].score:.1f})"
        media = render_policy(executor, heldout, top[0].skeleton, top[0].params, run_dir, title)
        best.media = {name: str(path.relative_to(run_dir)) for name, path in (("plot", media.plot), ("video", media.video)) if path}
        if media.note:
            best.media["note"] = media.note
            log.warning("best policy: %s", media.note)
    return best


def _simplify(cfg: SearchConfig, executor: Executor, evaluator: Evaluator, heldout: Evaluator, record: SampleRecord, run_dir: Path, until: float) -> dict:
    """The best policy simplified into `simplified_policy.py`; its `to_json()` for the summary."""
    from colmo.simplify import simplify_program

    options = cfg.simplify
    try:
        result = simplify_program(
            executor, evaluator, heldout, record.code, cfg.gfo, options.tolerance, cfg.seed, options.max_rounds,
            options.batch_size, stop=lambda: _left(until) <= 0,
        )
    except RunError as error:  # the best program fails where the simplifier measures it
        log.warning("best policy not simplified: %s", error)
        return {"failure": str(error)}
    size = result.size
    log.info(
        "best policy simplified: %d -> %d AST nodes, %d -> %d parameters, training score %.2f -> %.2f",
        result.size_initial.nodes, size.nodes, result.size_initial.params, size.params, result.scores_initial.train, result.scores.train,
    )
    header = f"# colmo: the best policy of {cfg.task.name} simplified: training score {result.scores.train:.2f}, held-out {result.scores.heldout:.2f}\n"
    (run_dir / SIMPLIFIED_POLICY_FILE).write_text(header + result.code + "\n")
    return result.to_json()
