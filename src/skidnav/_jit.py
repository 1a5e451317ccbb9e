"""The one place numba is configured.

Every compiled hot loop in skidnav is plain Python over NumPy arrays, decorated with :func:`jit`.
With ``NUMBA_DISABLE_JIT=1`` in the environment numba leaves the functions as they are, so the
same code runs interpreted and must give bit-identical results (the test suite checks it).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

import numba

F = TypeVar("F", bound=Callable[..., Any])


def jit(function: F) -> F:
    """Compile ``function`` in nopython mode with an on-disk cache (no fastmath: results must match
    the interpreter bit for bit)."""
    return numba.njit(cache=True, nogil=True)(function)  # type: ignore[return-value]


def jit_disabled() -> bool:
    """True when ``NUMBA_DISABLE_JIT`` is set, i.e. kernels run as plain Python."""
    return bool(getattr(numba.config, "DISABLE_JIT", False))
