"""Session-wide test settings: oracles are cached in a temporary folder, never in the user's."""

from __future__ import annotations

import os
import tempfile

if not os.environ.get("SKIDNAV_CACHE_DIR"):
    os.environ["SKIDNAV_CACHE_DIR"] = tempfile.mkdtemp(prefix="skidnav-test-cache-")
