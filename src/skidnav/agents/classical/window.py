"""The robot's motion as the classical navigator sees it: its velocity from its own poses, the
dynamic window of the commands it can reach, and whether it is making progress.

Fox, Burgard & Thrun (1997), "The dynamic window approach to collision avoidance", §4.1: of the
velocities (v, ψ̇) the controller could command, only those the robot can reach within one
control period T from its current velocity under its acceleration limits are searched,

    v ∈ [v₀ − a T, v₀ + a T],    ψ̇ ∈ [ψ̇₀ − α T, ψ̇₀ + α T],

intersected with the commands the wheels allow. Per observation:

1. **Current velocity** (:class:`Odometry`), from successive poses T apart, nothing else: the
   forward speed v₀ = ((x − x′) cos ψ̄ + (y − y′) sin ψ̄) / T along the mean heading ψ̄ (the
   chord of a constant-twist step points along it) and the yaw rate ψ̇₀ = wrap(ψ − ψ′) / T; at
   an episode's first observation the robot is at rest.
2. **Window** (:func:`window_commands`): ``speed_samples`` speeds and ``yaw_rate_samples`` yaw
   rates evenly over the window (and 0 where the window holds it: stopping, and turning in
   place), as wheel speeds within ± Ω (:func:`wheel_commands`). A robot that takes a command
   at once (``acceleration`` and ``yaw_acceleration`` None, the kinematic simulator) has the
   whole range as its window: the fixed samples of :func:`command_samples`.
3. **Progress** (:class:`ProgressCheck`; as Nav2's progress checker): the robot is *stuck* when
   its position has moved less than ``stuck_speed`` × v_max × ``stuck_time`` over the last
   ``stuck_time`` seconds. Standing still can be the best admissible command for ever (in a
   gap the padded footprint barely fits, every motion meets an obstacle at once); the
   recovery then runs for ``recovery_time`` seconds (:mod:`skidnav.agents.classical.dwa`).
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from skidnav.robot.kinematics import wrap_angle


def wheel_commands(
    speeds: np.ndarray, yaw_rates: np.ndarray, wheel_radius: float, half_track: float, top: float
) -> np.ndarray:
    """Every pair of the forward ``speeds`` [m/s] (outer) and ``yaw_rates`` [rad/s] (inner) as
    wheel speeds (ω_L, ω_R) [rad/s], float64 (K, 2): the inverse of the ICR model without slip,
    ω_R = (v + c ψ̇) / r, ω_L = (v − c ψ̇) / r, scaled down together (the same curvature) until
    both lie within ± ``top`` [rad/s]."""
    v, yaw = (grid.ravel() for grid in np.meshgrid(speeds, yaw_rates, indexing="ij"))
    right = (v + half_track * yaw) / wheel_radius
    left = (v - half_track * yaw) / wheel_radius
    largest = np.maximum(np.abs(left), np.abs(right))
    scale = np.where(largest > top, top / np.maximum(largest, 1e-300), 1.0)
    return np.ascontiguousarray(np.stack([left * scale, right * scale], axis=1))


def command_samples(
    wheel_radius: float,
    half_track: float,
    top: float,
    max_speed: float,
    reverse_speed: float,
    max_yaw_rate: float,
    speed_samples: int,
    yaw_rate_samples: int,
) -> np.ndarray:
    """The whole range's commands as wheel speeds [rad/s], float64 (K, 2): ``speed_samples``
    forward speeds from 0 to ``max_speed`` [m/s] and, if ``reverse_speed`` [m/s] > 0,
    −``reverse_speed``, each with ``yaw_rate_samples`` yaw rates over ± ``max_yaw_rate``
    [rad/s] (which the caller caps at r Ω / c); r = ``wheel_radius`` [m], c = ``half_track``
    [m], Ω = ``top`` [rad/s]."""
    speeds = np.linspace(0.0, max_speed, speed_samples)
    if reverse_speed > 0.0:
        speeds = np.append(speeds, -reverse_speed)
    yaw_rates = np.linspace(-max_yaw_rate, max_yaw_rate, yaw_rate_samples)
    return wheel_commands(speeds, yaw_rates, wheel_radius, half_track, top)


def window_levels(current: float, reach: float, low: float, high: float, count: int) -> np.ndarray:
    """``count`` levels evenly over [current − reach, current + reach] ∩ [low, high] (the
    current value clipped to [low, high] first, so the window is never empty), and 0 added
    where the window holds it but the levels miss it."""
    centre = min(max(current, low), high)
    lower, upper = max(low, centre - reach), min(high, centre + reach)
    levels = np.linspace(lower, upper, count)
    if lower < 0.0 < upper and not (levels == 0.0).any():
        levels = np.sort(np.append(levels, 0.0))
    return levels


def window_commands(
    velocity: tuple[float, float],
    reach: tuple[float, float],
    wheel_radius: float,
    half_track: float,
    top: float,
    speed_range: tuple[float, float],
    max_yaw_rate: float,
    samples: tuple[int, int],
) -> np.ndarray:
    """The dynamic window's commands as wheel speeds [rad/s], float64 (K, 2) (module doc,
    step 2): from the current ``velocity`` (v₀ [m/s], ψ̇₀ [rad/s]), within ``reach`` (a T
    [m/s], α T [rad/s]; ``math.inf``: the whole range) of it, forward speeds within
    ``speed_range`` (lowest, highest) [m/s] and yaw rates within ± ``max_yaw_rate`` [rad/s];
    ``samples`` (speed levels, yaw-rate levels)."""
    speeds = window_levels(velocity[0], reach[0], *speed_range, samples[0])
    yaw_rates = window_levels(velocity[1], reach[1], -max_yaw_rate, max_yaw_rate, samples[1])
    return wheel_commands(speeds, yaw_rates, wheel_radius, half_track, top)


class Odometry:
    """The robot's velocity from its successive poses ``period`` [s] apart (module doc,
    step 1)."""

    def __init__(self, period: float) -> None:
        self.period = period
        self.reset()

    def reset(self) -> None:
        """A new episode: the robot starts at rest."""
        self.previous: tuple[float, float, float] | None = None

    def update(self, x: float, y: float, heading: float) -> tuple[float, float]:
        """(v [m/s], ψ̇ [rad/s]) over the period that ended at the pose (x [m], y [m], heading
        [rad]); (0, 0) at the episode's first pose."""
        previous, self.previous = self.previous, (x, y, heading)
        if previous is None:
            return 0.0, 0.0
        turned = wrap_angle(heading - previous[2])
        mean_heading = previous[2] + 0.5 * turned
        forward = (x - previous[0]) * math.cos(mean_heading) + (y - previous[1]) * math.sin(
            mean_heading
        )
        return forward / self.period, turned / self.period


class ProgressCheck:
    """Whether the robot is stuck (module doc, step 3): it has moved less than ``distance`` [m]
    over the last ``periods`` control periods (0 periods: never stuck)."""

    def __init__(self, periods: int, distance: float) -> None:
        self.periods, self.distance = periods, distance
        self.positions: deque[tuple[float, float]] = deque(maxlen=periods + 1)

    def reset(self) -> None:
        """Forget the positions: a new episode, or a recovery just ended."""
        self.positions.clear()

    def stuck(self, x: float, y: float) -> bool:
        """Record the position (x [m], y [m]); whether the robot has moved less than the
        distance since ``periods`` periods ago."""
        self.positions.append((x, y))
        if self.periods == 0 or len(self.positions) <= self.periods:
            return False
        start = self.positions[0]
        return math.hypot(x - start[0], y - start[1]) < self.distance
