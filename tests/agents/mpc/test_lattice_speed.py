"""The cost-to-go's lattice trusts the learned model at full speed only where it has seen fast
commands: a fit on slow commands alone on a floor with a dead zone would make every lattice
action too short to leave its cell (:func:`skidnav.agents.mpc.dynamics.lattice_coefficients`)."""

from __future__ import annotations

import numpy as np

from skidnav.agents.mpc.dynamics import lattice_coefficients
from skidnav.models.kinematic import KinematicModel, KinematicModelConfig
from skidnav.models.kinematic_regression import nominal_coefficients
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization

ROBOT = RobotParams()
REGION = 8
"""The slip region every sample is logged in."""
ETA = 0.3
"""The slippery floor's wheel-speed loss [rad/s]: each wheel loses U(0, η), never past zero."""
FULL_SPEED = ROBOT.wheel_radius * (ROBOT.wheel_speed - ETA / 2)
"""The floor's true v_x of full speed ahead [m/s]: r (Ω − η/2), the mean loss taken."""


def drive(rng: np.random.Generator, n: int, largest: float, region: int) -> np.ndarray:
    """``n`` kinematic-log rows ``[region, ω_L, ω_R, v_x, v_y, yaw rate]`` of random straight
    commands up to ``largest`` [rad/s] on the dead-zone floor, in one region."""
    command = rng.uniform(-largest, largest, n)
    loss = rng.uniform(0.0, ETA, n)
    wheel = np.sign(command) * np.maximum(np.abs(command) - loss, 0.0)
    rows = np.zeros((n, 6))
    rows[:, 0] = region
    rows[:, 1] = rows[:, 2] = command
    rows[:, 3] = ROBOT.wheel_radius * wheel
    return rows


def full_speed(coefficients: np.ndarray) -> float:
    """v_x [m/s] of full speed ahead (both wheels at Ω) by the coefficients (n_regions, 8), the
    largest over the regions (those without a fit of their own hold the pooled fit)."""
    return float(((coefficients[:, 0] + coefficients[:, 1]) * ROBOT.wheel_speed).max())


def model_after(*parts: np.ndarray) -> KinematicModel:
    model = KinematicModel(ROBOT, Discretization(), KinematicModelConfig(speed_strata=3))
    for part in parts:
        model.feed(part)
    model.refit()
    return model


def test_slow_commands_alone_leave_the_lattice_on_the_datasheet() -> None:
    rng = np.random.default_rng(0)
    model = model_after(drive(rng, 400, 0.5, REGION))
    assert full_speed(model.coefficients) < 0.7 * FULL_SPEED  # the fit on slow commands: too slow
    lattice = lattice_coefficients(model, model.coefficients)
    np.testing.assert_array_equal(lattice, np.tile(nominal_coefficients(ROBOT), (len(lattice), 1)))


def test_once_fast_commands_are_seen_the_lattice_takes_the_fit() -> None:
    rng = np.random.default_rng(0)
    model = model_after(drive(rng, 400, 0.5, REGION), drive(rng, 200, 1.7, REGION))
    lattice = lattice_coefficients(model, model.coefficients)
    np.testing.assert_array_equal(lattice, model.coefficients)
    # the fit at full speed is now near the floor's
    assert abs(full_speed(lattice) - FULL_SPEED) < 0.1 * FULL_SPEED
