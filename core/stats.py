"""Statistics every table of racf uses: a rate's Wilson interval, a median's bootstrap interval,
and how an interval is written.

The floor of racf (it imports nothing of racf's): episodes, sweeps, detector benchmarks,
scorecards and the results pages all state their intervals the same way. Intervals are 95 %
unless asked otherwise; the bootstrap's generator is fixed, so the same values give the same
interval on any machine.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy.stats import binomtest

__all__ = ["wilson_interval", "median_ci", "ci", "num", "rate", "cell", "cell_ci"]


def wilson_interval(successes: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval of ``successes`` out of ``n``; (0, 1) when n = 0."""
    if n < 0 or not 0 <= successes <= max(n, 0):
        raise ValueError(f"need 0 <= successes <= n, got successes={successes}, n={n}")
    if n == 0:
        return 0.0, 1.0
    ci = binomtest(int(successes), int(n)).proportion_ci(confidence_level=confidence, method="wilson")
    return float(ci.low), float(ci.high)


def median_ci(values, confidence: float = 0.95, resamples: int = 2000) -> tuple[float | None, list]:
    """The median and its percentile-bootstrap interval (a fixed generator: same values, same
    interval); (None, [None, None]) without values."""
    values = np.asarray(pd.to_numeric(pd.Series(values), errors="coerce").dropna(), float)
    if not values.size:
        return None, [None, None]
    rng = np.random.default_rng(0)
    medians = np.median(rng.choice(values, (resamples, values.size)), axis=1)
    alpha = (1.0 - confidence) / 2
    return float(np.median(values)), [float(np.quantile(medians, alpha)), float(np.quantile(medians, 1 - alpha))]


def ci(pair, digits: int = 2) -> str:
    """``[lo, hi]``, or nothing where the interval is undefined."""
    return "" if not pair or pair[0] is None else f"[{pair[0]:.{digits}f}, {pair[1]:.{digits}f}]"


def num(value, digits: int = 3) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def rate(value, pair, digits: int = 2) -> str:
    """A value with its interval (``-`` where there is none)."""
    return "-" if value is None else f"{value:.{digits}f} {ci(pair, digits)}".strip()


def cell(value, digits: int = 2) -> str:
    """A number in a sweep's table: ``—`` where it is missing (None or NaN)."""
    return "—" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{value:.{digits}f}"


def cell_ci(pair) -> str:
    """An interval in a sweep's table: ``[lo, hi]``, ``—`` for a missing end."""
    return f"[{cell(pair[0])}, {cell(pair[1])}]"
