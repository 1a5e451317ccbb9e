"""The speed guard of the lattice values' repair: after wall probabilities change, repairing
the values around the changed cells stays much faster than searching the whole lattice again
(``benchmarks/bench_mppi.py``'s figure, its quick drive)."""

from __future__ import annotations

import pytest

from skidnav._jit import jit_disabled
from tests.benchmark_scripts import benchmark
from tests.speed_support import assert_ratio_above

FLOOR = 10.0  # measured 95–130× on the quick drive (39× on make bench's) on the 2-core machine
"""The guard fails below this ratio of repaired to searched updates per second."""


@pytest.mark.skipif(jit_disabled(), reason="nothing is compiled with NUMBA_DISABLE_JIT=1")
def test_a_repair_of_the_values_stays_faster_than_a_search() -> None:
    """A ratio against the search measured in the same process (tests/speed_support.py)."""
    value_update_rates = benchmark("bench_mppi").value_update_rates
    assert_ratio_above(
        lambda: value_update_rates(True), FLOOR, "the values' repair against a search"
    )
