"""Racing (`gfo.racing`): stopping a GFO candidate early once it very likely cannot beat the
incumbent. A `Race` travels inside an `EvalRequest`, so the rule runs where the episodes run
(`colmo.rollout`, `colmo.sandbox.referee`); `colmo.optimize.tune` builds it from the incumbent.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional, Sequence

# One-sided 90 % quantiles of Student's t with 1, 2, ..., 30 degrees of freedom; past 30 the
# last one, which errs (by under 3 %) on the side of running a candidate on.
_T90 = (
    3.078, 1.886, 1.638, 1.533, 1.476, 1.440, 1.415, 1.397, 1.383, 1.372, 1.363, 1.356, 1.350, 1.345, 1.341,
    1.337, 1.333, 1.330, 1.328, 1.325, 1.323, 1.321, 1.319, 1.318, 1.316, 1.315, 1.314, 1.313, 1.311, 1.310,
)
# Racing waits while the incumbent's returns spread over more than this fraction of its largest
# absolute return (episodes it fails next to episodes it does well: `Race`).
_UNEVEN = 0.8


@dataclass(frozen=True)
class Race:
    """Racing (`gfo.racing`): a candidate's episodes run in order, and it gives up once it very
    likely cannot beat the incumbent by more than a negligible margin over all the episodes.
    `incumbent` holds the incumbent's returns on the same seeds, in the same order.

    The rule is a paired test. Common random numbers (every candidate gets the same seeds, so
    the same initial states) pair each episode of the candidate with the incumbent's, and the
    differences `d_i = candidate_i - incumbent_i` vary far less than the returns themselves.
    After `k` of the `n` episodes, with `mean` and `sd` those of `d_1 .. d_k`, the candidate
    gives up when

        mean + t(k - 1) * sd / sqrt(k) * sqrt(1 - k / n)  <  margin * mean(|incumbent_1 .. incumbent_k|)

    The left side is a 90 % upper confidence bound (`t`: Student's one-sided 90 % quantile) on
    the candidate's mean over all `n` episodes minus the incumbent's; the last factor is the
    finite-population correction: what is estimated is the mean over these `n` seeds, `k` of
    which are known exactly. The right side is the smallest improvement worth finishing a
    candidate for: `margin` (a fraction) of the incumbent's typical return, so that the near
    ties a converged (1+1)-ES keeps proposing stop early too. Racing needs two episodes (a
    spread) and at least `min_episodes`, and never stops a candidate at its last episode:
    a candidate that runs them all is a full evaluation.

    The test assumes the first episodes' differences tell about the others'. They do not
    while the incumbent itself fails some episodes it does well on others (a ball-in-cup
    policy that misses some catches, a pendulum policy that swings up from some initial
    states only): a candidate that trails on the first episodes may succeed where the
    incumbent fails, later. So racing waits while the incumbent's returns spread over more
    than `_UNEVEN` (80 %) of its largest absolute return.
    """

    incumbent: tuple[float, ...]
    min_episodes: int
    margin: float

    def gives_up(self, returns: Sequence[float]) -> bool:
        """Whether the candidate, after its first `len(returns)` episodes, stops (the rule above)."""
        k, n = len(returns), len(self.incumbent)
        if k < max(self.min_episodes, 2) or k >= n or self.uneven:
            return False
        differences = [r - i for r, i in zip(returns, self.incumbent)]
        mean = sum(differences) / k
        sd = math.sqrt(sum((d - mean) ** 2 for d in differences) / (k - 1))
        bound = mean + _T90[min(k - 1, len(_T90)) - 1] * sd / math.sqrt(k) * math.sqrt(1 - k / n)
        return bound < self.margin * sum(abs(i) for i in self.incumbent[:k]) / k

    @property
    def uneven(self) -> bool:
        """Whether the incumbent fails some episodes it does well on others (racing waits)."""
        return max(self.incumbent) - min(self.incumbent) > _UNEVEN * max(abs(r) for r in self.incumbent)

    def estimate(self, returns: Sequence[float], episodes: Optional[Sequence[int]] = None) -> float:
        """The candidate's estimated mean over all the incumbent's episodes from the returns of
        the episodes it ran (`episodes`: their indices; by default the first `len(returns)`):
        the incumbent's mean plus the mean paired difference. What a method is to be told for
        a raced-out candidate (`colmo.optimize.methods`): unlike the mean of the episodes run,
        it does not depend on how easy those episodes happen to be."""
        episodes = range(len(returns)) if episodes is None else episodes
        paired = [r - self.incumbent[i] for r, i in zip(returns, episodes, strict=True)]
        return sum(self.incumbent) / len(self.incumbent) + sum(paired) / len(paired)
