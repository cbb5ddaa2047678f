"""Simplifying a task's policy for real: every program scored by the referee in sandboxed
workers, the constants re-tuned by the GFO.

`simplify_program` is what `colmo-simplify` runs and what a search runs on its best policy.
It plugs two things into the greedy algorithm (`colmo.simplify.greedy`):
  * scoring: each program of a batch goes through `colmo.intake.read_program` (the static
    check every program passes before it runs; a refused one scores -inf) and is evaluated by
    the referee (`colmo.sandbox.referee`), the program process only mapping observations to
    actions, on the training episodes or on the held-out ones. A batch is one
    `executor.evaluate` call; when it has fewer programs than there are workers, each program's
    episodes are split over several requests, so every worker is busy;
  * re-tuning: `colmo.optimize.tune.optimize_alone` with the run's GFO settings on the
    training episodes, whose result is the readable (4-digit) code; `gfo.method=none` skips it.

A round's candidates go to the executor `BATCH_PER_WORKER` per worker at a time, largest
deletion first: enough to keep every worker busy, and the greedy search stops a round's
batches once no candidate left can beat the best acceptable one, which on the pendulum winner
of docs/pendulum-10min scores half the candidates that whole rounds do (436 against 877 on
2 workers).
"""

from __future__ import annotations

import math
import time
from typing import TYPE_CHECKING, Callable, Optional, Sequence

from colmo.coverage import Pruned
from colmo.errors import RunError
from colmo.evaluation import REFEREE, Evaluation, Evaluator, Executor
from colmo.intake import Unusable, read_program
from colmo.optimize.methods import tunes_constants
from colmo.optimize.tune import optimize_alone
from colmo.program import ParametricProgram
from colmo.sandbox.check import ForbiddenProgram
from colmo.simplify.greedy import ProgramFails, Retune, Scoring, SimplifyResult, simplify

BATCH_PER_WORKER = 4

if TYPE_CHECKING:
    from colmo.config import GFOConfig


class RefereeScores:
    """A `ScoreBatch`: the referee's mean return of each program on one evaluator's episodes
    (-inf for a refused or failed program, whose reason is kept in `failures`)."""

    def __init__(self, executor: Executor, evaluator: Evaluator):
        self.executor = executor
        self.evaluator = evaluator
        self.failures: dict[str, str] = {}

    def _read(self, code: str) -> Optional[ParametricProgram]:
        try:
            return read_program(code, self.evaluator.allowed_imports)
        except (Unusable, ForbiddenProgram) as error:
            self.failures[code] = f"refused: {error}"
            return None

    def __call__(self, codes: Sequence[str]) -> list[float]:
        programs = {code: program for code in codes if (program := self._read(code)) is not None}
        chunks = self.evaluator.seed_chunks(math.ceil(self.executor.n_workers / max(1, len(programs))))
        parts = len(chunks)
        requests = [
            self.evaluator.request(program.skeleton, program.values, seeds=chunk, mode=REFEREE)
            for program in programs.values()
            for chunk in chunks
        ]
        evaluations = self.executor.evaluate(requests) if requests else []
        scores = {}
        for k, code in enumerate(programs):
            evaluation = Evaluation.joined(evaluations[k * parts : (k + 1) * parts])
            if evaluation.failure or not evaluation.returns:
                self.failures[code] = evaluation.failure or "no episodes"
            scores[code] = evaluation.score
        return [scores.get(code, -math.inf) for code in codes]


def gfo_retune(executor: Executor, evaluator: Evaluator, gfo_cfg: "GFOConfig", seed: int, stop: Callable[[], bool] = lambda: False) -> Retune:
    """A `Retune`: the code with its constants tuned by `gfo_cfg`'s method on `evaluator`'s
    episodes and rounded to 4 digits (`optimize_alone`); the code itself if that failed or
    changed nothing."""

    def retune(code: str) -> str:
        program = read_program(code, evaluator.allowed_imports)
        result = optimize_alone(executor, evaluator, program, gfo_cfg, seed, stop)
        return code if result.failure or result.params == tuple(program.values) else result.code

    return retune


def simplify_program(
    executor: Executor,
    train_evaluator: Evaluator,
    heldout_evaluator: Evaluator,
    code: str,
    gfo_cfg: "GFOConfig",
    tolerance: float = 0.01,
    seed: int = 0,
    max_rounds: int = 200,
    batch_size: Optional[int] = None,
    stop: Callable[[], bool] = lambda: False,
    max_seconds: Optional[float] = None,
    hint: Optional[Pruned] = None,
    names: Sequence[str] = (),
    max_constants: Optional[int] = None,
) -> SimplifyResult:
    """Simplify a policy program of a task: dead code out, constants folded, deletions that cost
    at most `tolerance` of the training score (and do not widen the held-out gap by more), and
    the remaining constants re-tuned (`colmo.simplify.greedy` says exactly what is accepted).

    `train_evaluator` is the task's calibrated evaluator on the training episodes
    (`colmo.heldout.training_evaluator`), `heldout_evaluator` the same on held-out episodes
    (`colmo.heldout.heldout_evaluator`); every score in the result is the referee's. `code` is
    a program as the intake returns it (`colmo.extract.extract_policy`). `batch_size` is the
    number of candidates per executor call (None: `BATCH_PER_WORKER` per worker); `max_rounds`
    `stop()` (a search's deadline) and `max_seconds` (from now) cut the greedy search short,
    keeping the best program so far; `hint` is tried first and variables that contradict the
    spec's observation `names` are renamed last; `max_constants`: a budget of tunable constants met
    by deletions past the tolerance (`colmo.simplify.greedy.simplify`).

    Its callers: the finish of a search, on its best program before the executor closes, with
    `stop` at the finish's deadline (`colmo.finish`), and `colmo-simplify` on a policy file
    (`colmo.simplify.__main__`); `result.to_json()` has what a summary reports and
    `result.code` is the simplified policy.

    Raises RunError if the program fails on the training episodes (nothing to keep)."""
    if max_seconds is not None:
        deadline, deadline_stop = time.monotonic() + max_seconds, stop
        stop = lambda: deadline_stop() or time.monotonic() >= deadline  # noqa: E731
    train = RefereeScores(executor, train_evaluator)
    heldout = RefereeScores(executor, heldout_evaluator)
    retune = gfo_retune(executor, train_evaluator, gfo_cfg, seed, stop) if tunes_constants(gfo_cfg) else None
    batch_size = batch_size or BATCH_PER_WORKER * executor.n_workers
    try:
        return simplify(
            code, Scoring(train, heldout), retune, tolerance, max_rounds, batch_size, stop=stop, hint=hint, names=names, max_constants=max_constants,
        )
    except ProgramFails:
        raise RunError(f"the policy fails on the training episodes: {train.failures.get(code, 'no score')}") from None
