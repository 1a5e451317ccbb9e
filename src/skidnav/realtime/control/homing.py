"""Driving the robot back to the start between episodes: a path-following pose controller.

Path: breadth-first distances over the free cells of the map towards the start cell
(world/grid.py ``cell_distances``); the target is the centre of the cell ``lookahead`` steps
down that distance field from the robot's cell, and finally the start position itself.

The controlled point is the pivot P = (x, y) + x_ICR (cos ψ, sin ψ): the body point that stays
still when a skid-steer robot turns on the spot (its lateral skid v_y = −x_ICR·ω cancels there,
Kozłowski & Pazderski 2004), so turning never undoes progress. Its goal is the start position
shifted by x_ICR along the start heading. x_ICR is one value, or one per coarse region (the
real-time loop passes its online estimates, realtime/control/transition.py ``IcrEstimates``):
a floor that shifts the ICR moves a pivot computed with the nominal value at every turn.

Control law (turn-then-drive, a unicycle go-to-goal controller; see e.g. Siegwart, Nourbakhsh &
Scaramuzza (2011) §3.6): with bearing error e = wrap(atan2(Δy, Δx) − ψ) from P to the target,

- |e| > ``turn_threshold``: turn on the spot, ω_L = −s·ω_max, ω_R = +s·ω_max with s = sign(e);
- otherwise drive: ω_L = ω_max − k·e·ω_max, ω_R = ω_max + k·e·ω_max, clipped to ±ω_max.

Once P is within ``tolerance`` of its goal, the robot turns on the spot to the start heading
(0 rad, aiming at the middle of its heading bin's first half so the discretized start state
matches the env's); it keeps aligning while within 4 × ``tolerance`` (hysteresis against noise).
"""

from __future__ import annotations

import math

import numpy as np

from skidnav.realtime.link.interface import Pose
from skidnav.robot.kinematics import wrap_angle
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap, cell_distances


class HomingController:
    """Wheel commands that bring the robot to the start pose of ``grid_map``.

    Args:
        grid_map: walls and start cell. grid: cell geometry. wheel_speed: ω_max [rad/s].
        tolerance: position tolerance [m]. lookahead: cells ahead on the path.
        x_icr: x_ICR [m], one value or float64 (n_regions,) indexed by the flat coarse region.
    """

    def __init__(
        self,
        grid_map: GridMap,
        grid: Discretization,
        wheel_speed: float,
        tolerance: float = 0.02,
        lookahead: int = 2,
        x_icr: float | np.ndarray = 0.05,
    ) -> None:
        self.grid = grid
        self.wheel_speed = wheel_speed
        self.tolerance = tolerance
        self.lookahead = lookahead
        self.turn_threshold = 0.4
        self.gain = 1.5
        self.heading_target = 0.25 * 2.0 * math.pi / grid.n_headings
        self.heading_tolerance = self.heading_target * 0.8
        self.x_icr = np.broadcast_to(np.asarray(x_icr, dtype=np.float64), (grid.n_regions,))
        start = grid.cell_centre(*grid_map.start)
        offset = self.x_icr[grid.region(*start)]
        heading = self.heading_target
        # the pivot's goal: where it is when the body centre is on the start, at the start heading
        self.start = (start[0] + offset * math.cos(heading), start[1] + offset * math.sin(heading))
        self.start_cell = grid_map.start
        self.distance = cell_distances(grid_map.occupancy, grid_map.start)
        self.aligning = False
        self.reach = 0.6 * min(grid.cell_width, grid.cell_height)
        self._waypoint: tuple[float, float] | None = None
        self.stuck_periods = 40
        self.backup_periods = 8
        self._backing_up = 0
        self._anchor: tuple[float, float] | None = None
        self._since_anchor = 0

    def _target(self, pose: Pose, px: float, py: float) -> tuple[float, float]:
        """Pivot target: the current waypoint until the pivot comes within ``reach`` of it
        (hysteresis: the pivot's cell may flicker at a cell border while turning), then the
        centre of the path cell ``lookahead`` steps ahead, or the pivot's goal once that close."""
        if self._waypoint is not None:
            wx, wy = self._waypoint
            if math.hypot(wx - px, wy - py) > self.reach:
                return self._waypoint
        self._waypoint = self._next_waypoint(pose, px, py)
        return self._waypoint

    def _next_waypoint(self, pose: Pose, px: float, py: float) -> tuple[float, float]:
        """Path cell ahead of the pivot's cell (of the body centre's if the pivot is over a
        wall; the start itself if neither is on the free space connected to it)."""
        cell = self.grid.cell(px, py)
        if self.distance[cell] < 0:
            cell = self.grid.cell(pose.x, pose.y)
        if self.distance[cell] < 0 or self.distance[cell] <= self.lookahead:
            return self.start
        n_x, n_y = self.distance.shape
        for _ in range(self.lookahead):
            i, j = cell
            for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                ni, nj = i + di, j + dj
                inside = 0 <= ni < n_x and 0 <= nj < n_y
                if inside and 0 <= self.distance[ni, nj] < self.distance[i, j]:
                    cell = (ni, nj)
                    break
        return self.grid.cell_centre(*cell)

    def command(self, pose: Pose) -> tuple[float, float] | None:
        """(ω_L, ω_R) [rad/s] for the next control period, or None once home."""
        offset = self.x_icr[self.grid.region(pose.x, pose.y)]
        px = pose.x + offset * math.cos(pose.heading)
        py = pose.y + offset * math.sin(pose.heading)
        away = math.hypot(px - self.start[0], py - self.start[1])
        # hysteresis: turning on the spot slides a skid-steer robot sideways (x_ICR ≠ 0)
        self.aligning = away <= (4.0 if self.aligning else 1.0) * self.tolerance
        if self.aligning:
            return self._align(pose)
        if self._backing_up > 0:
            self._backing_up -= 1
            return -self.wheel_speed, -self.wheel_speed
        if self._stuck(px, py):
            self._backing_up = self.backup_periods
            self._waypoint = None
            return -self.wheel_speed, -self.wheel_speed
        tx, ty = self._target(pose, px, py)
        return self._steer(wrap_angle(math.atan2(ty - py, tx - px) - pose.heading))

    def _align(self, pose: Pose) -> tuple[float, float] | None:
        """Turn on the spot to the start heading; None once aligned in the start cell."""
        error = wrap_angle(self.heading_target - pose.heading)
        if abs(error) <= self.heading_tolerance:
            if self.grid.cell(pose.x, pose.y) == self.start_cell:
                return None
            self.aligning = False  # the turn slid the body out of the cell: approach again
            return 0.0, 0.0
        scale = min(1.0, max(0.3, abs(error) / self.turn_threshold))
        sign = math.copysign(1.0, error)
        return -sign * scale * self.wheel_speed, sign * scale * self.wheel_speed

    def _steer(self, error: float) -> tuple[float, float]:
        """Turn on the spot for a large bearing error, else drive with a proportional turn."""
        speed = self.wheel_speed
        if abs(error) > self.turn_threshold:
            sign = math.copysign(1.0, error)
            return -sign * speed, sign * speed
        correction = float(np.clip(self.gain * error, -1.0, 1.0)) * speed
        return (
            float(np.clip(speed - correction, -speed, speed)),
            float(np.clip(speed + correction, -speed, speed)),
        )

    def _stuck(self, px: float, py: float) -> bool:
        """True when the pivot moved less than a quarter cell in ``stuck_periods`` periods
        (pushing against a wall): the controller then backs up and re-plans."""
        anchor = self._anchor
        if anchor is None or math.hypot(px - anchor[0], py - anchor[1]) > self.reach / 2:
            self._anchor, self._since_anchor = (px, py), 0
            return False
        self._since_anchor += 1
        if self._since_anchor < self.stuck_periods:
            return False
        self._anchor = None
        return True
