"""The measured greedy simplification: the static clean-up, then deletions, then re-tuning.

`simplify` owns the algorithm, not the running of programs: programs are scored by an injected
`Scoring` (in colmo, the referee in sandboxed workers, on the task's training and held-out
episodes: `colmo.simplify.sandboxed`) and constants are re-tuned by an injected `Retune` (the
GFO), so this module never executes policy code.

1. The original program and its `remove_dead_code` version are both scored; the clean-up is
   kept only if the scores are the same, which confirms it changed nothing.
2. Round after round, every `deletion_candidates` of the current program (under a constant
   budget, those that do not take it over the budget) is scored and the
   acceptable one that removes the most AST nodes is kept, until none is acceptable (or
   `max_rounds`, or `stop()`). Candidates are scored on the training episodes, largest deletion
   first, in batches of `batch_size` (None: the whole round at once); batching stops once no
   unscored candidate could beat the best acceptable one. Held-out scores are needed only to
   decide between candidates that pass on the training episodes, so only those are scored on
   the held-out episodes, best first, until one is accepted. The choice is the same as if
   every candidate had been scored on every episode.
3. With a constant budget (`max_constants`) the program still holds more tunable constants,
   deletions go on past the tolerance: round after round, the candidate with fewer constants
   that loses the least training score per constant it removes (constants removed beyond the
   budget earn nothing) is kept, until the budget is met or no deletion removes a constant. Its
   losses are what the budget costs; the result says whether the budget was met. From here on
   the rule below is measured against this program's scores, and step 2 goes on from it.
4. `retune` re-tunes the constants of the result; the re-tuned code is kept if its training
   score is higher and its held-out gap passes the rule below.

The acceptance rule
-------------------
Every score is measured: the original program, the cleaned one, the candidates, the re-tuned
code. The reference is the ORIGINAL program's scores, not the current program's, so accepted
losses never compound past the tolerance: every accepted program keeps
    train >= ref.train - allowed,  allowed = tolerance * |ref.train| + noise,
with noise = 1e-9 * max(1, |ref.train|) for floating-point round-off. Relative to |ref.train|,
the rule reads the same for positive and negative scores (-100 may fall to -101 at 1%); a
reference of exactly 0 allows no loss beyond the noise. The held-out gap (train - held-out) may
not grow by more than `allowed` over the original's gap, so a deletion that fits the training
episodes at the expense of the held-out ones is refused; together the two rules keep
held-out >= ref.heldout - 2 * allowed. A failed program scores -inf and is never accepted.
Among acceptable candidates the largest node reduction wins, then the higher training score,
then the first in source order, so a run is a deterministic function of the scores.
"""

from __future__ import annotations

import ast
import logging
import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Optional, Sequence

from colmo import astutil
from colmo.coverage import Pruned
from colmo.names import renamed
from colmo.program import DISPLAY_DIGITS, ProgramSize, instantiate, measure, parametrize, round_significant
from colmo.record import finite_or_none
from colmo.simplify.candidates import Candidate, deletion_candidates
from colmo.simplify.deadcode import remove_dead_code

log = logging.getLogger("colmo.simplify")

ScoreBatch = Callable[[Sequence[str]], list[float]]
"""The mean returns of a batch of program codes, in order (-inf: the program failed); the
programs of a batch are scored in parallel."""
Retune = Callable[[str], str]
"""Returns the code with its constants re-tuned (colmo's GFO)."""


class ProgramFails(ValueError):
    """The original program fails on the training episodes: there is no score to keep."""


@dataclass(frozen=True)
class Scoring:
    """How programs are scored: on the training episodes and on the held-out ones."""

    train: ScoreBatch
    heldout: ScoreBatch


@dataclass(frozen=True)
class Scores:
    """A program's mean return on the training episodes and on the held-out ones (-inf: failed)."""

    train: float
    heldout: float

    @property
    def gap(self) -> float:
        return self.train - self.heldout


@dataclass(frozen=True)
class Step:
    """One accepted simplification and the program it left."""

    description: str
    code: str
    scores: Scores
    size: ProgramSize

    def to_json(self) -> dict[str, Any]:
        return {
            "description": self.description, "score": finite_or_none(self.scores.train),
            "heldout_score": finite_or_none(self.scores.heldout), "size": self.size.nodes,
        }


@dataclass(frozen=True)
class SimplifyResult:
    code_initial: str
    code: str
    scores_initial: Scores
    scores: Scores
    size_initial: ProgramSize
    size: ProgramSize
    steps: tuple[Step, ...]  # accepted steps in order: the static clean-up, deletions, re-tuning
    programs_scored: int  # programs scored on the training episodes, the original included
    heldout_scored: int  # programs also scored on the held-out episodes
    rounds: int  # greedy rounds run (the last found nothing acceptable, unless cut short)
    cut_short: bool  # `stop()` ended the rounds (a deadline, Ctrl-C): more might have gone
    static_pass_confirmed: bool  # False: the cleaned program scored differently, so it was not used
    retuned: bool  # the re-tuned code scored better and was kept
    seconds: float
    max_constants: Optional[int] = None  # the constant budget (None: no budget)

    @property
    def within_budget(self) -> bool:
        """The program holds at most `max_constants` tunable constants (always, without a budget)."""
        return self.max_constants is None or self.size.params <= self.max_constants

    @property
    def over_budget(self) -> Optional[str]:
        """The line a report carries where the budget was missed; None where it was met."""
        return None if self.within_budget else f"over the constant budget: {self.size.params} constants left, at most {self.max_constants} asked"

    def to_json(self) -> dict[str, Any]:
        """The report's fields; sizes are AST node counts; non-finite scores are None (JSON has
        no infinities)."""
        return {
            "score_initial": finite_or_none(self.scores_initial.train),
            "heldout_score_initial": finite_or_none(self.scores_initial.heldout),
            "score": finite_or_none(self.scores.train),
            "heldout_score": finite_or_none(self.scores.heldout),
            "size_initial": self.size_initial.nodes,
            "size": self.size.nodes,
            "lines_initial": self.size_initial.lines,
            "lines": self.size.lines,
            "n_params_initial": self.size_initial.params,
            "n_params": self.size.params,
            "code_initial": self.code_initial,
            "code": self.code,
            "steps": [step.to_json() for step in self.steps],
            "programs_scored": self.programs_scored,
            "heldout_scored": self.heldout_scored,
            "rounds": self.rounds,
            "cut_short": self.cut_short,
            "static_pass_confirmed": self.static_pass_confirmed,
            "retuned": self.retuned,
            "max_constants": self.max_constants,
            "within_budget": self.within_budget,
            "seconds": round(self.seconds, 3),
        }


@dataclass
class _Scorer:
    """Scores programs through the injected `Scoring`, each distinct code once per episode set."""

    scoring: Scoring
    train_scores: dict[str, float] = field(default_factory=dict)
    heldout_scores: dict[str, float] = field(default_factory=dict)

    @staticmethod
    def _scored(codes: Sequence[str], score_batch: ScoreBatch, cache: dict[str, float]) -> list[float]:
        new = list(dict.fromkeys(c for c in codes if c not in cache))
        if new:
            results = score_batch(new)
            if len(results) != len(new):
                raise ValueError(f"the scoring returned {len(results)} scores for {len(new)} programs")
            cache.update(zip(new, results))
        return [cache[c] for c in codes]

    def train(self, codes: Sequence[str]) -> list[float]:
        return self._scored(codes, self.scoring.train, self.train_scores)

    def heldout(self, codes: Sequence[str]) -> list[float]:
        return self._scored(codes, self.scoring.heldout, self.heldout_scores)

    def both(self, codes: Sequence[str]) -> list[Scores]:
        return [Scores(t, h) for t, h in zip(self.train(codes), self.heldout(codes))]


class _Rule:
    """The acceptance rule of the module docstring, against the original program's scores."""

    def __init__(self, reference: Scores, tolerance: float):
        scale = abs(reference.train)
        self.reference = reference
        self.allowed = tolerance * scale + 1e-9 * max(1.0, scale)  # the loss a program may cost, noise included

    def passes_training(self, train: float) -> bool:
        return train >= self.reference.train - self.allowed

    def accepts(self, scores: Scores) -> bool:
        return self.passes_training(scores.train) and scores.gap <= self.reference.gap + self.allowed


def _same_scores(a: Scores, b: Scores) -> bool:
    return all(x == y or abs(x - y) <= 1e-9 * max(1.0, abs(x)) for x, y in ((a.train, b.train), (a.heldout, b.heldout)))


def _same_code(a: str, b: str) -> bool:
    return ast.dump(astutil.parse(a)) == ast.dump(astutil.parse(b))


def simplify(
    code: str,
    scoring: Scoring,
    retune: Optional[Retune] = None,
    tolerance: float = 0.01,
    max_rounds: int = 200,
    batch_size: Optional[int] = None,
    function_name: str = "policy",
    stop: Callable[[], bool] = lambda: False,
    hint: Optional[Pruned] = None,
    names: Sequence[str] = (),
    max_constants: Optional[int] = None,
) -> SimplifyResult:
    """Simplify `code` (module docstring) and report what it cost. `stop()` is asked before each
    round, between a round's batches and before re-tuning; once it says so, the best program so far is the result.
    `max_constants`: the constant budget (step 3 of the module docstring; None: none).
    `hint`: the program without the branches it never took (`colmo.coverage.prune`), known
    before any trial, tried first under the same rule. `names`: the spec's observation names;
    a variable whose name contradicts them is renamed last (`colmo.names.renamed`: nothing to score).
    Raises `ProgramFails` if the original program fails on the training episodes."""
    if not 0 <= tolerance < 1:
        raise ValueError(f"tolerance must be in [0, 1), got {tolerance}")
    if batch_size is not None and batch_size < 1:
        raise ValueError(f"batch_size must be positive, got {batch_size}")
    if max_constants is not None and max_constants < 0:
        raise ValueError(f"max_constants must be >= 0, got {max_constants}")
    start = time.perf_counter()
    scorer = _Scorer(scoring)
    cleaned = remove_dead_code(code, function_name)
    scores_initial, scores_cleaned = scorer.both([code, cleaned])
    if not math.isfinite(scores_initial.train):
        raise ProgramFails("the program fails on the training episodes: there is no score to keep")
    rule = _Rule(scores_initial, tolerance)
    steps: list[Step] = []
    confirmed = _same_scores(scores_initial, scores_cleaned)
    current, scores = code, scores_initial
    if confirmed and not _same_code(cleaned, code):
        current, scores = cleaned, scores_cleaned
        steps.append(Step("removed dead code and folded constants", cleaned, scores, measure(cleaned)))
    if hint is not None and not stop():
        hinted = remove_dead_code(hint.code, function_name)
        hinted_scores = scorer.both([hinted])[0]
        hinted_size = measure(hinted)
        if rule.accepts(hinted_scores) and hinted_size.nodes < measure(current).nodes:
            current, scores = hinted, hinted_scores
            steps.append(Step(hint.description, current, scores, hinted_size))

    current, scores, rounds = _deletion_rounds(current, scores, steps, scorer, rule, max_rounds, batch_size, function_name, stop, max_constants)
    if max_constants is not None and measure(current).params > max_constants:
        current, scores, cuts = _budget_cuts(current, scores, steps, scorer, max_constants, batch_size, function_name, stop)
        rounds += cuts
        if cuts:  # the budget's program is the reference from here on
            rule = _Rule(scores, tolerance)
            current, scores, more = _deletion_rounds(
                current, scores, steps, scorer, rule, max_rounds - rounds, batch_size, function_name, stop, max_constants,
            )
            rounds += more

    cut_short = stop()
    retuned = False
    if retune is not None and not cut_short and parametrize(current, function_name).n_params:
        tuned = retune(current)
        if not _same_code(tuned, current):
            (tuned_train,) = scorer.train([tuned])
            if tuned_train > scores.train:
                tuned_scores = Scores(tuned_train, scorer.heldout([tuned])[0])
                if rule.accepts(tuned_scores):
                    current, scores, retuned = tuned, tuned_scores, True
                    steps.append(Step("re-tuned the constants", current, scores, measure(current)))

    readable = readable_constants(current, function_name)
    if readable != current and not stop():
        readable_scores = scorer.both([readable])[0]
        if rule.accepts(readable_scores):
            current, scores = readable, readable_scores
            steps.append(Step(f"constants written to {DISPLAY_DIGITS} significant digits", current, scores, measure(current)))

    current, renamings = renamed(current, names, function_name=function_name)
    size = measure(current)
    steps += [Step(description, current, scores, size) for description in renamings]

    return SimplifyResult(
        code_initial=code, code=current, scores_initial=scores_initial, scores=scores,
        size_initial=measure(code), size=size, steps=tuple(steps),
        programs_scored=len(scorer.train_scores), heldout_scored=len(scorer.heldout_scores), rounds=rounds, cut_short=cut_short,
        static_pass_confirmed=confirmed, retuned=retuned, seconds=time.perf_counter() - start, max_constants=max_constants,
    )


def readable_constants(code: str, function_name: str = "policy") -> str:
    """`code` with its tunable constants written to `DISPLAY_DIGITS` significant digits (a folded
    `np.pi / 6.512` is `0.4824313042981869` otherwise); the caller scores it before keeping it."""
    program = parametrize(code, function_name)
    if round_significant(program.values) == tuple(program.values):  # already as readable (or none)
        return code
    return instantiate(program.skeleton, program.values, digits=DISPLAY_DIGITS)


def _deletion_rounds(
    current: str, scores: Scores, steps: list[Step], scorer: _Scorer, rule: _Rule, max_rounds: int, batch_size: Optional[int],
    function_name: str, stop: Callable[[], bool], max_constants: Optional[int] = None,
) -> tuple[str, Scores, int]:
    """Step 2 of the module docstring from `current`: the program, its scores and the rounds run;
    each accepted deletion is appended to `steps`. With a constant budget, no deletion takes the
    program over it, or adds a constant to one already over it (`obs[3]` replaced by 0.0 is one more)."""
    rounds = 0
    while rounds < max_rounds and not stop():
        rounds += 1
        candidates = deletion_candidates(current, function_name, stop)
        if max_constants is not None:
            cap = max(max_constants, measure(current).params)
            candidates = [c for c in candidates if measure(c.code).params <= cap]
        choice = _best_deletion(candidates, scorer, rule, batch_size, stop)
        if choice is None:
            log.info("round %d: none of %d deletions is acceptable", rounds, len(candidates))
            break
        candidate, scores = choice
        current = candidate.code
        steps.append(Step(candidate.description, current, scores, measure(current)))
        log.info("round %d: %d nodes, training %.2f, held-out %.2f: %s", rounds, candidate.nodes, scores.train, scores.heldout, candidate.description)
    return current, scores, rounds


def _best_deletion(
    candidates: list[Candidate], scorer: _Scorer, rule: _Rule, batch_size: Optional[int], stop: Callable[[], bool] = lambda: False,
) -> Optional[tuple[Candidate, Scores]]:
    """The acceptable candidate removing the most nodes (then scoring best, then first); once
    `stop()` says so, the best of the batches scored so far (a deadline must not wait for a round)."""
    ranked = sorted(range(len(candidates)), key=lambda i: (candidates[i].nodes, i))
    best: Optional[tuple[tuple[int, float, int], Candidate, Scores]] = None
    step = batch_size or max(1, len(ranked))
    for start in range(0, len(ranked), step):
        if best is not None and candidates[ranked[start]].nodes > best[1].nodes:
            break  # nothing left removes as much as the best acceptable one
        if start and stop():
            break
        chunk = ranked[start : start + step]
        trains = scorer.train([candidates[i].code for i in chunk])
        # Held-out scores only for what passes on the training episodes and could still win.
        contenders = sorted(((-candidates[i].nodes, train, -i) for i, train in zip(chunk, trains) if rule.passes_training(train)), reverse=True)
        for key in contenders:
            if best is not None and key <= best[0]:
                break
            candidate = candidates[-key[2]]
            scores = Scores(key[1], scorer.heldout([candidate.code])[0])
            if rule.accepts(scores):
                best = (key, candidate, scores)
    return None if best is None else (best[1], best[2])


def _budget_cuts(
    current: str, scores: Scores, steps: list[Step], scorer: _Scorer, max_constants: int, batch_size: Optional[int],
    function_name: str, stop: Callable[[], bool],
) -> tuple[str, Scores, int]:
    """Step 3 of the module docstring from `current`: the program, its scores and the cuts made;
    each cut is appended to `steps`."""
    cuts = 0
    while not stop():
        constants = measure(current).params
        choice = _cheapest_constant_cut(deletion_candidates(current, function_name, stop), scorer, scores, constants, max_constants, batch_size, stop)
        if choice is None:
            log.info("no deletion removes a constant; %d constants left", constants)
            break
        candidate, scores = choice
        current, cuts = candidate.code, cuts + 1
        steps.append(Step(f"{candidate.description} (for the constant budget)", current, scores, measure(current)))
        log.info("cut %d: %d constants, training %.2f: %s", cuts, steps[-1].size.params, scores.train, candidate.description)
        if steps[-1].size.params <= max_constants:
            break
    return current, scores, cuts


def _cheapest_constant_cut(
    candidates: list[Candidate], scorer: _Scorer, now: Scores, constants_now: int, max_constants: int, batch_size: Optional[int],
    stop: Callable[[], bool] = lambda: False,
) -> Optional[tuple[Candidate, Scores]]:
    """Of the candidates with fewer tunable constants than `constants_now`, the one losing the
    least training score against `now` per constant removed, counting none removed beyond
    `max_constants` (then the smaller program, then the first); None if no such candidate runs.
    Once `stop()` says so, the best of the batches scored so far."""
    needed = constants_now - max_constants
    cuts = [(i, c, min(needed, constants_now - measure(c.code).params)) for i, c in enumerate(candidates)]
    cuts = [cut for cut in cuts if cut[2] > 0]
    best: Optional[tuple[tuple[float, int, int], Candidate, float]] = None
    step = batch_size or max(1, len(cuts))
    for start in range(0, len(cuts), step):
        if start and stop():
            break
        chunk = cuts[start : start + step]
        for (i, candidate, removed), train in zip(chunk, scorer.train([c.code for _, c, _ in chunk])):
            key = ((now.train - train) / removed, candidate.nodes, i)
            if math.isfinite(train) and (best is None or key < best[0]):
                best = (key, candidate, train)
    if best is None:
        return None
    _, candidate, train = best
    return candidate, Scores(train, scorer.heldout([candidate.code])[0])
