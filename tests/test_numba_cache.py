"""numba's on-disk cache works across processes: a second process loads the compiled fused
training loop from the cache instead of compiling it again."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from skidnav._jit import jit_disabled

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
print(json.dumps({"hits": sum(stats.cache_hits.values()),
                  "misses": sum(stats.cache_misses.values()),
                  "q": float(np.abs(agent.q).sum())}))
"""


def _train_once(cache: Path) -> dict[str, float]:
    environment = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    done = subprocess.run(
        [sys.executable, "-c", TRAIN_ONCE],
        capture_output=True, text=True, timeout=600, env=environment, check=True,
    )  # fmt: skip
    result: dict[str, float] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


@pytest.mark.skipif(jit_disabled(), reason="numba's cache needs the JIT")
def test_a_second_process_loads_the_compiled_loop_from_the_cache(tmp_path: Path) -> None:
    first = _train_once(tmp_path / "cache")
    second = _train_once(tmp_path / "cache")
    assert first["misses"] >= 1 and first["hits"] == 0
    assert second["hits"] >= 1 and second["misses"] == 0
    assert second["q"] == first["q"]
