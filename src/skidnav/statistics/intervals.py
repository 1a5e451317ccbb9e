"""Aggregate statistics over seeds: mean, interquartile mean, percentile-bootstrap intervals.

* IQM: the mean of the middle 50 % of the values (25 % trimmed from each end, ``int(0.25 n)``
  values per side), robust to a few outlying seeds (Agarwal et al. (2021), "Deep RL at the edge of
  the statistical precipice").
* Intervals: percentile bootstrap (Efron & Tibshirani (1993) ch. 13) over seeds, with a seeded
  Generator. Two-sample statistics (ratio and difference of means) resample *paired* seeds
  when both samples come from the same seeds (the runner gives all agents the same worlds), and
  each sample independently otherwise.

NaN values (e.g. a metric undefined for a run) are dropped before any statistic; with fewer than
two values left, the interval bounds are NaN.

>>> iqm([1, 2, 3, 4, 5, 6, 7, 100])
4.5
>>> ci = bootstrap_interval([1.0, 2.0, 3.0, 4.0], np.random.default_rng(0))
>>> ci.estimate, ci.low <= 2.5 <= ci.high
(2.5, True)
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np

ArrayLike = Sequence[float] | np.ndarray
Statistic = Callable[[np.ndarray], np.ndarray]
"""Maps resamples, shape (n_resamples, n), to one value per resample, shape (n_resamples,)."""


class Interval(NamedTuple):
    """A point estimate with a confidence interval [low, high]."""

    estimate: float
    low: float
    high: float

    def contains(self, value: float) -> bool:
        """True when ``value`` lies in [low, high]."""
        return bool(self.low <= value <= self.high)

    @property
    def width(self) -> float:
        """high − low."""
        return self.high - self.low


NAN_INTERVAL = Interval(float("nan"), float("nan"), float("nan"))


def _clean(values: ArrayLike) -> np.ndarray:
    array = np.asarray(values, dtype=np.float64).ravel()
    return array[~np.isnan(array)]


def rowwise_mean(samples: np.ndarray) -> np.ndarray:
    """Mean of each row, shape (n_rows,)."""
    return np.asarray(samples.mean(axis=-1))


def rowwise_iqm(samples: np.ndarray) -> np.ndarray:
    """Interquartile mean of each row (25 % trimmed each side), shape (n_rows,)."""
    n = samples.shape[-1]
    cut = int(0.25 * n)
    ordered = np.sort(samples, axis=-1)
    return np.asarray(ordered[..., cut : n - cut].mean(axis=-1))


def iqm(values: ArrayLike) -> float:
    """Interquartile mean of ``values`` (NaN dropped); NaN when empty."""
    array = _clean(values)
    return float(rowwise_iqm(array[None, :])[0]) if array.size else float("nan")


def _percentiles(resampled: np.ndarray, confidence: float) -> tuple[float, float]:
    tail = (1.0 - confidence) / 2.0 * 100.0
    low, high = np.percentile(resampled, [tail, 100.0 - tail])
    return float(low), float(high)


def bootstrap_interval(
    values: ArrayLike,
    rng: np.random.Generator,
    *,
    statistic: Statistic = rowwise_mean,
    n_resamples: int = 2000,
    confidence: float = 0.95,
) -> Interval:
    """Statistic of ``values`` with its percentile-bootstrap interval (NaN dropped).

    Args:
        values: one value per seed, shape (n,).
        rng: draws the resamples.
        statistic: :func:`rowwise_mean` or :func:`rowwise_iqm` (or any row-wise statistic).
        n_resamples: bootstrap resamples.
        confidence: interval level, e.g. 0.95.
    """
    array = _clean(values)
    if array.size == 0:
        return NAN_INTERVAL
    estimate = float(statistic(array[None, :])[0])
    if array.size < 2:  # one value says nothing about its spread
        return Interval(estimate, float("nan"), float("nan"))
    picks = rng.integers(0, array.size, size=(n_resamples, array.size))
    return Interval(estimate, *_percentiles(statistic(array[picks]), confidence))


def _two_sample(
    first: ArrayLike,
    second: ArrayLike,
    combine: Callable[[np.ndarray, np.ndarray], np.ndarray],
    rng: np.random.Generator,
    paired: bool,
    n_resamples: int,
    confidence: float,
) -> Interval:
    a = np.asarray(first, dtype=np.float64).ravel()
    b = np.asarray(second, dtype=np.float64).ravel()
    if paired and a.size == b.size:
        keep = ~(np.isnan(a) | np.isnan(b))
        a, b = a[keep], b[keep]
        if a.size == 0:
            return NAN_INTERVAL
        picks = rng.integers(0, a.size, size=(n_resamples, a.size))
        picks_b = picks
    else:
        a, b = _clean(a), _clean(b)
        if a.size == 0 or b.size == 0:
            return NAN_INTERVAL
        picks = rng.integers(0, a.size, size=(n_resamples, a.size))
        picks_b = rng.integers(0, b.size, size=(n_resamples, b.size))
    estimate = float(combine(a.mean(keepdims=True), b.mean(keepdims=True))[0])
    if min(a.size, b.size) < 2:  # one value per side says nothing about the spread
        return Interval(estimate, float("nan"), float("nan"))
    resampled = combine(a[picks].mean(axis=1), b[picks_b].mean(axis=1))
    resampled = resampled[np.isfinite(resampled)]
    if resampled.size == 0:
        return Interval(estimate, float("nan"), float("nan"))
    return Interval(estimate, *_percentiles(resampled, confidence))


def ratio_interval(
    numerator: ArrayLike,
    denominator: ArrayLike,
    rng: np.random.Generator,
    *,
    paired: bool = True,
    n_resamples: int = 2000,
    confidence: float = 0.95,
) -> Interval:
    """mean(numerator) / mean(denominator) with a bootstrap interval.

    Used for speed-ups: mean convergence episode of the baseline over that of an agent.
    Resamples whose denominator mean is 0 are dropped.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        return _two_sample(numerator, denominator, np.divide, rng, paired, n_resamples, confidence)


def difference_interval(
    first: ArrayLike,
    second: ArrayLike,
    rng: np.random.Generator,
    *,
    paired: bool = True,
    n_resamples: int = 2000,
    confidence: float = 0.95,
) -> Interval:
    """mean(first) − mean(second) with a bootstrap interval.

    "No significant difference" at the chosen level means the interval contains 0; its width
    says how small a difference the data could have detected.
    """
    return _two_sample(first, second, np.subtract, rng, paired, n_resamples, confidence)


def curve_band(
    curves: np.ndarray,
    rng: np.random.Generator,
    *,
    n_resamples: int = 1000,
    confidence: float = 0.95,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-episode mean over runs with a bootstrap band (runs resampled jointly).

    Args:
        curves: shape (n_runs, n_episodes), NaN-free.

    Returns:
        (mean, low, high), each shape (n_episodes,).
    """
    curves = np.asarray(curves, dtype=np.float64)
    n_runs = curves.shape[0]
    picks = rng.integers(0, n_runs, size=(n_resamples, n_runs))
    # Each resample's mean is a weighted mean of the runs, weights = how often a run was drawn.
    rows = np.repeat(np.arange(n_resamples), n_runs)
    counts = np.zeros((n_resamples, n_runs))
    np.add.at(counts, (rows, picks.ravel()), 1.0)
    means = counts @ curves / n_runs
    tail = (1.0 - confidence) / 2.0 * 100.0
    low, high = np.percentile(means, [tail, 100.0 - tail], axis=0)
    return curves.mean(axis=0), low, high
