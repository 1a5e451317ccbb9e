"""The cost-to-go's lattice trusts the learned model at full speed only where it has seen fast
commands: a fit on slow commands alone on a floor with a dead zone would make every lattice
action too short to leave its cell (:func:`skidnav.agents.mpc.dynamics.lattice_coefficients`).
Fast commands are counted among the kept samples of a region's window (``lattice_guard =
"window"``, the default, with any number of rings) or by the fastest speed ring (``"rings"``,
which needs ``kinematic_speed_strata`` > 1)."""

from __future__ import annotations

import numpy as np
import pytest

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


def model_after(*parts: np.ndarray, strata: int = 3) -> KinematicModel:
    model = KinematicModel(ROBOT, Discretization(), KinematicModelConfig(speed_strata=strata))
    for part in parts:
        model.feed(part)
    model.refit()
    return model


GUARDS = [(3, "rings"), (3, "window"), (1, "window")]
"""(speed rings, lattice_guard) of the guarded settings."""
DATASHEET = np.tile(nominal_coefficients(ROBOT), (Discretization().n_regions, 1))


@pytest.mark.parametrize(("strata", "guard"), GUARDS)
def test_slow_commands_alone_leave_the_lattice_on_the_datasheet(strata: int, guard: str) -> None:
    rng = np.random.default_rng(0)
    model = model_after(drive(rng, 400, 0.5, REGION), strata=strata)
    assert full_speed(model.coefficients) < 0.7 * FULL_SPEED  # the fit on slow commands: too slow
    np.testing.assert_array_equal(lattice_coefficients(model, model.coefficients, guard), DATASHEET)


@pytest.mark.parametrize(("strata", "guard"), GUARDS)
def test_once_fast_commands_are_seen_the_lattice_takes_the_fit(strata: int, guard: str) -> None:
    rng = np.random.default_rng(0)
    model = model_after(drive(rng, 400, 0.5, REGION), drive(rng, 200, 1.7, REGION), strata=strata)
    lattice = lattice_coefficients(model, model.coefficients, guard)
    np.testing.assert_array_equal(lattice, model.coefficients)
    # the fit at full speed is now near the floor's
    assert abs(full_speed(lattice) - FULL_SPEED) < 0.1 * FULL_SPEED


def test_one_ring_counted_by_rings_guards_nothing() -> None:
    rng = np.random.default_rng(0)
    model = model_after(drive(rng, 400, 0.5, REGION), strata=1)
    np.testing.assert_array_equal(
        lattice_coefficients(model, model.coefficients, "rings"), model.coefficients
    )


def test_the_window_guard_counts_what_the_fit_still_sees() -> None:
    """Fast commands pushed out of the one window by slow ones: the fit no longer sees them, so
    the window guard returns to the datasheet where the rings' count (ever fed) would not."""
    rng = np.random.default_rng(0)
    model = model_after(drive(rng, 100, 1.7, REGION), drive(rng, 500, 0.5, REGION), strata=1)
    assert model.fast_counts()[REGION] == 0
    np.testing.assert_array_equal(
        lattice_coefficients(model, model.coefficients, "window"), DATASHEET
    )


def test_fast_counts_are_the_kept_commands_in_the_fastest_third_of_the_wheel_speed() -> None:
    rows = np.zeros((80, 6))
    rows[:, 0] = REGION
    rows[:30, 1] = 0.9 * ROBOT.wheel_speed  # fast: the faster wheel decides
    rows[30:, 1:3] = 0.6 * ROBOT.wheel_speed  # under 2/3 of the top speed
    rows[:30, 2] = -0.1
    model = KinematicModel(ROBOT, Discretization(), KinematicModelConfig(window=50))
    model.feed(rows)
    counts = model.fast_counts()
    assert counts[REGION] == 0 and counts.sum() == 0  # the 30 fast ones were pushed out
    model.feed(rows[:10])
    assert model.fast_counts()[REGION] == 10 and model.fast_counts().sum() == 10


def test_a_held_model_is_its_mean_whatever_the_guard() -> None:
    rng = np.random.default_rng(0)
    model = model_after(drive(rng, 400, 0.5, REGION), strata=1)
    model.hold()
    for guard in ("rings", "window"):
        np.testing.assert_array_equal(
            lattice_coefficients(model, model.coefficients, guard), model.coefficients
        )
