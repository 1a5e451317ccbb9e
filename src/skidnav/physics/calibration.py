"""Floors from physics: the ICR model fitted to the MuJoCo robot on each floor material.

The robot drives over one material (the whole floor) under a seeded excitation: 1-s segments
alternating the four discrete actions and uniform random wheel-speed pairs in ±``wheel_speed``, each
logged per 0.1-s sub-step as the kinematic log is (commanded ω_L, ω_R; the measured body twist). The
thesis's regressions (Alhawary (2020), ch. 7; docs/agents/dyna-kinematic.md) are then fitted by
Bayesian ridge without intercepts (MacKay 1992; :mod:`skidnav.models.bayesian_ridge`):

    v_x ≈ β_L ω_L + β_R ω_R,   yaw_rate ≈ γ_L ω_L + γ_R ω_R,   v_y ≈ s · yaw_rate

and read as the ICR model's parameters: effective wheel radius r = β_L + β_R, effective half
track c = r / (γ_R − γ_L), x_ICR = −s (Kozłowski & Pazderski 2004). Intervals are the 2.5 and
97.5 percentiles of the parameters over draws from the Gaussian posterior of the coefficients
(seeded). The residual slip noise is the standard deviation of the v_x and yaw-rate residuals,
also stated as the η of the kinematic simulator's U(0, η) wheel-speed loss that gives the same
v_x variance: var(v_x) = r² η² / 24 (two independent wheels, each r/2 · U(0, η)).

An effective half track wider than the geometric one is how skid-steer robots turn slower than
their wheels suggest; Mandow et al. (2007, "Experimental kinematics for wheeled skid-steer mobile
robots", IROS) measured the same widening on a real platform.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from skidnav.models.bayesian_ridge import fit_bayesian_ridge
from skidnav.models.kinematic_regression import icr_parameters
from skidnav.physics.mjcf import PhysicsParams, physics_for, uniform_floor
from skidnav.physics.mujoco_robot import PhysicsRobot
from skidnav.robot.kinematics import N_ACTIONS, commanded_wheel_speeds
from skidnav.robot.params import RobotParams

POSTERIOR_DRAWS = 4000
"""Posterior draws behind each interval."""


@dataclass(frozen=True)
class FloorFit:
    """The ICR model fitted on one material (SI units; intervals are (low, high), 95 %).

    Attributes:
        material: the floor material.
        samples: logged sub-steps.
        wheel_radius, half_track, x_icr: effective r, c, x_ICR [m] and their intervals.
        vx_noise: residual standard deviation of v_x [m/s]; yaw_noise: of the yaw rate [rad/s].
        eta: the kinematic simulator's η [rad/s] with the same v_x variance.
    """

    material: str
    samples: int
    wheel_radius: float
    wheel_radius_interval: tuple[float, float]
    half_track: float
    half_track_interval: tuple[float, float]
    x_icr: float
    x_icr_interval: tuple[float, float]
    vx_noise: float
    yaw_noise: float
    eta: float

    def as_dict(self) -> dict[str, object]:
        """The fit as plain JSON values."""
        return asdict(self)


def excitation(
    rng: np.random.Generator, segments: int, wheel_speed: float
) -> list[tuple[float, float]]:
    """``segments`` commands (ω_L, ω_R) [rad/s]: even segments a uniform random pair in
    ±``wheel_speed``, odd ones a random discrete action's."""
    commands: list[tuple[float, float]] = []
    for k in range(segments):
        if k % 2:
            left, right = commanded_wheel_speeds(int(rng.integers(N_ACTIONS)), wheel_speed)
        else:
            left, right = rng.uniform(-wheel_speed, wheel_speed, 2)
        commands.append((float(left), float(right)))
    return commands


def drive_log(
    material: str,
    commands: list[tuple[float, float]],
    robot: RobotParams,
    physics: PhysicsParams,
) -> np.ndarray:
    """Drive each command for one action (``robot.substeps`` × ``robot.dt``) on a floor of
    ``material``; float64 (n_substeps, 5): ω_L, ω_R [rad/s], v_x, v_y [m/s], yaw rate [rad/s]."""
    body = PhysicsRobot(robot, uniform_floor(material), physics)
    body.reset(robot.arena_width / 2, robot.arena_height / 2, 0.0)
    rows = []
    for command in commands:
        for _ in range(robot.substeps):
            set_points, twist = body.substep(command, 0.0, (0.0, 0.0), robot.dt)
            rows.append((*set_points, *twist))
    return np.array(rows, dtype=np.float64)


def _posterior(inputs: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bayesian ridge without intercept: posterior mean and covariance of the coefficients."""
    regression = fit_bayesian_ridge(inputs, target, np.ones(len(target)), fit_intercept=False)
    return regression.coef, regression.covariance


def fit_floor(material: str, log: np.ndarray, rng: np.random.Generator) -> FloorFit:
    """:class:`FloorFit` of a :func:`drive_log` (see the module docstring)."""
    wheels, v_x, v_y, yaw_rate = log[:, 0:2], log[:, 2], log[:, 3], log[:, 4]
    beta, beta_cov = _posterior(wheels, v_x)
    gamma, gamma_cov = _posterior(wheels, yaw_rate)
    slope, slope_cov = _posterior(yaw_rate[:, None], v_y)
    betas = rng.multivariate_normal(beta, beta_cov, POSTERIOR_DRAWS)
    gammas = rng.multivariate_normal(gamma, gamma_cov, POSTERIOR_DRAWS)
    slopes = rng.normal(slope[0], math.sqrt(slope_cov[0, 0]), POSTERIOR_DRAWS)
    radii, tracks, icrs = icr_parameters(betas, gammas, slopes)
    radius, half_track, x_icr = icr_parameters(beta, gamma, slope[0])

    def interval(values: np.ndarray) -> tuple[float, float]:
        low, high = np.percentile(values, [2.5, 97.5])
        return float(low), float(high)

    vx_noise = float(np.std(v_x - wheels @ beta))
    return FloorFit(
        material=material,
        samples=int(log.shape[0]),
        wheel_radius=float(radius),
        wheel_radius_interval=interval(radii),
        half_track=float(half_track),
        half_track_interval=interval(tracks),
        x_icr=float(x_icr),
        x_icr_interval=interval(icrs),
        vx_noise=vx_noise,
        yaw_noise=float(np.std(yaw_rate - wheels @ gamma)),
        eta=math.sqrt(24.0) * vx_noise / float(radius),
    )


def calibrate(
    materials: list[str],
    rng: np.random.Generator,
    segments: int = 60,
    robot: RobotParams | None = None,
    physics: PhysicsParams | None = None,
) -> list[FloorFit]:
    """Fit every material in ``materials`` on the same seeded excitation (common random
    numbers: differences between materials are the floors', not the commands')."""
    robot = robot or RobotParams()
    physics = physics or physics_for(robot)
    commands = excitation(rng, segments, robot.wheel_speed)
    return [fit_floor(name, drive_log(name, commands, robot, physics), rng) for name in materials]
