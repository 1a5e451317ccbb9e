"""The speed guard: the key ratios of ``make bench`` (``benchmarks/key_figures.py``), each a
compiled path against its plain-Python or ``SyncVectorEnv`` twin measured in the same process,
checked against floors set well below the ratios measured on the CI machine. A ratio, never an
absolute time: a loaded machine slows both sides alike. A ratio below its floor is measured
again (up to :data:`ATTEMPTS` times in all), so that a moment of load passes and a slowdown
does not."""

from __future__ import annotations

import pytest

from skidnav._jit import jit_disabled
from tests.benchmark_scripts import benchmark
from tests.speed_support import ATTEMPTS

key_figures = benchmark("key_figures")


@pytest.mark.skipif(jit_disabled(), reason="nothing is compiled with NUMBA_DISABLE_JIT=1")
@pytest.mark.parametrize(
    "name", [name for name, figure in key_figures.FIGURES.items() if figure.guarded]
)
def test_a_key_ratio_stays_above_its_floor(name: str) -> None:
    figure = key_figures.FIGURES[name]
    measured = []
    for _ in range(ATTEMPTS):
        compiled, twin = figure.measure(True)
        measured.append(f"{compiled:,.0f} / {twin:,.0f} = {compiled / twin:.1f}×")
        if compiled / twin >= figure.floor:
            return
    pytest.fail(
        f"{figure.compiled} against {figure.twin} ({figure.unit}/s): "
        f"{'; '.join(measured)}: below its floor {figure.floor:g}× in {ATTEMPTS} attempts"
    )
