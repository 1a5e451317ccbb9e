"""Training speed per agent on the navigation env, three ways, all measured in this run.

Real steps per second (env, ε-greedy and the agent's one learning step; 5 planning updates per
real step for the planning agents) of:

* **fused**: ``train_agent_fast``, whole stretches of episodes in one compiled call;
* **step by step**: ``train_agent`` on the env made by ``gymnasium.make`` (its wrappers
  included), one compiled learning step per real step;
* **plain Python**: ``train_agent`` with ``NUMBA_DISABLE_JIT=1`` (a subprocess): the same code
  interpreted, the baseline of both ratios.

Workload: the 25 × 25 × 20 obstacles arena (world seed 1, rough floor), episodes of at most
:data:`MAX_STEPS` actions; one warm-up episode (compilation) before each timed run; best of
:data:`REPEATS`. The plain-Python runs are shorter (:data:`PLAIN_EPISODES`): rates, not times,
are compared.
"""

from __future__ import annotations

import time
from typing import Any

import gymnasium as gym
import numpy as np
from plain_python import interpreted

import skidnav.envs  # noqa: F401  (registers the env)
from skidnav.agents.tabular.fast_training import train_agent_fast
from skidnav.agents.tabular.registry import AGENT_MODULES, make_agent
from skidnav.agents.training import train_agent

MAX_STEPS = 300
EPISODES = 20
PLAIN_EPISODES = 2
REPEATS = 3


def steps_per_second(name: str, fused: bool, episodes: int) -> float:
    """Real steps/s of one timed run of ``episodes`` after a warm-up episode."""
    env = gym.make("skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=1, slip="rough",
                   max_episode_steps=MAX_STEPS)  # fmt: skip
    task = env.unwrapped.task  # type: ignore[attr-defined]
    classic = ("q-learning", "dyna-q", "dyna-q-plus", "prioritized-sweeping")
    context: dict[str, Any] = {} if name in classic else {"task": task}
    config = {} if name == "q-learning" else {"planning_steps": 5}
    agent = make_agent(
        name, env.observation_space.n, 4, config, np.random.default_rng(0), **context
    )  # type: ignore[attr-defined]
    trainer = train_agent_fast if fused else train_agent
    trainer(agent, env, 1, seed=0)
    start = time.perf_counter()
    log = trainer(agent, env, episodes)
    return float(log.lengths.sum()) / (time.perf_counter() - start)


def best_rate(name: str, fused: bool, episodes: int) -> float:
    """The best of :data:`REPEATS` timings of :func:`steps_per_second`."""
    return max(steps_per_second(name, fused, episodes) for _ in range(REPEATS))


def plain_python_rate(name: str) -> float:
    """:func:`steps_per_second` step by step as plain Python (:func:`plain_python.interpreted`)."""
    return interpreted("bench_training", f"steps_per_second({name!r}, False, {PLAIN_EPISODES})")


def main() -> None:
    print(f"real steps/s on the obstacles arena (episodes of <= {MAX_STEPS} actions), "
          "ratios against plain Python measured in this run:")  # fmt: skip
    for name in AGENT_MODULES:
        plain = plain_python_rate(name)
        fused = best_rate(name, True, EPISODES)
        stepwise = best_rate(name, False, EPISODES // 4)
        print(
            f"  {name:24s} plain {plain:9,.0f}  step by step {stepwise:9,.0f} "
            f"({stepwise / plain:5.1f}x)  fused {fused:10,.0f} ({fused / plain:6.1f}x)",
            flush=True,
        )


if __name__ == "__main__":
    main()
