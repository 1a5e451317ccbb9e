"""The benchmark scripts (``benchmarks/``), for the tests that check their numbers or guard their
ratios: the folder goes on ``sys.path`` once, here, since the scripts import one another by
name."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path
from types import ModuleType

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
sys.path.insert(0, str(BENCHMARKS))


def benchmark(name: str) -> ModuleType:
    """The benchmark script ``benchmarks/<name>.py``, imported."""
    return importlib.import_module(name)
