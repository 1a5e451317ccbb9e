"""Numbers for people (:mod:`skidnav.statistics.formatting`): never "nan", "[nan, nan]", "1
episodes" or
a bare 95 % interval over two seeds."""

from __future__ import annotations

import math

import pytest

from skidnav.statistics.formatting import MIN_INTERVAL_SEEDS, interval, plural, readable

NAN = math.nan


@pytest.mark.parametrize(
    ("value", "text"),
    [
        (6819378.33, "6,820,000"),
        (-12345.6, "-12,300"),
        (1234.5, "1,234"),
        (99.94, "99.9"),
        (0.5, "0.5"),
        (0.000123456, "0.000123"),
        (0.0, "0"),
        (NAN, "n/a"),
        (None, "n/a"),
        (math.inf, "∞"),
    ],
)
def test_readable_rounds_to_three_significant_figures(value: float | None, text: str) -> None:
    assert readable(value) == text


def test_an_interval_shares_its_estimate_s_precision_and_never_prints_nan() -> None:
    assert interval(1.0, 0.8, 1.2) == "1.00 [0.80, 1.20]"
    assert interval(0.0, -0.05, 0.31) == "0.000 [-0.050, 0.310]"
    assert interval(6.0, 1.0, math.inf) == "6.00 [1.00, ∞]"
    assert interval(12.0, NAN, NAN) == "12" and interval(NAN, NAN, NAN) == "n/a"
    assert interval(3.14159, 3.0, 3.3, digits=3) == "3.142 [3.000, 3.300]"


def test_too_few_seeds_give_the_estimate_and_a_caveat() -> None:
    assert MIN_INTERVAL_SEEDS == 3
    assert interval(5.0, 4.0, 6.0, seeds=2) == "5 (2 seeds: too few for an interval)"
    assert interval(5.0, 4.0, 6.0, seeds=1) == "5 (1 seed: too few for an interval)"
    assert interval(5.0, 4.0, 6.0, seeds=3) == "5.00 [4.00, 6.00]"


def test_plural_counts_its_noun() -> None:
    assert [plural(n, "episode") for n in (0, 1, 2)] == ["0 episodes", "1 episode", "2 episodes"]
    assert plural(12000, "run") == "12,000 runs"
