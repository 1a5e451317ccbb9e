"""Session-wide test settings: oracles are cached in a temporary folder, never in the user's;
MuJoCo's GL backend is chosen before any test module imports MuJoCo; Ctrl-C raises
KeyboardInterrupt again after every test."""

from __future__ import annotations

import os
import signal
import tempfile
from collections.abc import Iterator

import pytest

if not os.environ.get("SKIDNAV_CACHE_DIR"):
    os.environ["SKIDNAV_CACHE_DIR"] = tempfile.mkdtemp(prefix="skidnav-test-cache-")

import skidnav.physics  # noqa: F401  (sets MUJOCO_GL before MuJoCo's first import)


@pytest.fixture(autouse=True)
def _ctrl_c_as_a_shell_gives_it() -> Iterator[None]:
    """A test that runs a command in this process may leave SIGINT ignored, and an ignored
    signal is inherited by every child process started later: a CLI a later test starts would
    then not stop on SIGINT (``tests/experiments/test_interrupt.py``)."""
    yield
    if signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        signal.signal(signal.SIGINT, signal.default_int_handler)
