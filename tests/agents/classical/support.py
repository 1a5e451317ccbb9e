"""Worlds of the classical navigator's tests: the Jackal on a BARN world, and the footprint
collisions of a run against the true map."""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np

import skidnav  # noqa: F401  (registers the env)
from skidnav.sim.footprint import footprint_collides
from skidnav.world.barn import load_barn_world

JACKAL = {"footprint_length": 0.458, "footprint_width": 0.416}
"""The Jackal's footprint [m] (docs/barn.md), handed to the navigator as settings."""


def barn_env(world: int, rays: int = 180, max_steps: int = 300) -> gymnasium.Env[Any, Any]:
    """The Jackal on BARN world ``world``: 0.1-s wheel-speed actions, features with ``rays``
    lidar rays of 10 m, the nominal floor."""
    barn = load_barn_world(world)
    return gymnasium.make(
        "skidnav/SkidSteerNav-v0", grid_map=barn.map.grid, discretization=barn.discretization,
        robot="jackal", control_period=0.1, action="continuous", observation="features",
        lidar_rays=rays, lidar_range=10.0, slip="nominal", max_episode_steps=max_steps,
    )  # fmt: skip


def drive(agent: Any, env: gymnasium.Env[Any, Any], greedy: bool = False) -> tuple[bool, int, int]:
    """One episode of ``agent`` on ``env`` from ``reset(seed=0)``: (reached the goal, actions,
    actions whose end pose's Jackal footprint touches a wall cell's disc of the true map)."""
    truth = env.unwrapped.grid_map.as_uint8()
    grid = env.unwrapped.discretization.grid_shape()
    observation, _ = env.reset(seed=0)
    steps = touching = 0
    terminated = truncated = False
    while not (terminated or truncated):
        action = agent.greedy_action(observation) if greedy else agent.act(observation)
        observation, _, terminated, truncated, _ = env.step(action)
        steps += 1
        heading = float(np.arctan2(observation[3], observation[2]))
        touching += footprint_collides(
            truth, grid, observation[0], observation[1], heading,
            JACKAL["footprint_length"], JACKAL["footprint_width"],
        )  # fmt: skip
    return bool(terminated), steps, touching
