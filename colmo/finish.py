"""What a finished search does with its best programs: the held-out scores of the top ones, the
simplified best policy, and a video and plot of it in action.

A search selects programs by their training score, which therefore flatters the winner; the
top `finish.top` structures get a held-out score from the referee on `heldout.episodes`
fresh episodes (`colmo.heldout`). The best one's branches are counted over the training and
held-out episodes (`colmo.coverage`: the comments of best_policy.py); it is rendered
(`colmo.render`) on its first held-out episode, into the run directory; with `finish.robustness`
scored over a grid of model-mismatch magnitudes (`colmo.robustness`: robustness.json/.csv/.png, a
few numbers in the summary); then simplified (`colmo.simplify`), and with `finish.retune_budget`
the result's constants re-tuned at that budget (retuned_policy.py, with its held-out score beside
the one it started from: the search tunes each program at `gfo.budget`, far fewer evaluations
than a final policy of many constants may need). Each step is
optional, and none can fail the search: a missing OpenGL or a simplification that finds
nothing to remove is a line in the log and in the summary.

With `search.max_seconds`, the whole run must end by the limit, this work included: at the end,
`finish` plans its steps with the time actually left (`colmo.finish_plan`), and each step ends by
its slot; the summary says where the work was cut (`episodes` of each held-out score, the
video's `size` and `note`).
"""

from __future__ import annotations

import logging
import math
import threading
import time
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Optional, Sequence

from colmo import coverage, readability
from colmo.bounds import Bounds, decided_comparisons
from colmo.config import SearchConfig
from colmo.coverage import Pruned
from colmo.errors import RunError
from colmo.evaluation import CANCELLED, Evaluator, Executor
from colmo.finish_plan import RENDER_FIXED_S, VIDEO_MIN_S, FinishPlan, RefereeCost, plan_finish
from colmo.heldout import alike, branch_counts, heldout_evaluator, heldout_score, robustness_of
from colmo.intake import read_program
from colmo.names import misnamed
from colmo.optimize.tune import optimize_alone
from colmo.record import EVALUATED, SampleRecord, Summary, Totals, finite_or_none
from colmo.robustness import save
from colmo.shell import shell_override
from colmo.store import BEST_POLICY_FILE, RETUNED_POLICY_FILE, SIMPLIFIED_POLICY_FILE, ProgramStore

if TYPE_CHECKING:
    from colmo.database import StoredProgram

log = logging.getLogger("colmo.search")

_UNMEASURED = RefereeCost(0.0, 0.0)  # without a time limit, what the referee costs plans nothing


@dataclass
class BestPrograms:
    """The results of `finish`, for the summary: held-out scores of the top programs, and the
    files made for the best one (paths relative to the run directory)."""

    heldout: list[dict] = field(default_factory=list)
    media: dict = field(default_factory=dict)
    simplified: dict = field(default_factory=dict)
    retuned: dict = field(default_factory=dict)
    robustness: dict = field(default_factory=dict)
    coverage: dict = field(default_factory=dict)
    misnamed: list[str] = field(default_factory=list)
    decided: list[str] = field(default_factory=list)
    readability: dict = field(default_factory=dict)

    def summary(
        self, task: str, best: Optional["StoredProgram"], best_so_far: Sequence[tuple[int, float]], stop_reason: str, run_dir: Path, totals: Totals,
        startup_seconds: float = 0.0, search_seconds: float = 0.0, by_generator: Optional[dict] = None,
    ) -> Summary:
        """A search's summary: its `best` program (None if it has none), with its held-out score
        where it got one, and these results."""
        best_heldout = next((h["heldout_score"] for h in self.heldout if best and h["key"] == best.key), None)
        return Summary(
            task=task, best_score=best.score if best else None, best_heldout_score=best_heldout, best_key=best.key if best else None,
            best_code=best.code if best else None, best_so_far=tuple(best_so_far), stop_reason=stop_reason, run_dir=str(run_dir),
            heldout=tuple(self.heldout), media=self.media, simplified=self.simplified, retuned=self.retuned, robustness=self.robustness, coverage=self.coverage,
            misnamed=tuple(self.misnamed), decided=tuple(self.decided), readability=self.readability, startup_seconds=startup_seconds,
            search_seconds=search_seconds, by_generator=by_generator or {},
            **asdict(totals),
        )


def top_records(store: ProgramStore, count: int) -> list[SampleRecord]:
    """The `count` best evaluated programs of a run, best first (earliest first among equals);
    the starter among them, since a short run's best may be the starter."""
    records = sorted((r for r in store.records() if r.status == EVALUATED), key=lambda r: (-r.score, r.sample))
    return records[:count]


def _left(until: float) -> float:
    return until - time.monotonic()


def finish(
    cfg: SearchConfig, store: ProgramStore, executor: Executor, evaluator: Evaluator, run_dir: Path,
    until: float = math.inf, referee: RefereeCost = _UNMEASURED, observation_names: Sequence[str] = (), observation_bounds: Bounds = (),
) -> BestPrograms:
    """Held-out scores of the top programs (stored with them), then the best one rendered and
    simplified, all by `until` (`time.monotonic()` seconds), each step in its slot of `plan_finish`;
    the best one's variables named against the spec's `observation_names` (`colmo.names`), its
    comparisons that the code decides within the spec's `observation_bounds` listed (`colmo.bounds`)."""
    best = BestPrograms()
    warming = _warm_up_render() if cfg.finish.render else None
    started, took = time.monotonic(), {}  # seconds each step took, for the closing log line
    plan = plan_finish(cfg, referee, executor.n_workers, max(_left(until), 0.0))
    if plan.reduced:
        log.warning("finishing in %.0f s: %s", max(_left(until), 0.0), plan.describe(cfg))
    top = top_records(store, plan.top)
    heldout = heldout_evaluator(evaluator, cfg.seed, plan.heldout_episodes)
    heldout_until = time.monotonic() + plan.heldout_seconds
    best_took = 0.0  # seconds the best program's held-out score took: what simplifying costs per measurement
    step = time.monotonic()
    for record in top:
        # The best program may use the whole run's time left; the others only the held-out slot.
        limit, scoring = min(_left(until if not best.heldout else heldout_until), heldout.referee_timeout_s), time.monotonic()
        evaluation = heldout_score(executor, heldout, record.skeleton, record.params, timeout_s=limit) if limit > 0 else None
        if evaluation is not None and evaluation.failure == CANCELLED:  # the search is stopping at once
            return best
        # No time was left, or the time limit cut the evaluation short (it did not fail on its own).
        if evaluation is None or (evaluation.failure and limit < heldout.referee_timeout_s and _left(until) <= 0):
            log.warning("no time left for %d held-out scores (search.max_seconds)", len(top) - len(best.heldout))
            break
        best_took = best_took or time.monotonic() - scoring
        score: Optional[float] = None if evaluation.failure else evaluation.score
        store.set_heldout(record.sample, score)
        best.heldout.append({
            "sample": record.sample, "key": record.key, "score": record.score, "heldout_score": score, "heldout_failure": evaluation.failure,
            "episodes": len(heldout.seeds), "episodes_alike": alike(record.returns),
        })
        log.info("sample %d: training score %.2f, held-out %s over %d episodes", record.sample, record.score, _shown(score), len(heldout.seeds))
    if not top:
        return best
    if best.heldout and best.heldout[0]["episodes_alike"]:
        log.warning("every training episode of the best policy returned the same: the task's episodes do not differ, so held-out scores repeat training ones")
    best.misnamed, best.decided = misnamed(top[0].code, observation_names), list(map(str, decided_comparisons(top[0].code, observation_bounds)))
    took["held-out"] = time.monotonic() - step
    if cfg.finish.coverage and best.heldout:
        step = time.monotonic()
        best.coverage = _coverage(executor, evaluator, heldout, top[0], referee, until - plan.render_seconds)
        took["coverage"] = time.monotonic() - step
    if cfg.finish.render:
        # The video shows the best program as found, so it comes before the steps that change it:
        # what its slot does not use (its frames cost less than planned on most tasks) is theirs.
        # The slot counts from the warm-up's end: in a short run the held-out scores are too short to hide it.
        step = time.monotonic()
        warming.join(max(min(plan.render_seconds, _left(until)), 0.0))
        best.media = _render(cfg, executor, heldout, top[0], run_dir, until, plan)
        took["video and plot"] = time.monotonic() - step
    if cfg.finish.robustness:
        # Its time comes out of the simplification's slot, which takes what is left.
        if not best.heldout or not plan.robustness_seconds or _left(until) < plan.robustness_seconds:
            log.warning("no time left for the robustness report of the best policy (search.max_seconds)")
        else:
            step = time.monotonic()
            # More episodes for a stated precision only from the slack: the simplification keeps its planned slot.
            best.robustness = _robustness(cfg, executor, evaluator, top[0], run_dir, until - plan.simplify_seconds - plan.retune_seconds)
            took["robustness"] = time.monotonic() - step
    if cfg.finish.simplify:
        simplify_until = until - plan.retune_seconds
        # Simplifying first measures the best program on the training and the held-out episodes.
        if not best.heldout or simplify_until - time.monotonic() < 2 * best_took:
            log.warning("no time left to simplify the best policy (search.max_seconds)")
        else:
            # What is being scored when it stops still ends: about two such measurements.
            step = time.monotonic()
            hint = coverage.prune(top[0].code, coverage.counts_of(best.coverage)) if best.coverage else None
            best.simplified = _simplify(
                cfg, executor, evaluator, heldout, top[0], run_dir, simplify_until - 2 * best_took, plan.reduced, hint, observation_names,
            )
            took["simplification"] = time.monotonic() - step
    if cfg.finish.retune_budget and best.heldout:
        step = time.monotonic()
        best.retuned = _retune(cfg, executor, evaluator, heldout, top[0], best, run_dir, until, best_took)
        took["re-tuning"] = time.monotonic() - step
    best.readability = readability.report(top[0].code, best.coverage, best.simplified, best.misnamed, best.decided)
    log.info("best policy's readability: %s", readability.describe(best.readability))
    log.info(
        "finish took %.0f s of the %.0f s planned: %s", time.monotonic() - started, plan.seconds,
        ", ".join(f"{name} {seconds:.0f} s" for name, seconds in took.items()),
    )
    return best


def _retune(
    cfg: SearchConfig, executor: Executor, evaluator: Evaluator, heldout: Evaluator, record: SampleRecord, best: BestPrograms, run_dir: Path,
    until: float, heldout_took: float,
) -> dict:
    """The final policy (the simplified one where simplification made it, else the best program)
    with its constants re-tuned by `gfo.method` at `finish.retune_budget` evaluations, as many
    candidates at a time as there are workers, stopped
    early enough before `until` for its held-out score (`heldout_took`: what the best program's
    took), written to `retuned_policy.py`; the summary's `retuned`."""
    simplified = "score" in best.simplified  # a failed simplification says only why
    source = "simplified" if simplified else "best"
    code = best.simplified["code"] if simplified else record.code
    initial_heldout = best.simplified["heldout_score"] if simplified else best.heldout[0]["heldout_score"]
    program = read_program(code, evaluator.allowed_imports)
    if not program.n_params:
        log.info("the %s policy has no constants to re-tune", source)
        return {}
    # Its own constants, the final ones and the held-out score; what is being scored when the
    # tuning stops still ends, and the referee's two scores follow.
    reserve = 3 * heldout_took
    if _left(until) < reserve:
        log.warning("no time left to re-tune the %s policy (search.max_seconds)", source)
        return {}
    # The finish has the workers to itself: a candidate for each (racing runs a candidate's episodes in one request).
    gfo = replace(cfg.gfo, budget=cfg.finish.retune_budget, workers=max(executor.n_workers, 1))
    result = optimize_alone(executor, evaluator, program, gfo, cfg.seed, stop=lambda: _left(until) <= reserve, label="re-tuning")
    if result.failure:
        log.warning("the %s policy not re-tuned: %s", source, result.failure)
        return {"from": source, "failure": result.failure}
    limit = min(max(_left(until), 1.0), heldout.referee_timeout_s)
    scored = heldout_score(executor, heldout, program.skeleton, result.params, timeout_s=limit)
    score = None if scored.failure else finite_or_none(scored.score)
    log.info(
        "the %s policy re-tuned (gfo=%s, %d evaluations%s): training score %.2f -> %.2f, held-out %s -> %s",
        source, gfo.method, result.evaluations, ", cut short at the finish's deadline" if result.cut_short else "",
        result.initial.score, result.score, _shown(initial_heldout), _shown(score),
    )
    header = (
        f"# colmo: the {source} policy of {cfg.task.name} re-tuned (gfo={gfo.method}, {result.evaluations} evaluations): "
        f"training score {result.score:.2f}, held-out {_shown(score)}\n"
    )
    (run_dir / RETUNED_POLICY_FILE).write_text(header + result.code + "\n")
    return {
        "from": source, "gfo": gfo.method, "budget": gfo.budget, "evaluations": result.evaluations, "cut_short": result.cut_short,
        "seconds": round(result.seconds, 3), "n_params": program.n_params, "score_initial": finite_or_none(result.initial.score),
        "heldout_score_initial": initial_heldout, "score": finite_or_none(result.score), "heldout_score": score,
        "heldout_failure": scored.failure, "code": result.code, "file": RETUNED_POLICY_FILE,
    }


def _warm_up_render() -> threading.Thread:
    """`colmo.render.warm_up` in a thread, done while the held-out scores wait on the workers (a
    thread: the imports and the GL probe are this process's)."""
    from colmo.render import warm_up

    thread = threading.Thread(target=warm_up, name="colmo-render-warm-up", daemon=True)
    thread.start()
    return thread


def _coverage(executor: Executor, evaluator: Evaluator, heldout: Evaluator, record: SampleRecord, referee: RefereeCost, until: float) -> dict:
    """What each branch of the best program did over the training and held-out episodes, on the
    fast path (`colmo.coverage`; it takes its seconds from the simplification's slot); the
    summary's `coverage`, {} where the time or the program does not allow it."""
    if not coverage.same_sites(record.code, record.skeleton):
        log.warning("no branch coverage: the best program's code and skeleton differ in their branches")
        return {}
    both = replace(evaluator, seeds=evaluator.seeds + heldout.seeds)
    workers = max(executor.n_workers, 1)
    if _left(until) < referee.seconds(len(both.seeds), workers):
        log.warning("no time left to count the best policy's branches (search.max_seconds)")
        return {}
    scale = max(math.ceil(len(both.seeds) / workers) / len(evaluator.seeds), 1.0)  # a chunk against the calibrated request
    evaluation = branch_counts(executor, both, record.skeleton, record.params, min(evaluator.timeout_s * scale, _left(until)))
    if evaluation.failure or evaluation.coverage is None:
        log.warning("no branch coverage of the best policy: %s", evaluation.failure or "no counts")
        return {}
    log.info("branch coverage of the best policy over %d episodes: %d site(s)", len(both.seeds), len(evaluation.coverage))
    return coverage.summary(record.code, evaluation.coverage, len(both.seeds))


def _robustness(cfg: SearchConfig, executor: Executor, evaluator: Evaluator, record: SampleRecord, run_dir: Path, until: float) -> dict:
    """The best policy's robustness report (`colmo.robustness`) on `finish.robustness_episodes`
    held-out episodes per grid point (with `finish.robustness_precision`, more while they fit
    before `until`, at the pace of those scored), saved into the run directory; the summary's `robustness`."""
    options, started = cfg.finish, time.monotonic()

    def may_add(scored: int, added: int) -> bool:
        return time.monotonic() + (time.monotonic() - started) * added / scored <= until

    report = robustness_of(
        executor, evaluator, record.skeleton, record.params, cfg.seed, options.robustness_episodes,
        options.robustness_magnitudes, options.robustness_delays, options.robustness_precision, options.robustness_max_episodes, may_add,
    )
    if any(point.evaluation.failure == CANCELLED for point in report.points):  # the search is stopping at once
        return {}
    paths = save(report, run_dir, f"{cfg.task.name}: best policy (sample {record.sample})")
    headline = report.headline()
    episodes = len(report.nominal.returns) or options.robustness_episodes
    log.info(
        "best policy under model mismatch (%d held-out episodes per point): nominal %s, worst %s, every factor at 10%% %s; %s",
        episodes, *(_shown(headline[name]) for name in ("robustness_nominal", "robustness_worst", "robustness_all_10")),
        ", ".join(path.name for path in paths),
    )
    for failure in report.failures():
        log.warning("robustness: %s", failure)
    return {**headline, "episodes": episodes, "files": [path.name for path in paths]}


def _shown(score: Optional[float]) -> str:
    return "failed" if score is None else f"{score:.2f}"


def _render(cfg: SearchConfig, executor: Executor, heldout: Evaluator, record: SampleRecord, run_dir: Path, until: float, plan: FinishPlan) -> dict:
    """The video and plot of the best policy, if the run's time left (to `until`) allows the
    smallest, its frames in its slot: `plan.render_seconds` from now, or up to the slots of the
    steps after it, if that is later; the summary's `media`."""
    later = plan.robustness_seconds + plan.simplify_seconds + plan.retune_seconds
    slot_end = min(until, max(time.monotonic() + plan.render_seconds, until - later))
    trace_seconds = plan.render_seconds - plan.video_seconds - RENDER_FIXED_S  # the episode the referee records
    if _left(until) < RENDER_FIXED_S + trace_seconds + VIDEO_MIN_S:
        log.warning("no time left for the video and plot of the best policy (search.max_seconds)")
        return {}
    from colmo.render import render_policy  # matplotlib and the renderer: only when asked for

    width, height = plan.size
    video_seconds = None if math.isinf(until) else max(min(plan.video_seconds, _left(slot_end) - RENDER_FIXED_S - trace_seconds), VIDEO_MIN_S)
    title = f"{cfg.task.name}: best policy (sample {record.sample}, training score {record.score:.1f})"
    media = render_policy(executor, heldout, record.skeleton, record.params, run_dir, title, width=width, height=height, video_seconds=video_seconds)
    found = {name: str(path.relative_to(run_dir)) for name, path in (("plot", media.plot), ("video", media.video)) if path}
    if media.video:
        found["size"] = f"{width}x{height}"
    if media.note:
        found["note"] = media.note
        log.warning("best policy: %s", media.note)
    return found


def _constant_budget(cfg: SearchConfig) -> Optional[int]:
    """The simplifier's budget of constants: `simplify.max_constants`, and a search that kept only
    programs of at most `database.max_constants` keeps its simplified policy within that too."""
    budgets = [b for b in (cfg.simplify.max_constants, cfg.database.max_constants) if b is not None]
    return min(budgets) if budgets else None


def _simplify(
    cfg: SearchConfig, executor: Executor, evaluator: Evaluator, heldout: Evaluator, record: SampleRecord, run_dir: Path, until: float,
    short: bool = False, hint: Optional[Pruned] = None, names: Sequence[str] = (),
) -> dict:
    """The best policy simplified into `simplified_policy.py`; its `to_json()` for the summary.
    `short`: one candidate per worker at a time, so the deadline is checked often; `hint`: the
    program without the branches it never took, tried first; `names`: the spec's observation names."""
    from colmo.simplify import simplify_program

    options = cfg.simplify
    batch_size = options.batch_size or (executor.n_workers if short else None)
    try:
        result = simplify_program(
            executor, evaluator, heldout, record.code, cfg.gfo, options.tolerance, cfg.seed, options.max_rounds,
            batch_size, stop=lambda: _left(until) <= 0, max_seconds=options.max_seconds, hint=hint, names=names,
            max_constants=_constant_budget(cfg),
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
    if result.cut_short:  # the finish's time ran out before a round found nothing more to delete
        more = f"colmo-simplify task={cfg.task.name} seed={cfg.seed} {shell_override('policy_file', run_dir / BEST_POLICY_FILE)}"
        log.warning("the simplification stopped at the finish's deadline after %d round(s); to go on: %s", result.rounds, more)
        header += f"# cut short at the finish's deadline after {result.rounds} round(s); to go on: {more}\n"
    if result.over_budget:
        log.warning("the simplified policy is %s", result.over_budget)
        header += f"# {result.over_budget}\n"
    (run_dir / SIMPLIFIED_POLICY_FILE).write_text(header + result.code + "\n")
    return result.to_json()
