"""One episode of the classical navigator: the map it builds, the route it plans, the command it
chooses, from the feature observations alone.

Per observation (the features, :mod:`skidnav.sim.features`: pose, goal distance and bearing,
lidar ranges):

1. the goal point from the goal's distance d and bearing β: (x + d cos(ψ + β), y + d sin(ψ + β));
2. the readings into the occupancy grid (:mod:`skidnav.agents.classical.costmap`, step 1);
3. if the occupied cells or the goal's cell changed: inflation and route (steps 2 and 3);
4. the command of the local controller (:func:`skidnav.agents.classical.dwa.choose_command`),
   wheel speeds within ± Ω.

It is a :class:`~skidnav.agents.wheel_policy.WheelSpeedPolicy` with a state (the map): a new
episode starts from an empty map (:meth:`ClassicalNavigator.reset`). Nothing is learned from
one episode to the next.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from skidnav.agents.classical.config import ClassicalConfig
from skidnav.agents.classical.costmap import new_cost_map, replan, route_settings, update_occupancy
from skidnav.agents.classical.dwa import Controller, choose_command, command_samples
from skidnav.agents.mpc.laser import record_scan
from skidnav.robot.datasheet import Datasheet
from skidnav.robot.params import RobotParams
from skidnav.sim.features import check_lidar
from skidnav.world.discretization import Discretization, cell_of

GOAL_MOVE = 0.01
"""How far [m] the goal point computed from an observation must lie from the route's goal for a
new route: the goal's distance and bearing give it back only to rounding, and a goal on a cell
boundary would otherwise change cells from step to step."""


class Laser(NamedTuple):
    """The layout of the observations' lidar readings.

    Attributes:
        rays: k readings per observation. range: their limit [m].
        field_of_view: the sector they span [rad], centred on the heading (2π: a full turn from
            the heading, counter-clockwise).
    """

    rays: int
    range: float
    field_of_view: float = 2.0 * math.pi


def footprint_of(config: ClassicalConfig, robot: RobotParams) -> tuple[float, float]:
    """(length, width) [m] of the footprint the navigator plans for: the config's, else the
    robot's (0 × 0, a point, for a robot without one)."""
    length = config.footprint_length
    width = config.footprint_width
    if length is None:
        length = float(getattr(robot, "footprint_length", 0.0))
    if width is None:
        width = float(getattr(robot, "footprint_width", 0.0))
    return length, width


class ClassicalNavigator:
    """The navigator of one episode (module doc).

    Args:
        config: its settings. robot: the datasheet robot (r, c, Ω, x_ICR, the arena, and the
            footprint unless the config gives one). grid: the cells of its map.
        laser: the observations' lidar layout.
    """

    name = "classical"

    def __init__(
        self, config: ClassicalConfig, robot: RobotParams, grid: Discretization, laser: Laser
    ) -> None:
        check_lidar(laser.rays, laser.range)
        self.config, self.robot, self.laser = config, robot, laser
        self.lidar_rays, self.lidar_range = laser.rays, laser.range
        self.grid = grid.grid_shape()
        sheet = Datasheet.of(robot)
        max_speed = config.max_speed or sheet.forward_speed()
        length, width = footprint_of(config, robot)
        padding = config.footprint_padding
        self.inscribed_radius = 0.5 * min(length, width) + padding
        """r_in [m]: the cells within it of an obstacle are lethal."""
        self.samples = command_samples(
            sheet, max_speed, config.reverse_speed, config.max_yaw_rate, config.speed_samples,
            config.yaw_rate_samples,
        )  # fmt: skip
        steps = max(1, round(config.horizon / config.rollout_step))
        self.controller = Controller(
            sheet.wheel_radius, sheet.half_track, sheet.x_icr, steps, config.horizon / steps,
            length + 2 * padding, width + 2 * padding, max_speed, config.heading_weight,
            config.obstacle_weight, config.speed_weight, config.deceleration,
            robot.action_duration,
        )  # fmt: skip
        self.reset()

    def reset(self) -> None:
        """Forget the map and the route: a new episode."""
        n_x, n_y = self.grid.n_x, self.grid.n_y
        self.ray_ends = np.zeros((n_x, n_y), dtype=np.int64)
        self.ray_crossings = np.zeros((n_x, n_y), dtype=np.int64)
        self.occupied = np.zeros((n_x, n_y), dtype=np.uint8)
        self._no_hits = np.zeros((n_x, n_y), dtype=np.int64)
        self.cost_map = new_cost_map(n_x, n_y)
        self.costs = route_settings(
            (-1, -1), self.grid, self.config.inflation_weight, self.config.lookahead
        )
        self.goal_point = (math.inf, math.inf)
        """The goal (x, y) [m] the route leads to."""
        self.replans = 0
        """Routes planned this episode."""
        self.recoveries = 0
        """Steps this episode with no admissible command (the recovery's choice)."""

    def start_greedy_rollout(self) -> None:
        """A rollout starts: :meth:`reset` (:class:`~skidnav.agents.training.RolloutState`)."""
        self.reset()

    def wheel_speeds(self, observation: np.ndarray) -> tuple[float, float]:
        """(ω_L, ω_R) [rad/s] within ± Ω for a feature observation float64 (7 + k,) (module
        doc); ValueError for another shape or a non-finite pose or goal."""
        values = np.asarray(observation, dtype=np.float64)
        if values.shape != (7 + self.laser.rays,):
            raise ValueError(
                f"expected a feature observation of shape ({7 + self.laser.rays},), got "
                f"{values.shape}"
            )
        if not np.isfinite(values[:7]).all():
            raise ValueError("expected a finite pose, goal distance and bearing")
        x, y = float(values[0]), float(values[1])
        heading = math.atan2(values[3], values[2])
        self._map(x, y, heading, values)
        index, admissible = choose_command(
            x, y, heading, self.samples, self.occupied, self.cost_map, self.costs, self.grid,
            self.controller,
        )  # fmt: skip
        self.recoveries += not admissible
        limit = self.robot.wheel_speed
        left, right = self.samples[index]
        return float(min(max(left, -limit), limit)), float(min(max(right, -limit), limit))

    def _map(self, x: float, y: float, heading: float, values: np.ndarray) -> None:
        """Steps 1–3 of the module doc."""
        distance, direction = values[4], heading + math.atan2(values[6], values[5])
        goal_x, goal_y = x + distance * math.cos(direction), y + distance * math.sin(direction)
        moved = math.hypot(goal_x - self.goal_point[0], goal_y - self.goal_point[1])
        ranges = np.ascontiguousarray(values[7:])
        record_scan(
            x, y, heading, ranges, self.laser.range, self.laser.field_of_view,
            self.config.ray_stride, self.grid, self.ray_ends, self.ray_crossings, self._no_hits,
        )  # fmt: skip
        changed = update_occupancy(self.ray_ends, self.ray_crossings, self.occupied)
        if moved > GOAL_MOVE:  # a new goal (the first one, or a goal that moved)
            self.goal_point = (goal_x, goal_y)
            goal_i, goal_j = cell_of(goal_x, goal_y, self.grid)
            self.costs = self.costs._replace(goal_i=int(goal_i), goal_j=int(goal_j))
        if changed or moved > GOAL_MOVE:
            replan(
                self.occupied, self.grid, self.cost_map, self.costs, self.inscribed_radius,
                self.config.inflation_radius, self.config.cost_scaling,
            )  # fmt: skip
            self.replans += 1
