"""The speed guards' shared check: a ratio of two rates measured in the same process against a
floor, measured again up to :data:`ATTEMPTS` times in all so that a moment of load passes and a
slowdown does not. A ratio, never an absolute time: a loaded machine slows both sides alike.
The benchmark scripts come from :mod:`tests.benchmark_scripts`."""

from __future__ import annotations

from collections.abc import Callable

import pytest

ATTEMPTS = 3


def assert_ratio_above(measure: Callable[[], tuple[float, float]], floor: float, what: str) -> None:
    """Fail unless ``measure()`` → (rate, the rate it is compared with) gives a ratio of at
    least ``floor`` in one of :data:`ATTEMPTS` measurements; ``what`` names the ratio."""
    measured = []
    for _ in range(ATTEMPTS):
        fast, slow = measure()
        measured.append(fast / slow)
        if fast / slow >= floor:
            return
    pytest.fail(f"{what} only {measured} ×, floor {floor}")
