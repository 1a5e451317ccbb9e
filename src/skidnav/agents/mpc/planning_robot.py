"""What ``mppi-kinematic``'s planner makes of the robot: the cost map's scalars (the distance and
turn of one control step at the route's top speeds, the weights, the inscribed radius of the
padded footprint), the rollouts' padded robot and the lattice's robots timed for its actions."""

from __future__ import annotations

import dataclasses

from skidnav.agents.mpc.config import MPPIConfig
from skidnav.agents.mpc.costmap import MapCosts
from skidnav.agents.mpc.dynamics import nominal_speeds
from skidnav.envs.navigation import with_control_period
from skidnav.robot.params import KinematicConstants, RobotParams


def map_costs(
    config: MPPIConfig,
    robot: RobotParams,
    goal: tuple[int, int],
    speeds: tuple[float, float] | None = None,
) -> MapCosts:
    """The cost map's scalars: the goal, the config's weights, the distance [m] and turn [rad]
    of one control step at the top speeds ``speeds`` (forward [m/s], turn [rad/s]; None: the
    nominal robot's), and the inscribed radius [m] of the padded footprint (0 for a point
    robot)."""
    speed, yaw_rate = speeds if speeds is not None else nominal_speeds(robot)
    period = robot.action_duration
    planned = padded(robot, config.footprint_padding)
    inscribed = 0.5 * min(planned.footprint_length, planned.footprint_width)
    return MapCosts(
        goal[0], goal[1], speed * period, yaw_rate * period, float(config.collision_cost),
        float(config.blocked_cost), float(config.free_prior), float(config.ray_weight),
        float(config.heading_weight),
        float(config.lookahead), config.cost_to_go == "states", float(inscribed),
    )  # fmt: skip


def padded(robot: RobotParams, padding: float) -> RobotParams:
    """``robot`` with ``padding`` [m] added to each side of its footprint; a point robot
    (footprint 0 × 0) unchanged."""
    if not robot.has_footprint:
        return robot
    return dataclasses.replace(
        robot,
        footprint_length=robot.footprint_length + 2.0 * padding,
        footprint_width=robot.footprint_width + 2.0 * padding,
    )


def lattice_robot(robot: RobotParams, duration: float) -> KinematicConstants:
    """``robot``'s kernel constants timed for a lattice action of ``duration`` [s]; ValueError
    unless it is a whole number ≥ 1 of the robot's sub-steps."""
    try:
        return with_control_period(robot, duration).kernel_constants()
    except ValueError:
        raise ValueError(
            f"expected each lattice duration to be a whole number >= 1 of the robot's "
            f"{robot.dt:g} s sub-steps, got {duration!r}"
        ) from None
