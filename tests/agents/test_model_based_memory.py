"""Memory of a dyna-full agent on a 100 × 100 × 36 arena (360,000 states)."""

from __future__ import annotations

import tracemalloc

import gymnasium as gym
import numpy as np

import skidnav.envs  # noqa: F401  (registers the env)
from skidnav.agents.fast_training import train_agent_fast
from skidnav.agents.registry import make_agent
from skidnav.world.discretization import Discretization

LIMIT = 300e6  # bytes


def test_dyna_full_stays_under_300_mb_after_100k_steps() -> None:
    grid = Discretization(n_x=100, n_y=100, n_headings=36)
    env = gym.make(
        "skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=0, discretization=grid,
        max_episode_steps=1000,
    )  # fmt: skip
    tracemalloc.start()
    try:
        agent = make_agent(
            "dyna-full", grid.n_states, 4, {"planning_steps": 5}, np.random.default_rng(0),
            task=env.unwrapped.task,  # type: ignore[attr-defined]
        )  # fmt: skip
        train_agent_fast(agent, env, 1, seed=0)
        while agent.steps < 100_000:
            train_agent_fast(agent, env, 10)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    held = agent.q.nbytes + sum(array.nbytes for array in agent._state_arrays().values())
    assert agent.steps >= 100_000 and agent.model.n_outcomes > 10_000
    assert held < LIMIT and peak < LIMIT, (held, peak)
