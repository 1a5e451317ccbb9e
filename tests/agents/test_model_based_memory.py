"""Memory of a dyna-full agent on a 100 × 100 × 36 arena (360,000 states)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

LIMIT = 300e6  # bytes
SRC = Path(__file__).resolve().parents[2] / "src"

# Run in a fresh process: ru_maxrss is the peak resident size of the whole process, so in the test
# process it would also hold whatever earlier tests allocated. The growth is measured from after
# the imports and the compilation (a short run on a 10 × 10 × 10 grid compiles every kernel the
# big run uses); resident size sees numba's allocations, tracemalloc sees only Python's.
_SCRIPT = """
import json, resource, tracemalloc
import gymnasium as gym
import numpy as np
import skidnav.envs
from skidnav.agents.tabular.fast_training import train_agent_fast
from skidnav.agents.tabular.registry import make_agent
from skidnav.world.discretization import Discretization

def run(grid, map_kind, steps):
    env = gym.make("skidnav/SkidSteerNav-v0", map_kind=map_kind, world_seed=0, discretization=grid,
                   max_episode_steps=1000)
    agent = make_agent("dyna-full", grid.n_states, 4, {"planning_steps": 5},
                       np.random.default_rng(0), task=env.unwrapped.task)
    train_agent_fast(agent, env, 1, seed=0)
    while agent.steps < steps:
        train_agent_fast(agent, env, 10)
    return agent

def max_rss():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # kB on Linux

run(Discretization(n_x=10, n_y=10, n_headings=10), "free", 200)
rss_before = max_rss()
tracemalloc.start()
agent = run(Discretization(n_x=100, n_y=100, n_headings=36), "obstacles", 100_000)
_, peak = tracemalloc.get_traced_memory()
tracemalloc.stop()
held = agent.q.nbytes + sum(array.nbytes for array in agent._state_arrays().values())
print(json.dumps({"steps": agent.steps, "outcomes": agent.model.n_outcomes, "held": held,
                  "peak": peak, "rss_growth": max_rss() - rss_before}))
"""


def test_dyna_full_stays_under_300_mb_after_100k_steps() -> None:
    env = dict(os.environ, PYTHONPATH=str(SRC))
    done = subprocess.run(
        [sys.executable, "-c", _SCRIPT], env=env, capture_output=True, text=True, timeout=280
    )
    assert done.returncode == 0, done.stderr[-2000:]
    measured = json.loads(done.stdout.splitlines()[-1])
    assert measured["steps"] >= 100_000 and measured["outcomes"] > 10_000
    assert measured["held"] < LIMIT and measured["peak"] < LIMIT, measured
    assert measured["rss_growth"] < LIMIT, measured
