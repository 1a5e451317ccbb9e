"""``mppi-kinematic`` for a robot run: a new one for the run's world from ``[agents.
mppi-kinematic]``, and the warm-up that compiles its kernels before the robot moves
(:mod:`.mppi_loop` runs it)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from skidnav.agents.mpc.agent import AGENT_NAME, MPPIKinematicAgent
from skidnav.agents.mpc.config import MPPIConfig
from skidnav.envs.navigation import with_control_period
from skidnav.envs.step_info import step_info
from skidnav.errors import UserError, first_line
from skidnav.robot.params import RobotParams
from skidnav.sim.features import PoseFeatures
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap

LIDAR_KEYS = {"lidar_rays": 8, "lidar_range": 0.3}
"""Keys of ``[agents.mppi-kinematic]`` that are not the agent's config: the layout of the laser
readings it observes (rays over a full turn, range limit [m]), with their defaults (the env's)."""
WARM_UP_ROWS = 60
"""Kinematic log rows the warm-up feeds: more than a refit needs (``kinematic_refit_every``'s
default, 50)."""


def new_mppi_agent(
    table: Mapping[str, Any],
    robot: RobotParams,
    grid: Discretization,
    action_duration: float,
    grid_map: GridMap,
    rng: np.random.Generator,
) -> MPPIKinematicAgent:
    """A new agent for the run's world: the nominal ``robot`` timed for actions of
    ``action_duration`` [s] (``[run] period × substeps``), ``grid``, the goal of ``grid_map``,
    the hyperparameters and laser layout of ``table`` (``[agents.mppi-kinematic]``), drawing
    from ``rng``; UserError (one line naming the agent) for values it cannot take, such as
    ``kinematic_model = "true"`` (a robot offers no true model)."""
    values = dict(table)
    layout = {key: values.pop(key, default) for key, default in LIDAR_KEYS.items()}
    try:
        timed = with_control_period(robot, action_duration)
        config = MPPIConfig.from_mapping(values)
        return MPPIKinematicAgent(timed, grid, grid_map.goal, config, rng, **layout)
    except (ValueError, TypeError) as error:
        raise UserError(f"agent {AGENT_NAME!r}: {first_line(error)}") from None


def warm_up_mppi(agent: MPPIKinematicAgent, grid_map: GridMap) -> None:
    """Compile every kernel ``agent`` calls on the robot before it moves: a throwaway copy of it
    (same config, geometry, goal and laser layout) plans at the map's start, learns two steps
    (a collision among them) with enough log rows for a refit, and recomputes its map.
    Compilation holds the GIL, which would starve the driver's reader and trip the watchdog."""
    robot, grid = agent.robot, agent.discretization
    copy = MPPIKinematicAgent(
        robot, grid, agent.goal, agent.config, np.random.default_rng(0),
        lidar_rays=agent.lidar_rays, lidar_range=agent.lidar_range,
    )  # fmt: skip
    features = PoseFeatures(grid_map, grid, agent.lidar_rays, agent.lidar_range)
    x, y = grid.cell_centre(*grid_map.start)
    observation = features(np.array([x, y, 0.0]))
    region = grid.region(x, y)
    speed = robot.wheel_speed
    noise = np.random.default_rng(0).normal(size=(WARM_UP_ROWS, 5))  # a fit of full rank
    rows = np.column_stack([np.full(WARM_UP_ROWS, region), speed * (1.0 + 0.2 * noise[:, :2]),
                            0.02 + 0.01 * noise[:, 2:]])  # fmt: skip
    for collided in (False, True):
        command = copy.act_on(observation, copy.planning_view())
        info = step_info((x, y, 0.0), (0, 0, 0), collided, (speed, speed), region, rows)
        copy.observe(observation, command, -1.0, observation, False, False, info)
    copy.end_episode()
