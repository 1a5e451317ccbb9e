"""A tiny deterministic arena with pose observations, and agents on it."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

import skidnav  # noqa: F401  (registers the env)
from skidnav.agents.linear.agent import LinearAgent
from skidnav.agents.linear.registry import make_linear_agent
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SlipField
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap, border_walls

SIDE = 0.25
"""Arena side [m]."""


def small_pose_env() -> gym.Env[Any, Any]:
    """A free 9 × 9-cell arena of 0.25 m × 0.25 m without slip (deterministic), observations the
    pose Box (x [m], y [m], heading [rad]); the goal five forward actions away."""
    robot = RobotParams(arena_width=SIDE, arena_height=SIDE)
    grid = Discretization(
        n_x=9, n_y=9, n_headings=10, regions_x=2, regions_y=2, arena_width=SIDE, arena_height=SIDE
    )
    grid_map = GridMap(occupancy=border_walls((9, 9)), start=(2, 2), goal=(3, 6))
    slip = SlipField(
        eta=np.zeros((2, 2)), x_icr=np.full((2, 2), 0.05), drift_phase=np.zeros((2, 2))
    )
    return gym.make(
        "skidnav/SkidSteerNav-v0", grid_map=grid_map, robot=robot, discretization=grid,
        slip_field=slip, max_episode_steps=200, observation="pose",
    )  # fmt: skip


def make(name: str, env: gym.Env[Any, Any], seed: int, **options: Any) -> LinearAgent:
    """Agent ``name`` on ``env``'s observations with α = 0.5 and ``options``."""
    config = {"alpha": 0.5, **options}
    return make_linear_agent(name, env.observation_space, 4, config, np.random.default_rng(seed))  # type: ignore[arg-type]
