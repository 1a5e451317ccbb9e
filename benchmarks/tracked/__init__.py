"""The figures airspeed velocity records per commit (``make bench``, ``make bench-compare``):
see ``benchmarks/history.py``. The benchmark scripts of the folder above import one another by
name, so it is put on the path first."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
