"""``icr_parameters``: the ICR model's reading of the kinematic regressions, shared by
``skidnav world floors calibrate`` and the reading of a learned model's coefficients."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco")

from skidnav.models.kinematic import KinematicModel
from skidnav.models.kinematic_regression import icr_parameters, nominal_coefficients
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization


def test_nominal_coefficients_read_back_as_the_nominal_robot() -> None:
    robot = RobotParams()
    coefficients = nominal_coefficients(robot)
    r, c, x_icr = icr_parameters(coefficients[0:2], coefficients[3:5], coefficients[6])
    assert (r, c, x_icr) == pytest.approx((robot.wheel_radius, robot.half_track, robot.x_icr))


def test_agrees_with_the_learned_models_own_reading() -> None:
    """Same numbers as ``KinematicModel.estimates`` for any coefficients of a region."""
    model = KinematicModel(RobotParams(), Discretization())
    rng = np.random.default_rng(0)
    model.coefficients[3] = nominal_coefficients(RobotParams()) * rng.uniform(0.5, 1.5, 8)
    c = model.coefficients[3]
    assert icr_parameters(c[0:2], c[3:5], c[6]) == pytest.approx(model.estimates(3), rel=1e-12)


def test_reads_a_stack_of_fits_at_once() -> None:
    """Posterior draws (n, 2), (n, 2), (n,) give n readings, each that of its own draw."""
    rng = np.random.default_rng(1)
    betas, gammas = rng.uniform(0.01, 0.02, (5, 2)), rng.uniform(-0.2, 0.2, (5, 2))
    slopes = rng.normal(0.0, 0.01, 5)
    radii, tracks, icrs = icr_parameters(betas, gammas, slopes)
    assert radii.shape == tracks.shape == icrs.shape == (5,)
    for k in range(5):
        one = icr_parameters(betas[k], gammas[k], slopes[k])
        assert (radii[k], tracks[k], icrs[k]) == pytest.approx(one, rel=1e-15)
