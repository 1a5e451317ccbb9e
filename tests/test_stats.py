"""Statistics: IQM, bootstrap intervals (coverage), ratios, differences, bands."""

from __future__ import annotations

import numpy as np
import pytest

from skidnav.statistics.intervals import (
    bootstrap_interval,
    curve_band,
    difference_interval,
    iqm,
    ratio_interval,
    rowwise_iqm,
)


def test_iqm_of_known_data() -> None:
    # 8 values: int(0.25 * 8) = 2 trimmed each side of -50, 1, 2, 3, 4, 5, 6, 100 -> 2, 3, 4, 5.
    assert iqm([100, 1, 2, 3, 4, 5, 6, -50]) == pytest.approx(3.5)
    assert iqm([1, 2, 3, 4]) == pytest.approx(2.5)
    assert iqm([7.0]) == 7.0
    assert np.isnan(iqm([]))
    assert iqm([1.0, np.nan, 3.0]) == pytest.approx(2.0)


def test_rowwise_iqm_matches_scalar() -> None:
    rng = np.random.default_rng(1)
    rows = rng.normal(size=(5, 13))
    expected = [iqm(row) for row in rows]
    assert rowwise_iqm(rows) == pytest.approx(expected)


def test_bootstrap_interval_covers_true_mean_at_nominal_rate() -> None:
    rng = np.random.default_rng(2024)
    trials, hits = 300, 0
    for _ in range(trials):
        sample = rng.exponential(2.0, size=40)  # skewed, true mean 2
        interval = bootstrap_interval(sample, rng, n_resamples=500, confidence=0.95)
        assert interval.low <= interval.estimate <= interval.high
        hits += interval.contains(2.0)
    # Percentile bootstrap under-covers slightly for small skewed samples; nominal 0.95.
    assert 0.88 <= hits / trials <= 0.99


def test_bootstrap_interval_is_seeded_and_narrows_with_more_data() -> None:
    values = np.random.default_rng(0).normal(size=200)
    first = bootstrap_interval(values, np.random.default_rng(5))
    again = bootstrap_interval(values, np.random.default_rng(5))
    assert first == again
    small = bootstrap_interval(values[:20], np.random.default_rng(5))
    assert first.width < small.width


def test_ratio_interval_paired_and_unpaired() -> None:
    rng = np.random.default_rng(3)
    base = rng.uniform(50, 150, size=30)
    fast = base / 4 + rng.normal(0, 1, size=30)
    paired = ratio_interval(base, fast, np.random.default_rng(0))
    assert paired.contains(4.0) and paired.low > 3.0
    unpaired = ratio_interval(base, fast, np.random.default_rng(0), paired=False)
    assert unpaired.estimate == pytest.approx(paired.estimate)
    assert unpaired.width > paired.width  # pairing removes the shared per-seed variation


def test_difference_interval_contains_zero_only_without_effect() -> None:
    rng = np.random.default_rng(4)
    a = rng.normal(20, 2, size=30)
    same = a + rng.normal(0, 0.5, size=30)
    shifted = a + 3.0
    assert difference_interval(same, a, np.random.default_rng(1)).contains(0.0)
    shift = difference_interval(shifted, a, np.random.default_rng(1))
    assert not shift.contains(0.0) and shift.estimate == pytest.approx(3.0)


def test_nan_handling() -> None:
    assert np.isnan(bootstrap_interval([np.nan], np.random.default_rng(0)).estimate)
    interval = difference_interval([1.0, np.nan, 3.0], [1.0, 2.0, np.nan], np.random.default_rng(0))
    assert interval.estimate == pytest.approx(0.0)  # only the pair (1, 1) is complete


def test_curve_band_brackets_the_mean() -> None:
    rng = np.random.default_rng(6)
    curves = rng.normal(size=(20, 50)) + np.linspace(10, 0, 50)
    mean, low, high = curve_band(curves, np.random.default_rng(0))
    assert mean == pytest.approx(curves.mean(axis=0))
    assert np.all(low <= mean + 1e-12) and np.all(mean <= high + 1e-12)
    assert np.all(high - low < 2.0)
