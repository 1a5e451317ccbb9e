"""Turning measured poses into what the agents learn from: kinematic log rows and rewards.

Kinematic log (same columns as the env, sim/navigation.py ``LOG_COLUMNS``): between two
consecutive measured poses p₀ = (x₀, y₀, ψ₀) at t₀ and p₁ at t₁ (robot time, Δt = t₁ − t₀ > 0),
the body-frame finite differences consistent with the explicit-Euler model are

    v_x = ( cos ψ₀ Δx + sin ψ₀ Δy) / Δt,   v_y = (−sin ψ₀ Δx + cos ψ₀ Δy) / Δt,
    yaw_rate = wrap(ψ₁ − ψ₀) / Δt,

keyed by the coarse region of p₀, with the commanded wheel speeds of the action.

Reward: the env's rule, :func:`skidnav.sim.navigation.action_reward` (docs/simulator.md: +10 and
termination when the action ends in the goal cell; −10 after a collision; otherwise −1 − 10·var),
var being the observed (thesis) variance of the wheel speeds measured during forward actions in
the region where the action ends, corrected for pose noise (:class:`WheelSpeedStats`). A real
robot has no known slip field, so the observed variance is the only one available here;
uncorrected, a tracker's 1 mm of pose noise alone would read as a variance of ≈ 0.4 rad²/s² over
0.1 s periods, a −4 penalty on every step of every region.
Wheel speeds are recovered from the measured twist by inverting the ICR model:
ω_R = (v_x + c·yaw_rate)/r, ω_L = (v_x − c·yaw_rate)/r (Kozłowski & Pazderski 2004).
"""

from __future__ import annotations

import math

import numpy as np

from skidnav.realtime.link.interface import Pose
from skidnav.robot.kinematics import wrap_angle
from skidnav.robot.params import RobotParams
from skidnav.sim.navigation import LOG_COLUMNS, RewardScheme, action_reward
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap

assert len(LOG_COLUMNS) == 6


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
    """Per-region moments of the wheel speeds measured during forward actions, from which the
    slip variance is estimated free of white pose noise (see :meth:`variance`).

    A wheel speed measured over one control period from two noisy poses is the true speed plus
    (e₁ − e₀)/Δt-like noise: consecutive measurements share a pose, so their noise has lag-1
    autocovariance −½ of its variance, while slip drawn afresh each period has none. Hence
    γ₀ + 2γ₁ (variance plus twice the lag-1 autocovariance) keeps the slip variance and cancels
    the pose noise, whatever its size; it is also exact for slip that a measurement period
    straddles over two periods of the robot's own (an MA(1) mix of independent draws).

    Attributes:
        stats: float64 (n_regions, 7): per region the count n, Σω, Σω² [rad/s, rad²/s²] of
            single measurements, and the count m, Σ ω_t, Σ ω_{t+1} and Σ ω_t·ω_{t+1} of lag-1
            pairs (consecutive periods of one forward action, same wheel, both in the region).
    """

    def __init__(self, n_regions: int, robot: RobotParams) -> None:
        self.stats = np.zeros((n_regions, 7), dtype=np.float64)
        self.robot = robot

    def add(self, region: int, value: float, previous: float | None = None) -> None:
        """Record one wheel speed [rad/s] measured in ``region``; ``previous``: the same wheel's
        speed one period earlier in the same action and region, if any."""
        row = self.stats[region]
        row[0] += 1.0
        row[1] += value
        row[2] += value * value
        if previous is not None:
            row[3] += 1.0
            row[4] += previous
            row[5] += value
            row[6] += previous * value

    def add_rows(self, rows: np.ndarray) -> None:
        """Record the wheel speeds implied by the kinematic log rows of one forward action,
        in period order."""
        r, c = self.robot.wheel_radius, self.robot.half_track
        last_region, last_left, last_right = -1, 0.0, 0.0
        for row in rows:
            region, v_x, yaw_rate = int(row[0]), row[3], row[5]
            left, right = (v_x - c * yaw_rate) / r, (v_x + c * yaw_rate) / r
            paired = region == last_region
            self.add(region, left, last_left if paired else None)
            self.add(region, right, last_right if paired else None)
            last_region, last_left, last_right = region, left, right

    def variance(self, region: int) -> float:
        """Slip variance of the wheel speeds of ``region`` [rad²/s²]: max(0, γ₀ + 2γ₁), with γ₀
        the sample variance and γ₁ the lag-1 autocovariance (0 without lag pairs); 0 with fewer
        than two samples."""
        count, total, squares, pairs, firsts, seconds, products = self.stats[region]
        if count < 2.0:
            return 0.0
        mean = total / count
        gamma_0 = (squares - count * mean * mean) / (count - 1.0)
        # centred on the pairs' own means: shifting every speed by a constant changes nothing
        gamma_1 = (products - firsts * seconds / pairs) / pairs if pairs > 0 else 0.0
        return float(max(0.0, gamma_0 + 2.0 * gamma_1))

    def load(self, stats: np.ndarray) -> bool:
        """Restore :attr:`stats` saved by this class or by its earlier (count, mean, M2) form
        (Welford moments, no lag pairs); False if the shape fits neither."""
        if stats.shape == self.stats.shape:
            self.stats[:] = stats
            return True
        if stats.shape == (self.stats.shape[0], 3):
            count, mean, m2 = stats.T
            self.stats[:] = 0.0
            self.stats[:, 0], self.stats[:, 1] = count, count * mean
            self.stats[:, 2] = m2 + count * mean * mean
            return True
        return False


class IcrEstimates:
    """Per-region estimates of the longitudinal ICR offset x_ICR [m] from kinematic log rows:
    the skid-steer model says v_y = −x_ICR·ω (Kozłowski & Pazderski 2004), so x_ICR is the
    least-squares slope of −v_y on ω, shrunk (ridge regression with ``prior_weight``
    [rad²/s²], about a quarter of one turn action's rows) towards the pooled estimate: the same
    slope over every region's rows, itself shrunk towards the nominal value (partial pooling,
    Gelman & Hill 2007, §12). A region with few rows takes the floor's x_ICR seen so far, not
    the datasheet's.

    The homing controller turns about the pivot this estimate puts under the robot; with the
    nominal x_ICR on a floor that shifts it, every turn moves the controller's pivot and homing
    can circle for ever. Shrunk towards the nominal value alone, a region the robot had not
    turned in kept the datasheet's 5 cm beside regions at about 0 (the MuJoCo robot): the pivot
    jumped 4 cm as pose noise moved the robot across their border, a waypoint closer to the body
    than that jump lay behind the pivot whichever way the robot turned, and homing turned back
    and forth until it timed out (docs/robot-learning.md, "Measured on the MuJoCo robot").

    Attributes:
        sums: float64 (n_regions, 2): Σ −v_y·ω [m/s²] and Σ ω² [rad²/s²] per region.
    """

    def __init__(self, n_regions: int, nominal: float, prior_weight: float = 1.0) -> None:
        self.sums = np.zeros((n_regions, 2), dtype=np.float64)
        self.nominal = nominal
        self.prior_weight = prior_weight

    def add_rows(self, rows: np.ndarray) -> None:
        """Record kinematic log rows (columns of ``LOG_COLUMNS``)."""
        for row in rows:
            region, v_y, yaw_rate = int(row[0]), row[4], row[5]
            self.sums[region, 0] -= v_y * yaw_rate
            self.sums[region, 1] += yaw_rate * yaw_rate

    def values(self) -> np.ndarray:
        """float64 (n_regions,): the estimate of every region [m] (class doc)."""
        weight = self.prior_weight
        total = self.sums.sum(axis=0)
        pooled = (weight * self.nominal + total[0]) / (weight + total[1])
        values: np.ndarray = (weight * pooled + self.sums[:, 0]) / (weight + self.sums[:, 1])
        return values


def reward_of(
    pose: Pose,
    collided: bool,
    goal: tuple[int, int],
    grid: Discretization,
    stats: WheelSpeedStats,
    scheme: RewardScheme | None = None,
) -> tuple[float, bool]:
    """(reward, terminated) of an action that ended at ``pose`` (see module doc)."""
    at_goal = grid.cell(pose.x, pose.y) == tuple(goal)
    variance = stats.variance(grid.region(pose.x, pose.y))
    reward = action_reward(scheme or RewardScheme(), at_goal, bool(collided), variance)
    return float(reward), at_goal


def compile_scoring(grid_map: GridMap, grid: Discretization, robot: RobotParams) -> None:
    """Compile (numba) what the control loop scores every action with, before the robot is
    contacted: the state, cell and region of a pose, the kinematic log row and the reward of
    :func:`reward_of`. On a cold cache their compilation (~0.25 s, holding the GIL) otherwise
    fell at the end of the first action, whose command then expired with the robot stopped."""
    x, y = grid.cell_centre(*grid_map.start)
    before, after = Pose(0.0, x, y, 0.0), Pose(0.1, x, y, 0.1)
    grid.state(after.x, after.y, after.heading)
    log_row(before, after, 0.1, grid.region(before.x, before.y), (0.0, 0.0))
    reward_of(after, False, grid_map.goal, grid, WheelSpeedStats(grid.n_regions, robot))
