"""Session-wide test settings: oracles are cached in a temporary folder, never in the user's;
MuJoCo's GL backend is chosen before any test module imports MuJoCo."""

from __future__ import annotations

import os
import tempfile

if not os.environ.get("SKIDNAV_CACHE_DIR"):
    os.environ["SKIDNAV_CACHE_DIR"] = tempfile.mkdtemp(prefix="skidnav-test-cache-")

import skidnav.physics  # noqa: F401  (sets MUJOCO_GL before MuJoCo's first import)
