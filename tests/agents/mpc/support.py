"""Worlds and helpers of the mppi-kinematic tests: a small arena with a wall between start and
goal, the simulator's own coefficients (what only a test may hand the agent), and an env that
exposes nothing but the Gymnasium API."""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np

import skidnav  # noqa: F401  (registers the env)
from skidnav.agents.mpc.agent import MPPIKinematicAgent
from skidnav.agents.mpc.config import MPPIConfig
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SlipField
from skidnav.world.discretization import Discretization
from skidnav.world.mapfile import parse_map

WALL_BETWEEN = """skidnav-map 1
width 13
height 11
map
#############
#...........#
#...........#
#.....#.....#
#.....#.....#
#.S...#...G.#
#.....#.....#
#.....#.....#
#...........#
#...........#
#############
"""
"""13 × 11 cells of 5.2 cm × 5.1 cm: start and goal on one row, 42 cm apart, a wall 26 cm
tall between them."""

SAME_START_AND_GOAL = """skidnav-map 1
width 13
height 11
map
#############
#...........#
#.........#.#
#.........#.#
#...........#
#.S.......G.#
#...........#
#...........#
#...........#
#...........#
#############
"""
"""The same start and goal with another wall, far from the start."""


def nav_env(
    text: str = WALL_BETWEEN,
    *,
    slip: str = "thesis",
    max_steps: int = 600,
    discretization: Discretization | None = None,
    world_seed: int = 0,
    observation: str = "pose",
) -> gymnasium.Env[Any, Any]:
    """The continuous navigation env of 0.1-s actions on the map ``text``, pose observations
    (or ``observation="features"``: pose, goal and 8 lidar ranges of at most 0.3 m)."""
    return gymnasium.make(
        "skidnav/SkidSteerNav-v0", grid_map=parse_map(text), slip=slip, world_seed=world_seed,
        action="continuous", observation=observation, control_period=0.1,
        max_episode_steps=max_steps, discretization=discretization,
    )  # fmt: skip


def true_coefficients(slip_field: SlipField, robot: RobotParams) -> np.ndarray:
    """The simulator's ICR coefficients of every slip region, float64 (n_regions, 8), without
    the wheel-speed loss (under 1 % on the thesis floor): only a test may know them."""
    radius = robot.wheel_radius * (
        1.0 if slip_field.wheel_radius_scale is None else slip_field.wheel_radius_scale
    )
    track = robot.half_track * (
        1.0 if slip_field.half_track_scale is None else slip_field.half_track_scale
    )
    radius = np.broadcast_to(radius, slip_field.shape).ravel()
    track = np.broadcast_to(track, slip_field.shape).ravel()
    zeros = np.zeros_like(radius)
    return np.stack(
        [radius / 2, radius / 2, zeros, -radius / (2 * track), radius / (2 * track), zeros,
         -slip_field.x_icr.ravel(), zeros],
        axis=1,
    )  # fmt: skip


class SealedEnv(gymnasium.Wrapper[Any, Any, Any, Any]):
    """An env of which an agent can use only ``reset``, ``step`` and the spaces: ``unwrapped``
    is the wrapper itself, and any other attribute (the map, the task, the slip field, the
    true kinematics) raises."""

    ALLOWED = frozenset({"reset", "step", "action_space", "observation_space", "spec", "close"})

    @property
    def unwrapped(self) -> Any:
        return self

    def __getattribute__(self, name: str) -> Any:
        if name.startswith("_") or name in SealedEnv.ALLOWED or name in ("env", "unwrapped"):
            return super().__getattribute__(name)
        raise AttributeError(f"the agent read env.{name}")


def agent_for(
    env: gymnasium.Env[Any, Any], seed: int = 0, true: bool = False, **options: Any
) -> MPPIKinematicAgent:
    """An agent for ``env`` with ``options`` (a small planner unless given), built from the
    env's robot, discretization and goal only; with ``true``, given the simulator's
    coefficients."""
    nav = env.unwrapped
    settings = {"samples": 64, "horizon": 30, **options}
    coefficients = None
    if true:
        settings["kinematic_model"] = "true"
        coefficients = true_coefficients(nav.slip_field, nav.robot)
    return MPPIKinematicAgent(
        nav.robot, nav.discretization, nav.grid_map.goal, MPPIConfig(**settings),
        np.random.default_rng(seed), true_coefficients=coefficients,
        lidar_rays=nav.features.lidar_rays, lidar_range=nav.features.lidar_range,
    )  # fmt: skip
