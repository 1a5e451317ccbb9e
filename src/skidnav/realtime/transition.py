"""Turning measured poses into what the agents learn from: kinematic log rows and rewards.

Kinematic log (same columns as the env, kernels/navigation.py ``LOG_COLUMNS``): between two
consecutive measured poses p₀ = (x₀, y₀, ψ₀) at t₀ and p₁ at t₁ (robot time, Δt = t₁ − t₀ > 0),
the body-frame finite differences consistent with the explicit-Euler model are

    v_x = ( cos ψ₀ Δx + sin ψ₀ Δy) / Δt,   v_y = (−sin ψ₀ Δx + cos ψ₀ Δy) / Δt,
    yaw_rate = wrap(ψ₁ − ψ₀) / Δt,

keyed by the coarse region of p₀, with the commanded wheel speeds of the action.

Reward (the env's rule, SPEC §3): +10 and termination when the action ends in the goal cell; −10
after a collision; otherwise −1 − 10·var with var the observed (thesis) sample variance of the
wheel speeds measured during forward actions in the region where the action ends. A real robot
has no known slip field, so the observed variance is the only one available here. Wheel speeds
are recovered from the measured twist by inverting the ICR model: ω_R = (v_x + c·yaw_rate)/r,
ω_L = (v_x − c·yaw_rate)/r (Kozłowski & Pazderski 2004).
"""

from __future__ import annotations

import math

import numpy as np

from skidnav.kernels.navigation import LOG_COLUMNS, RewardScheme
from skidnav.realtime.driver import Pose
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization

assert len(LOG_COLUMNS) == 6


def wrap_angle(angle: float) -> float:
    """``angle`` [rad] wrapped to [−π, π]."""
    return math.atan2(math.sin(angle), math.cos(angle))


def log_row(
    before: Pose, after: Pose, dt: float, region: int, command: tuple[float, float]
) -> np.ndarray | None:
    """One kinematic log row (float64 (6,)) from two poses, or None if no time passed.

    Args:
        before, after: consecutive poses.
        dt: robot time between them [s].
        region: flat coarse region of ``before``. command: (ω_L, ω_R) commanded [rad/s].
    """
    if not dt > 1e-9:
        return None
    dx, dy = after.x - before.x, after.y - before.y
    cos_h, sin_h = math.cos(before.heading), math.sin(before.heading)
    v_x = (cos_h * dx + sin_h * dy) / dt
    v_y = (-sin_h * dx + cos_h * dy) / dt
    yaw_rate = wrap_angle(after.heading - before.heading) / dt
    return np.array([region, command[0], command[1], v_x, v_y, yaw_rate], dtype=np.float64)


class WheelSpeedStats:
    """Running (count, mean, M2) of measured wheel speeds per region (Welford 1962).

    Attributes:
        stats: float64 (n_regions, 3).
    """

    def __init__(self, n_regions: int, robot: RobotParams) -> None:
        self.stats = np.zeros((n_regions, 3), dtype=np.float64)
        self.robot = robot

    def add(self, region: int, value: float) -> None:
        """Record one wheel speed [rad/s] measured in ``region``."""
        row = self.stats[region]
        row[0] += 1.0
        delta = value - row[1]
        row[1] += delta / row[0]
        row[2] += delta * (value - row[1])

    def add_rows(self, rows: np.ndarray) -> None:
        """Record the wheel speeds implied by kinematic log rows (forward actions only)."""
        r, c = self.robot.wheel_radius, self.robot.half_track
        for row in rows:
            v_x, yaw_rate = row[3], row[5]
            self.add(int(row[0]), (v_x - c * yaw_rate) / r)
            self.add(int(row[0]), (v_x + c * yaw_rate) / r)

    def variance(self, region: int) -> float:
        """Sample variance [rad²/s²] of ``region`` (0 with fewer than two samples)."""
        count = self.stats[region, 0]
        return float(self.stats[region, 2] / (count - 1.0)) if count > 1.0 else 0.0


def reward_of(
    pose: Pose,
    collided: bool,
    goal: tuple[int, int],
    grid: Discretization,
    stats: WheelSpeedStats,
    scheme: RewardScheme | None = None,
) -> tuple[float, bool]:
    """(reward, terminated) of an action that ended at ``pose`` (see module doc)."""
    scheme = scheme or RewardScheme()
    if grid.cell(pose.x, pose.y) == tuple(goal):
        return scheme.goal, True
    if collided:
        return scheme.collision, False
    variance = stats.variance(grid.region(pose.x, pose.y))
    return scheme.step - scheme.variance_weight * variance, False
