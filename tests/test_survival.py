"""Survival statistics of convergence episodes: Kaplan–Meier, medians, speed-ups, probability of
improvement (Gehan scoring), performance profiles and their bootstraps, and the two figures."""

from __future__ import annotations

import math
import time

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from skidnav.statistics.survival import (
    SpeedupInterval,
    gehan_scores,
    kaplan_meier,
    km_median,
    median_interval,
    performance_profile,
    probability_of_improvement,
    profile_band,
    speedup_interval,
)

TIMES = [1, 2, 2, 3, 4, 5]
OBSERVED = [1, 1, 0, 1, 0, 1]


def _grouped_km(times: np.ndarray, observed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Textbook form: S = ∏ (1 − d_i / n_i) over distinct event times."""
    event_times = np.unique(times[observed == 1])
    survival, value = [], 1.0
    for t in event_times:
        at_risk = np.sum(times >= t)
        events = np.sum((times == t) & (observed == 1))
        value *= 1.0 - events / at_risk
        survival.append(value)
    return event_times, np.array(survival)


def test_kaplan_meier_by_hand() -> None:
    # t=1: 6 at risk, 1 event -> 5/6; t=2: 5 at risk, 1 event (the censoring at 2 is still at
    # risk) -> 5/6 · 4/5 = 2/3; t=3: 3 at risk -> 2/3 · 2/3 = 4/9; t=4 censored;
    # t=5: 1 at risk -> 0.
    event_times, survival = kaplan_meier(TIMES, OBSERVED)
    assert event_times.tolist() == [1.0, 2.0, 3.0, 5.0]
    assert survival == pytest.approx([5 / 6, 2 / 3, 4 / 9, 0.0])
    assert km_median(TIMES, OBSERVED) == 3.0


def test_kaplan_meier_ties_and_nan() -> None:
    # The NaN run is dropped. Two events and a censoring tied at 2: the censored run is still at
    # risk at 2 (4 at risk, 2 events): 4/5, then 4/5 · 2/4, then 0 at 7.
    event_times, survival = kaplan_meier([1, 2, 2, 2, 7, np.nan], [1, 1, 1, 0, 1, 1])
    assert event_times.tolist() == [1.0, 2.0, 7.0]
    assert survival == pytest.approx([4 / 5, 2 / 5, 0.0])
    with pytest.raises(ValueError, match="same length"):
        kaplan_meier([1, 2], [1])
    with pytest.raises(ValueError, match="0 or 1"):
        kaplan_meier([1, 2], [1, 2])


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.tuples(st.integers(1, 8), st.booleans()), min_size=1, max_size=25),
)
def test_kaplan_meier_and_median_match_textbook_form(runs: list[tuple[int, bool]]) -> None:
    times = np.array([t for t, _ in runs], dtype=float)
    observed = np.array([o for _, o in runs], dtype=float)
    event_times, survival = kaplan_meier(times, observed)
    expected_times, expected = _grouped_km(times, observed)
    assert event_times == pytest.approx(expected_times)
    assert survival == pytest.approx(expected)
    reached = np.nonzero(expected <= 0.5 + 1e-12)[0]
    median = expected_times[reached[0]] if reached.size else math.inf
    assert km_median(times, observed) == median
    grid = np.arange(0, 11)
    index = np.searchsorted(expected_times, grid, side="right") - 1
    padded = np.concatenate([[1.0], expected])  # S = 1 before the first event
    at_grid = padded[index + 1]
    assert performance_profile(times, observed, grid) == pytest.approx(1.0 - at_grid)


def test_median_exactly_half_and_mostly_censored() -> None:
    assert km_median([1, 2, 3, 4], [1, 1, 1, 1]) == 2.0  # S(2) = 3/4 · 2/3 = 0.5 exactly
    assert km_median([4, 10, 10, 10], [1, 0, 0, 0]) == math.inf
    assert math.isnan(km_median([], []))
    interval = median_interval([4, 5, 6, 10, 10, 10, 10], [1, 1, 1, 0, 0, 0, 0], _rng())
    assert interval.estimate == math.inf and interval.high == math.inf
    assert interval.low < math.inf  # some resamples hold enough events to reach 0.5


def test_median_interval_brackets_and_is_deterministic() -> None:
    times = np.random.default_rng(1).integers(5, 60, size=30).astype(float)
    observed = np.ones(30)
    first = median_interval(times, observed, _rng(7))
    assert first == median_interval(times, observed, _rng(7))
    assert first.low <= first.estimate <= first.high < math.inf
    assert first.estimate == km_median(times, observed)


def test_speedup_plain_and_lower_bound() -> None:
    base = np.arange(40.0, 70.0)
    agent = base / 4
    ones = np.ones(30)
    plain = speedup_interval(base, ones, agent, ones, _rng())
    assert isinstance(plain, SpeedupInterval) and plain.bound == ""
    assert plain.estimate == pytest.approx(km_median(base, ones) / km_median(agent, ones))
    assert plain.low <= plain.estimate <= plain.high
    # Baseline censored at 100 in 20 of 30 runs: its median is inf, the largest censoring time
    # (100) stands in, and the speed-up is a lower bound.
    censored = np.where(np.arange(30) < 20, 0.0, 1.0)
    base_censored = np.where(censored == 0, 100.0, base)
    bound = speedup_interval(base_censored, censored, agent, ones, _rng())
    assert math.isinf(km_median(base_censored, censored))
    assert bound.bound == "lower" and bound.high == math.inf  # no upper end
    assert bound.estimate == pytest.approx(100.0 / km_median(agent, ones))
    assert bound.interval.estimate == bound.estimate
    assert bound.words(1).startswith("≥ ") and bound.words(1).endswith("∞)")


def test_speedup_agent_censored_is_an_upper_bound_and_both_censored_unknown() -> None:
    result = speedup_interval([5, 6, 7], [1, 1, 1], [50, 50, 50], [0, 0, 0], _rng())
    assert result.bound == "upper" and result.low == 0.0
    assert result.estimate == pytest.approx(6 / 50)  # at most: the agent converges after 50
    assert result.words(2).startswith("≤ 0.12× (0, ")
    # Both mostly censored: neither "slower" nor "faster", and never 0×.
    both = speedup_interval([50] * 6, [0, 0, 0, 0, 1, 1], [50] * 6, [0, 0, 0, 1, 0, 0], _rng())
    assert both.bound == "unknown" and math.isnan(both.estimate)
    assert both.words() == "unknown (both mostly censored)"


def test_speedup_paired_is_narrower_and_nan_seeds_drop() -> None:
    rng = np.random.default_rng(3)
    base = rng.uniform(50, 150, size=30).round()
    agent = (base / 3 + rng.normal(0, 1, size=30)).round()
    ones = np.ones(30)
    paired = speedup_interval(base, ones, agent, ones, _rng())
    unpaired = speedup_interval(base, ones, agent, ones, _rng(), paired=False)
    assert paired.estimate == unpaired.estimate
    assert paired.high - paired.low < unpaired.high - unpaired.low
    with_nan = speedup_interval([10, np.nan, 30], [1, 1, 1], [5, 5, np.nan], [1, 1, 1], _rng())
    assert with_nan.estimate == 2.0  # only seed 0 is complete on both sides
    assert math.isnan(with_nan.low)


def test_gehan_scores_of_censored_pairs() -> None:
    # Agent event at 3 vs baseline censored at 5: surely earlier. Agent event at 8 vs censored
    # at 5: undeterminable. Both censored: undeterminable. Agent censored at 3 vs baseline event
    # at 2: surely later; vs baseline event at 3: surely later (agent's true time > 3).
    scores = gehan_scores([3, 8, 4, 3], [1, 1, 0, 0], [5, 2, 3], [0, 1, 1])
    assert scores.tolist() == [
        [1.0, 0.0, 0.5],
        [0.5, 0.0, 0.0],
        [0.5, 0.0, 0.0],
        [0.5, 0.0, 0.0],
    ]
    assert gehan_scores([4], [0], [6], [1]).tolist() == [[0.5]]  # censored before the event
    assert gehan_scores([4], [1], [4], [1]).tolist() == [[0.5]]  # tie
    assert gehan_scores([4], [1], [4], [0]).tolist() == [[1.0]]  # baseline censored at 4: > 4


def test_probability_of_improvement() -> None:
    agent = np.arange(1.0, 21.0)
    base = np.arange(30.0, 50.0)
    ones = np.ones(20)
    better = probability_of_improvement(agent, ones, base, ones, _rng())
    assert better.estimate == better.low == better.high == 1.0
    worse = probability_of_improvement(base, ones, agent, ones, _rng())
    assert worse.estimate == 0.0
    same = probability_of_improvement(agent, ones, agent, ones, _rng())
    assert same.estimate == pytest.approx(0.5) and same.low < 0.5 < same.high
    # Agent converged by 20 in every run, baseline censored at 20 in every run: surely better.
    censored = probability_of_improvement(agent, ones, np.full(20, 20.0), np.zeros(20), _rng())
    assert censored.estimate == 1.0
    assert probability_of_improvement(agent, ones, agent, ones, _rng(5)) == (
        probability_of_improvement(agent, ones, agent, ones, _rng(5))
    )


def test_probability_of_improvement_bootstrap_matches_explicit_resampling() -> None:
    rng = np.random.default_rng(11)
    agent, base = rng.integers(1, 30, size=12), rng.integers(5, 40, size=9)
    agent_obs, base_obs = rng.integers(0, 2, size=12), rng.integers(0, 2, size=9)
    scores = gehan_scores(agent, agent_obs, base, base_obs)
    draws = _rng(2)
    picks_agent = draws.integers(0, 12, size=(50, 12))
    picks_base = draws.integers(0, 9, size=(50, 9))
    explicit = [scores[a][:, b].mean() for a, b in zip(picks_agent, picks_base, strict=True)]
    tail = np.percentile(explicit, [2.5, 97.5])
    result = probability_of_improvement(agent, agent_obs, base, base_obs, _rng(2), n_resamples=50)
    assert [result.low, result.high] == pytest.approx(tail)


def test_performance_profile_common_horizon_is_empirical_share() -> None:
    rng = np.random.default_rng(4)
    horizon = 200
    times = rng.integers(1, 400, size=30).astype(float)
    observed = (times <= horizon).astype(float)
    times = np.minimum(times, horizon)
    episodes = np.arange(1, horizon + 1)
    share = performance_profile(times, observed, episodes)
    empirical = ((times[None, :] <= episodes[:, None]) & (observed[None, :] == 1)).mean(axis=1)
    assert share == pytest.approx(empirical)
    low, high = profile_band(times, observed, episodes, _rng(1))
    assert low.shape == high.shape == (horizon,)
    assert np.all(low <= share + 1e-12) and np.all(share <= high + 1e-12)
    again = profile_band(times, observed, episodes, _rng(1))
    assert np.array_equal(low, again[0]) and np.array_equal(high, again[1])


def test_bootstraps_are_fast() -> None:
    rng = np.random.default_rng(8)
    times = rng.integers(1, 300, size=30).astype(float)
    observed = (times < 250).astype(float)
    start = time.perf_counter()
    median_interval(times, observed, _rng())
    speedup_interval(times * 2, observed, times, observed, _rng())
    probability_of_improvement(times, observed, times * 2, observed, _rng())
    profile_band(times, observed, np.arange(1, 301), _rng())
    assert time.perf_counter() - start < 1.0


def test_plots_return_png() -> None:
    from skidnav.experiments.report.plots import performance_profiles, speedup_vs_budget

    episodes = np.arange(1, 101)
    share = np.clip(episodes / 80, 0, 1)
    png = performance_profiles(
        {
            "dyna-q": (episodes, share, share - 0.1, share + 0.1),
            "q": (episodes, share / 2, share / 3, share / 1.5),
        },
        horizon=100,
        title="profiles",
    )
    assert png.startswith(b"\x89PNG")
    rows = pd.DataFrame(
        {
            "algorithm": ["dyna-q"] * 3 + ["dyna-full"] * 3,
            "planning_steps": [0, 5, 50] * 2,
            "speedup": [1.0, 3.0, 6.0, 1.2, 4.0, 9.0],
            "speedup_low": [0.8, 2.0, 4.0, 1.0, 3.0, 7.0],
            "speedup_high": [1.3, 4.0, 8.0, 1.5, 5.0, np.nan],
            "bound": ["", "", "", "", "upper", "lower"],
            "wall_time": [1.0, 2.0, 9.0, 1.5, 3.0, 12.0],
            "wall_time_low": [0.9, 1.8, 8.0, 1.4, 2.7, 11.0],
            "wall_time_high": [1.1, 2.2, 10.0, 1.6, 3.3, 13.0],
        }
    )
    assert speedup_vs_budget(rows).startswith(b"\x89PNG")


def _rng(seed: int = 0) -> np.random.Generator:
    return np.random.default_rng(seed)
