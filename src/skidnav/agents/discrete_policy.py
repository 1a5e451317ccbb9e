"""A saved agent of discrete actions as a frozen wheel-speed policy: how it drives the robot.

An agent that answers one of the robot's discrete actions (``greedy_action(observation)`` → an
int: the linear family, ``dqn``) over the env's ``observation="features"`` vector becomes a
:class:`~skidnav.agents.wheel_policy.WheelSpeedPolicy`: its wheel speeds are those of its greedy
action (:func:`~skidnav.robot.kinematics.commanded_wheel_speeds`, the env's action table), which
the real-time loop holds for one action (``period × substeps``), as the env holds a discrete
action for its ``dt × substeps``.

What the agent observes is read from the observation bounds it saved: 7 + k values bounded as
the feature observation (:func:`~skidnav.sim.features.feature_bounds`) carry k range readings
clipped at the bounds' last value [m]. An agent trained on the ``pose`` (x, y, heading) is
refused: the robot's loop computes the feature observation of the tracked pose, and the pose's
heading is not among the features (only its cosine and sine are).

``world.json`` beside the saved agent (:func:`~skidnav.agents.trained_world.world_beside`)
gives the robot whose top wheel speed [rad/s] the actions meant, and the goal cell and action
duration [s] it was trained for: the policy's ``goal`` and ``control_period``, which the
real-time run checks against its own (:func:`skidnav.realtime.policies.check_policy`). Without
it, the actions are the nominal robot's (:class:`~skidnav.robot.params.RobotParams`, the robot
of every real-time run) and the run checks only the arena the bounds record.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from skidnav.agents.trained_world import world_beside
from skidnav.errors import UserError, shown
from skidnav.robot.kinematics import N_ACTIONS, commanded_wheel_speeds
from skidnav.robot.params import RobotParams
from skidnav.sim.features import POSE_GOAL_NAMES, check_lidar, feature_bounds

POSE_SIZE = 3
"""Values of the env's ``observation="pose"`` (x [m], y [m], heading [rad])."""


class GreedyAgent(Protocol):
    """An agent of discrete actions: its greedy action at an observation."""

    def greedy_action(self, observation: np.ndarray) -> Any:
        """The index of the action of highest value at ``observation``."""
        ...


class DiscreteActionPolicy:
    """A frozen discrete-action agent driving by wheel speeds (module doc; a
    :class:`~skidnav.agents.wheel_policy.WheelSpeedPolicy`).

    Attributes:
        agent: the agent (asked for its greedy action only: it learns nothing here).
        lidar_rays: the k range readings its observations carry.
        lidar_range: their largest reading [m].
        wheel_speed: the top wheel speed [rad/s] of its actions (the robot it learned for).
        arena: (W, H) [m] of the arena its observation bounds record.
        goal: the goal cell (i, j) it was trained for, or None when unknown.
        control_period: the duration of its actions [s], or None when unknown.
    """

    def __init__(
        self,
        agent: GreedyAgent,
        lidar_rays: int,
        lidar_range: float,
        wheel_speed: float,
        arena: tuple[float, float],
        *,
        goal: tuple[int, int] | None = None,
        control_period: float | None = None,
    ) -> None:
        self.agent = agent
        self.lidar_rays, self.lidar_range, self.wheel_speed = lidar_rays, lidar_range, wheel_speed
        self.arena, self.goal, self.control_period = arena, goal, control_period

    def action(self, observation: np.ndarray) -> int:
        """The agent's greedy action at the feature observation float64 (7 + k,); ValueError
        for anything but one of the robot's :data:`~skidnav.robot.kinematics.N_ACTIONS`."""
        action = self.agent.greedy_action(observation)
        if isinstance(action, bool) or not isinstance(action, int | np.integer):
            raise ValueError(f"expected a discrete action, got {shown(action)}")
        if not 0 <= action < N_ACTIONS:
            raise ValueError(f"expected an action in 0..{N_ACTIONS - 1}, got {int(action)}")
        return int(action)

    def wheel_speeds(self, observation: np.ndarray) -> tuple[float, float]:
        """(ω_L, ω_R) [rad/s] of the greedy action at the feature observation float64
        (7 + k,)."""
        left, right = commanded_wheel_speeds(self.action(observation), self.wheel_speed)
        return float(left), float(right)


def feature_lidar(low: np.ndarray, high: np.ndarray) -> tuple[int, float]:
    """(k, lidar range [m]) of the feature observation bounded by ``low`` and ``high``
    (float (7 + k,) each: :func:`~skidnav.sim.features.feature_bounds` of the arena they
    record); ValueError naming what they are otherwise. With no range readings, the range is
    the arena's diagonal (no reading is ever clipped; none is taken)."""
    low, high = np.asarray(low, dtype=np.float64), np.asarray(high, dtype=np.float64)
    if low.shape == (POSE_SIZE,):
        raise ValueError(
            "it observes the pose (x, y, heading), the robot's loop computes the feature "
            'observation only (train it with [env] observation = "features")'
        )
    rays = low.size - len(POSE_GOAL_NAMES)
    if low.ndim != 1 or high.shape != low.shape or rays < 0:
        raise ValueError(f"expected the bounds of the feature observation, got shape {low.shape}")
    arena = (float(high[0]), float(high[1]))
    reach = float(high[-1]) if rays else float(high[4])
    check_lidar(rays, reach)
    expected = feature_bounds(arena, rays, reach)
    if not all(
        np.allclose(a, b, rtol=1e-9, atol=0.0) for a, b in zip((low, high), expected, strict=True)
    ):
        raise ValueError("expected the bounds of the feature observation")
    return rays, reach


def discrete_policy(
    load: Callable[[], GreedyAgent], json_path: Path, name: str,
    bounds: tuple[np.ndarray, np.ndarray], n_actions: int,
) -> DiscreteActionPolicy:  # fmt: skip
    """The frozen policy of the agent saved at ``json_path`` (registry name ``name``), over the
    observation of ``bounds`` (low, high) with ``n_actions`` actions (module doc), the agent
    loaded by ``load()`` once they are checked; UserError in one line naming the file for an
    agent of other actions or another observation than the features (:func:`feature_lidar`),
    CorruptFileError for a damaged ``world.json``."""
    if n_actions != N_ACTIONS:
        raise UserError(f"{json_path}: it takes {n_actions} actions, the robot's are {N_ACTIONS}")
    try:
        rays, reach = feature_lidar(*bounds)
    except ValueError as error:
        raise UserError(f"{json_path}: {error}") from None
    arena = (float(bounds[1][0]), float(bounds[1][1]))
    world = world_beside(json_path, name)
    if world is None:
        return DiscreteActionPolicy(load(), rays, reach, RobotParams().wheel_speed, arena)
    return DiscreteActionPolicy(
        load(), rays, reach, world.robot.wheel_speed, arena,
        goal=world.grid_map.goal, control_period=world.action_duration,
    )  # fmt: skip
