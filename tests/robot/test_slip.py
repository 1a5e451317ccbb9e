import numpy as np
import pytest

from skidnav.kernels.navigation_api import build_task
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SlipField, make_slip_field
from skidnav.world.discretization import Discretization
from skidnav.world.grid import generate_map


def test_thesis_preset_matches_the_thesis_numbers():
    field = make_slip_field("thesis", np.random.default_rng(0))
    assert field.shape == (7, 7)
    assert field.eta[0, 0] == 0.0
    assert field.eta[3, 5] == pytest.approx(0.008)
    assert np.all(field.x_icr == 0.05)
    assert not field.drifting


def test_presets_order_slip_as_named():
    rng = np.random.default_rng(1)
    slippery = make_slip_field("slippery", rng)
    rough = make_slip_field("rough", rng)
    assert slippery.eta.max() == pytest.approx(1.7)  # patches lose up to all, 50 % on average
    assert rough.eta.max() < 0.1 * 1.7
    assert np.all((slippery.x_icr >= 0) & (slippery.x_icr <= 0.05))


def test_presets_are_seeded():
    a = make_slip_field("slippery", np.random.default_rng(7))
    b = make_slip_field("slippery", np.random.default_rng(7))
    c = make_slip_field("slippery", np.random.default_rng(8))
    assert np.array_equal(a.eta, b.eta) and np.array_equal(a.x_icr, b.x_icr)
    assert not (np.array_equal(a.eta, c.eta) and np.array_equal(a.x_icr, c.x_icr))


def test_drift_changes_eta_over_time_and_never_below_zero():
    field = make_slip_field(
        "rough", np.random.default_rng(0), drift_amplitude=1.5, drift_period=10.0
    )
    values = np.array([field.eta_at(t) for t in np.linspace(0, 10, 41)])
    assert values.min() >= 0.0
    assert values.std(axis=0).min() > 0.0
    np.testing.assert_allclose(field.eta_at(0.0), field.eta_at(10.0))
    np.testing.assert_allclose(field.wheel_speed_variance(3.0), field.eta_at(3.0) ** 2 / 12)


def test_slip_field_is_validated():
    with pytest.raises(ValueError, match="eta"):
        SlipField(eta=-np.ones((7, 7)), x_icr=np.zeros((7, 7)))
    with pytest.raises(ValueError, match="x_icr"):
        SlipField(eta=np.ones((7, 7)), x_icr=np.zeros((6, 7)))
    with pytest.raises(ValueError, match="slip preset"):
        make_slip_field("ice", np.random.default_rng(0))


def test_x_icr_outside_the_axles_is_rejected_when_the_task_is_built():
    robot = RobotParams()  # a = b = 0.05 m
    grid_map = generate_map("free", np.random.default_rng(0))
    x_icr = np.full((7, 7), 0.05)
    x_icr[2, 3] = 0.08
    x_icr[4, 4] = -0.07
    field = SlipField(eta=np.zeros((7, 7)), x_icr=x_icr)
    with pytest.raises(ValueError, match=r"\[-0.05, 0.05\] m .* got 0.08 m in region \(2, 3\)"):
        build_task(grid_map, field, robot, Discretization())
    wider = RobotParams(front_axle=0.1, rear_axle=0.1)
    build_task(grid_map, field, wider, Discretization())  # within [-a, b] of that robot
