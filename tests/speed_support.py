"""The speed guards' shared pieces: the benchmark scripts made importable, and the check of a
ratio of two rates measured in the same process against a floor, measured again up to
:data:`ATTEMPTS` times in all so that a moment of load passes and a slowdown does not. A ratio,
never an absolute time: a loaded machine slows both sides alike."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
sys.path.insert(0, str(BENCHMARKS))  # the benchmark scripts import one another by name
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
