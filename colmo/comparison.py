"""What a comparison of two variants over seeds can state: each variant's mean ± sample std,
and the difference of their means with a bootstrap confidence interval (`scipy.stats.bootstrap`,
resampling each variant's seeds on its own). A difference is *significant* only when its
interval leaves out 0; with fewer than two seeds a side there is no interval, and nothing is
called significant. The end-of-sweep table (`colmo.sweep_comparison`) and `colmo-report` both
say it this way, so neither announces a winner whose spread overlaps the other's. `half_width`
is the interval of one mean (a robustness report's points, `colmo.robustness`).
"""

from __future__ import annotations

import statistics
from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np

CONFIDENCE = 0.95
_RESAMPLES = 9999


def mean_std(values: Sequence[float], digits: int = 1) -> str:
    """`mean ± sample std`; the mean alone for one value."""
    if len(values) == 1:
        return f"{values[0]:.{digits}f}"
    return f"{statistics.mean(values):.{digits}f} ± {statistics.stdev(values):.{digits}f}"


def half_width(values: Sequence[float]) -> Optional[float]:
    """Half the `CONFIDENCE` interval of the mean of `values` (Student's t; None for fewer than two)."""
    from scipy.stats import t  # scipy only where an interval is made

    if len(values) < 2:
        return None
    return float(t.ppf((1 + CONFIDENCE) / 2, len(values) - 1) * statistics.stdev(values) / np.sqrt(len(values)))


@dataclass(frozen=True)
class Difference:
    """The mean of `other` less the mean of `baseline`, with its bootstrap interval (None with
    fewer than two seeds a side)."""

    mean: float
    low: Optional[float] = None
    high: Optional[float] = None

    @property
    def significant(self) -> bool:
        """Whether the interval leaves out 0: only then is one variant better."""
        return self.low is not None and (self.low > 0 or self.high < 0)

    def text(self, digits: int = 1) -> str:
        """`+185.3, 95% interval [+34.8, +311.8]`, saying when the interval holds 0 or is missing."""
        mean = f"{self.mean:+.{digits}f}"
        if self.low is None:
            return f"{mean} (no interval: fewer than 2 seeds a side)"
        interval = f"{CONFIDENCE:.0%} interval [{self.low:+.{digits}f}, {self.high:+.{digits}f}]"
        return f"{mean}, {interval}" + ("" if self.significant else ": no significant difference")


def difference(baseline: Sequence[float], other: Sequence[float], seed: int = 0) -> Difference:
    """The difference of means `other - baseline` and its percentile bootstrap interval at
    `CONFIDENCE` (the percentile method: BCa's jackknife is undefined for a handful of equal
    seeds); `seed` makes the interval reproducible."""
    from scipy.stats import bootstrap  # scipy only where a comparison is made

    a, b = np.asarray(baseline, dtype=float), np.asarray(other, dtype=float)
    mean = float(b.mean() - a.mean())
    if len(a) < 2 or len(b) < 2:
        return Difference(mean)
    result = bootstrap(
        (b, a), lambda x, y, axis: x.mean(axis=axis) - y.mean(axis=axis), vectorized=True, paired=False, confidence_level=CONFIDENCE,
        n_resamples=_RESAMPLES, method="percentile", rng=np.random.default_rng(seed),
    )
    interval = result.confidence_interval
    return Difference(mean, float(interval.low), float(interval.high))
