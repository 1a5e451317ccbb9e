"""One episode of the classical navigator: the map it builds, the route it plans, the command it
chooses, from the feature observations alone.

Per observation (the features, :mod:`skidnav.sim.features`: pose, goal distance and bearing,
lidar ranges):

1. the goal point from the goal's distance d and bearing β: (x + d cos(ψ + β), y + d sin(ψ + β));
2. the readings into the occupancy grid (:mod:`skidnav.agents.classical.costmap`, step 1);
3. if the occupied cells or the goal's cell changed: inflation and route (steps 2 and 3);
4. the robot's velocity from its last two poses, the dynamic window's commands and the progress
   check (:mod:`skidnav.agents.classical.window`);
5. the command of the local controller (:func:`skidnav.agents.classical.dwa.choose_command`),
   wheel speeds within ± Ω; once the robot is stuck, the recovery's for ``recovery_time``.

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
from skidnav.agents.classical.dwa import Controller, choose_command
from skidnav.agents.classical.window import (
    Odometry,
    ProgressCheck,
    command_samples,
    window_commands,
)
from skidnav.agents.mpc.laser import record_scan
from skidnav.robot.datasheet import Datasheet
from skidnav.robot.params import RobotParams
from skidnav.sim.features import check_lidar
from skidnav.world.discretization import Discretization, cell_of

GOAL_MOVE = 0.01
"""How far [m] the goal point computed from an observation must lie from the route's goal for a
new route: the goal's distance and bearing give it back only to rounding, and a goal on a cell
boundary would otherwise change cells from step to step."""


MOVING = 1e-6
"""A command moves a wheel when its wheel speed exceeds this fraction of the top wheel speed
(the zero yaw rate of the samples comes out of a linear spacing only to rounding)."""


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
        radius, half_track = sheet.wheel_radius, config.half_track or sheet.half_track
        top_yaw = min(config.max_yaw_rate, radius * sheet.wheel_speed / half_track)
        self._wheels = (radius, half_track, sheet.wheel_speed)
        self.samples = command_samples(
            *self._wheels, max_speed, config.reverse_speed, top_yaw, config.speed_samples,
            config.yaw_rate_samples,
        )  # fmt: skip
        """The commands of the whole range (a robot that takes any command at once)."""
        moving = np.abs(self.samples).max(axis=1) > MOVING * sheet.wheel_speed
        self.recovery_samples = np.ascontiguousarray(self.samples[moving])
        """The recovery's commands: those of the whole range that move a wheel."""
        period = robot.action_duration
        acceleration, yaw_acceleration = config.acceleration, config.yaw_acceleration
        self.reach = (
            math.inf if acceleration is None else acceleration * period,
            math.inf if yaw_acceleration is None else yaw_acceleration * period,
        )
        """(a T [m/s], α T [rad/s]): the dynamic window's half widths."""
        self._window = ((-config.reverse_speed, max_speed), top_yaw)
        self.odometry = Odometry(period)
        stuck_periods = round(config.stuck_time / period)
        self.progress = ProgressCheck(
            stuck_periods, config.stuck_speed * max_speed * stuck_periods * period
        )
        self.recovery_periods = max(1, round(config.recovery_time / period))
        steps = max(1, round(config.horizon / config.rollout_step))
        self.controller = Controller(
            radius, half_track, sheet.x_icr, steps, config.horizon / steps,
            length + 2 * padding, width + 2 * padding, max_speed, config.heading_weight,
            config.obstacle_weight, config.speed_weight, config.deceleration, period,
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
        """Steps this episode with no admissible command or stuck (the recovery's choice)."""
        self.stuck = 0
        """Times this episode the progress check found the robot stuck."""
        self._recovering = 0
        """Periods of the running recovery still to go."""
        self.odometry.reset()
        self.progress.reset()

    def start_greedy_rollout(self) -> None:
        """A rollout starts: :meth:`reset` (:class:`~skidnav.agents.greedy.RolloutState`)."""
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
        samples = self._commands(x, y, heading)
        recovering = self._recovering > 0
        if recovering:
            samples = self.recovery_samples  # a behaviour of its own: the whole range
        index, admissible = choose_command(
            x, y, heading, samples, self.occupied, self.cost_map, self.costs, self.grid,
            self.controller, recovering,
        )  # fmt: skip
        self.recoveries += not admissible
        if recovering:
            self._recovering -= 1
            if self._recovering == 0:
                self.progress.reset()  # a new look-back after the recovery
        limit = self.robot.wheel_speed
        left, right = samples[index]
        return float(min(max(left, -limit), limit)), float(min(max(right, -limit), limit))

    def _commands(self, x: float, y: float, heading: float) -> np.ndarray:
        """Step 4 of the module doc: the commands to search (the whole range's for a robot
        that takes any command at once), and a recovery started if the robot is stuck."""
        velocity = self.odometry.update(x, y, heading)
        if self.progress.stuck(x, y) and self._recovering == 0:
            self._recovering = self.recovery_periods
            self.stuck += 1
        if self.reach == (math.inf, math.inf):
            return self.samples
        config = self.config
        return window_commands(
            velocity, self.reach, *self._wheels, *self._window,
            (config.speed_samples, config.yaw_rate_samples),
        )  # fmt: skip

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
