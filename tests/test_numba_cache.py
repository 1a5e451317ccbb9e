"""numba's on-disk cache works across processes: a second process loads the compiled fused
training loop from the cache instead of compiling it again, and a change of any module (a
callee numba's own check would miss) compiles it afresh in a folder of its own."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from skidnav._jit import PACKAGE, cache_folder, jit_disabled, source_fingerprint

TRAIN_ONCE = """
import json
import gymnasium
import numpy as np
import skidnav.envs
from skidnav.agents.tabular import fused_loop
from skidnav.agents.tabular.fast_training import train_agent_fast
from skidnav.agents.tabular.registry import make_agent

env = gymnasium.make("skidnav/SkidSteerNav-v0", map_kind="free", world_seed=1).unwrapped
agent = make_agent("dyna-q", env.observation_space.n, 4, {"planning_steps": 5},
                   np.random.default_rng(0))
log = train_agent_fast(agent, env, 2, max_steps=50, seed=3)
stats = fused_loop.learn_stretch.stats
import os
print(json.dumps({"hits": sum(stats.cache_hits.values()),
                  "misses": sum(stats.cache_misses.values()),
                  "q": float(np.abs(agent.q).sum()),
                  "folder": os.environ["NUMBA_CACHE_DIR"]}))
"""


def _train_once(cache: Path, source: Path | None = None) -> dict[str, Any]:
    environment = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    if source is not None:
        environment["PYTHONPATH"] = str(source)
    done = subprocess.run(
        [sys.executable, "-c", TRAIN_ONCE],
        capture_output=True, text=True, timeout=600, env=environment, check=True,
    )  # fmt: skip
    result: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


@pytest.mark.skipif(jit_disabled(), reason="numba's cache needs the JIT")
def test_a_second_process_loads_the_compiled_loop_from_the_cache_until_a_module_changes(
    tmp_path: Path,
) -> None:
    source = tmp_path / "src"
    shutil.copytree(PACKAGE, source / "skidnav", ignore=shutil.ignore_patterns("__pycache__"))
    first = _train_once(tmp_path / "cache", source)
    second = _train_once(tmp_path / "cache", source)
    assert first["misses"] >= 1 and first["hits"] == 0
    assert second["hits"] >= 1 and second["misses"] == 0
    assert second["q"] == first["q"]
    assert first["folder"] == str(tmp_path / "cache" / source_fingerprint(source / "skidnav"))
    # a callee of the loop, in another file: numba's own check looks at the loop's file only
    callee = source / "skidnav" / "agents" / "tabular" / "planning.py"
    callee.write_text(callee.read_text() + "\n# changed\n")
    third = _train_once(tmp_path / "cache", source)
    assert third["folder"] != first["folder"] and third["misses"] >= 1 and third["hits"] == 0
    assert third["q"] == first["q"]


def test_the_cache_folder_is_named_by_the_sources() -> None:
    fingerprint = source_fingerprint()
    assert len(fingerprint) == 16 and fingerprint == source_fingerprint(PACKAGE)
    home = cache_folder({"XDG_CACHE_HOME": "/c"}, fingerprint)
    assert home == Path("/c/skidnav/numba") / fingerprint
    chosen = cache_folder({"NUMBA_CACHE_DIR": "/n"}, fingerprint)
    assert chosen == Path("/n") / fingerprint
    assert cache_folder({"NUMBA_CACHE_DIR": str(chosen)}, fingerprint) == chosen  # a worker's
