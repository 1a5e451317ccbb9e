"""The statistics checked against the libraries: Kaplan–Meier against lifelines, the percentile
bootstrap against scipy.stats.bootstrap on the same resamples, the IQM against
scipy.stats.trim_mean (docs/experiments.md, "Statistics", "Checked against the libraries")."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from skidnav.statistics.intervals import (
    bootstrap_interval,
    difference_interval,
    iqm,
    ratio_interval,
    rowwise_iqm,
    rowwise_mean,
)
from skidnav.statistics.survival import HALF, kaplan_meier, km_median, median_interval

lifelines = pytest.importorskip("lifelines")
scipy_stats = pytest.importorskip("scipy.stats")
lifelines_utils = pytest.importorskip("lifelines.utils")

runs = st.lists(st.tuples(st.integers(1, 60), st.booleans()), min_size=1, max_size=40).map(
    lambda pairs: (np.array([t for t, _ in pairs], float), np.array([o for _, o in pairs], float))
)
values = st.lists(
    st.floats(-1e3, 1e3, allow_nan=False, allow_subnormal=False), min_size=2, max_size=30
).map(np.array)
seeds = st.integers(0, 2**32 - 1)


def _lifelines_survival(times: np.ndarray, observed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """lifelines' Kaplan–Meier step function: its timeline and S there, shape (k,) each."""
    fitted = lifelines.KaplanMeierFitter().fit(times, observed)
    frame = fitted.survival_function_
    return frame.index.to_numpy(float), frame.iloc[:, 0].to_numpy(float)


def _lifelines_median(times: np.ndarray, observed: np.ndarray) -> float:
    """The median read from lifelines' curve as ours reads it: the smallest t with S(t) ≤ 0.5,
    within the rounding margin of :data:`HALF` (lifelines' own has none: see the next test)."""
    timeline, survival = _lifelines_survival(times, observed)
    below = np.flatnonzero(survival <= HALF)
    return float(timeline[below[0]]) if below.size else math.inf


@settings(max_examples=80, deadline=None)
@given(runs)
def test_kaplan_meier_curve_equals_lifelines(sample: tuple[np.ndarray, np.ndarray]) -> None:
    times, observed = sample
    event_times, survival = kaplan_meier(times, observed)
    timeline, expected = _lifelines_survival(times, observed)
    # Ours is a step function: S = 1 before the first event, survival[k] on [t_k, t_k+1).
    at = np.searchsorted(event_times, timeline, side="right") - 1
    ours = np.where(at >= 0, survival[np.maximum(at, 0)], 1.0) if event_times.size else 1.0
    np.testing.assert_allclose(ours, expected, rtol=0, atol=1e-12)
    assert km_median(times, observed) == _lifelines_median(times, observed)


def test_median_where_lifelines_rounds_past_one_half() -> None:
    # Six events at 1 … 6: S(3) = 3/6 = 1/2 exactly, so the median is 3 (smallest t with
    # S(t) ≤ 0.5). lifelines computes S(3) as exp(Σ log(1 − d/n)) = 0.5000000000000001 and
    # answers 4; ours has the rounding margin.
    times, observed = np.arange(1.0, 7.0), np.ones(6)
    assert km_median(times, observed) == 3.0
    fitted = lifelines.KaplanMeierFitter().fit(times, observed)
    assert fitted.median_survival_time_ == 4.0


@settings(max_examples=25, deadline=None)
@given(runs, seeds)
def test_median_interval_equals_lifelines_on_the_same_resamples(
    sample: tuple[np.ndarray, np.ndarray], seed: int
) -> None:
    """Ours is a percentile bootstrap of the KM median (not lifelines' band inversion): the
    same computation done with lifelines, resample by resample, gives the same interval."""
    times, observed = sample
    n_resamples = 30
    ours = median_interval(times, observed, np.random.default_rng(seed), n_resamples=n_resamples)
    if times.size < 2:
        assert math.isnan(ours.low) and math.isnan(ours.high)
        return
    # The same draws: indices into the runs sorted by (time, event first), as ours resamples.
    order = np.lexsort((observed == 0, times))
    picks = np.random.default_rng(seed).integers(0, times.size, size=(n_resamples, times.size))
    medians = np.sort([_lifelines_median(times[order][p], observed[order][p]) for p in picks])
    assert ours.low == pytest.approx(_quantile(medians, 0.025), rel=1e-12)
    assert ours.high == pytest.approx(_quantile(medians, 0.975), rel=1e-12)
    assert ours.estimate == _lifelines_median(times, observed)


def _quantile(ordered: np.ndarray, q: float) -> float:
    """Linear-interpolated quantile (NumPy's default) of sorted values that may hold inf."""
    position = q * (ordered.size - 1)
    below = math.floor(position)
    fraction = position - below
    low, high = ordered[below], ordered[min(below + 1, ordered.size - 1)]
    return float(low if fraction == 0 or low == high else low + fraction * (high - low))


def test_median_interval_coverage_and_lifelines_band_inversion() -> None:
    # Exponential convergence episodes (true median 100 ln 2), censored at a horizon of 150,
    # 30 runs: the bootstrap interval covers the true median near its nominal 95 % (measured
    # 0.94; lifelines' Brookmeyer–Crowley log-log interval 0.97 on these data), and both
    # intervals are of the same size.
    rng = np.random.default_rng(11)
    true_median, covered, widths = 100.0 * math.log(2.0), 0, []
    for _ in range(60):
        times = np.minimum(np.ceil(rng.exponential(100.0, size=30)), 150.0)
        observed = (times < 150.0).astype(float)
        ours = median_interval(times, observed, rng, n_resamples=1000)
        fitted = lifelines.KaplanMeierFitter().fit(times, observed)
        low, high = lifelines_utils.median_survival_times(fitted.confidence_interval_).iloc[0]
        covered += ours.contains(true_median)
        if math.isfinite(ours.high) and math.isfinite(high):
            widths.append(ours.width / (high - low))
    assert covered >= 52  # ≥ 87 % of 60
    assert 0.6 < float(np.median(widths)) < 1.4


@settings(max_examples=60, deadline=None)
@given(values, seeds, st.sampled_from(["mean", "iqm"]))
def test_bootstrap_equals_scipy_on_the_same_resamples(
    data: np.ndarray, seed: int, statistic: str
) -> None:
    # scipy draws rng.integers(0, n, (n_resamples, n)) and takes linear percentiles: the same
    # draws as ours from the same seed, so the intervals agree to rounding.
    ours_statistic = rowwise_mean if statistic == "mean" else rowwise_iqm

    def theirs(sample: np.ndarray, axis: int) -> np.ndarray:
        if statistic == "mean":
            return np.asarray(np.mean(sample, axis=axis))
        return np.asarray(scipy_stats.trim_mean(sample, 0.25, axis=axis))

    ours = bootstrap_interval(
        data, np.random.default_rng(seed), statistic=ours_statistic, n_resamples=500
    )
    expected = scipy_stats.bootstrap(
        (data,), theirs, method="percentile", n_resamples=500, rng=np.random.default_rng(seed)
    ).confidence_interval
    scale = max(1.0, float(np.abs(data).max()))
    assert ours.low == pytest.approx(expected.low, rel=1e-12, abs=1e-12 * scale)
    assert ours.high == pytest.approx(expected.high, rel=1e-12, abs=1e-12 * scale)


@settings(max_examples=40, deadline=None)
@given(
    st.integers(2, 20).flatmap(
        lambda n: st.tuples(
            *[st.lists(st.floats(0.5, 1e3), min_size=n, max_size=n).map(np.array)] * 2
        )
    ),
    seeds,
    st.booleans(),
)
def test_two_sample_intervals_equal_scipy(
    pair: tuple[np.ndarray, np.ndarray], seed: int, paired: bool
) -> None:
    first, second = pair
    for ours_function, combine in ((ratio_interval, np.divide), (difference_interval, np.subtract)):
        ours = ours_function(
            first, second, np.random.default_rng(seed), paired=paired, n_resamples=300
        )
        expected = scipy_stats.bootstrap(
            (first, second),
            lambda a, b, axis, combine=combine: combine(a.mean(axis=axis), b.mean(axis=axis)),
            method="percentile",
            paired=paired,
            n_resamples=300,
            rng=np.random.default_rng(seed),
        ).confidence_interval
        assert ours.low == pytest.approx(expected.low, rel=1e-12, abs=1e-9)
        assert ours.high == pytest.approx(expected.high, rel=1e-12, abs=1e-9)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-1e6, 1e6, allow_nan=False), min_size=1, max_size=50).map(np.array))
def test_iqm_equals_scipy_trim_mean(data: np.ndarray) -> None:
    # Both cut int(0.25 n) values from each end (rliable's IQM is this same trim_mean), so for
    # n not a multiple of 4 more than half of the values are kept, each with full weight.
    expected = float(scipy_stats.trim_mean(data, 0.25))
    assert iqm(data) == pytest.approx(expected, rel=1e-12, abs=1e-9)
    rows = np.stack([data, data[::-1] * 2.0])
    np.testing.assert_allclose(
        rowwise_iqm(rows), scipy_stats.trim_mean(rows, 0.25, axis=-1), rtol=1e-12, atol=1e-9
    )


def test_iqm_is_not_the_fractional_interquartile_mean() -> None:
    # n = 10: int(2.5) = 2 values cut each side, the 6 middle values averaged (scipy, rliable,
    # ours); the fractional IQM would weigh the 3rd and 8th values by 1/2 (5 values' worth).
    data = np.array([0, 0, 0, 0, 0, 1, 2, 3, 4, 5], float)
    assert iqm(data) == scipy_stats.trim_mean(data, 0.25) == 1.0
    fractional = (0.5 * 0 + 0 + 0 + 1 + 2 + 0.5 * 3) / 5
    assert fractional == pytest.approx(0.9)
