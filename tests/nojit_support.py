"""The no-JIT tests' one runner: a script run in a fresh interpreter with numba's JIT on or off
(``NUMBA_DISABLE_JIT``, read when numba is imported, so never in this process), whose arrays,
saved to an ``.npz`` named by its first argument, are compared bit for bit."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
"""The checkout: its ``src`` (skidnav) and itself (``tests.…`` helpers) are on the script's path."""


def script_arrays(
    script: str, out: Path, *, disable_jit: bool, timeout: float = 600.0
) -> dict[str, np.ndarray]:
    """The arrays ``script`` (Python source run as ``python -c SCRIPT OUT``) saved to ``out``,
    run with the JIT off when ``disable_jit``."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), str(ROOT)])
    env["NUMBA_DISABLE_JIT"] = "1" if disable_jit else "0"
    subprocess.run([sys.executable, "-c", script, str(out)], check=True, env=env, timeout=timeout)
    with np.load(out) as archive:
        return {key: archive[key] for key in archive.files}
