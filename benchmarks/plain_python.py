"""The plain-Python baseline of every benchmark: a figure of this folder's code measured again
with the JIT disabled (``NUMBA_DISABLE_JIT=1``), in a subprocess, so that the same kernels run
interpreted in the same run as their compiled figures."""

from __future__ import annotations

import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def interpreted(module: str, call: str) -> float:
    """The number printed by ``module.call`` (e.g. ``"steps_per_second(2_000)"``) evaluated
    with the JIT disabled, in a subprocess started in this folder."""
    code = f"import {module}; print({module}.{call})"
    result = subprocess.run(
        [sys.executable, "-c", code], env=dict(os.environ, NUMBA_DISABLE_JIT="1"),
        capture_output=True, text=True, check=True, cwd=HERE,
    )  # fmt: skip
    return float(result.stdout.strip().splitlines()[-1])
