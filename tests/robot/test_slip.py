import numpy as np
import pytest

from skidnav.robot.kinematics import (
    apply_slip,
    body_velocities,
    commanded_wheel_speeds,
    expected_slipped_speed,
)
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SlipField, make_slip_field
from skidnav.sim.task import build_task
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


def _quadrature_velocities(
    field: SlipField, robot: RobotParams, region: int, action: int, points: int = 200
) -> np.ndarray:
    """Mean body velocities of an action in a flat region over a midpoint grid of the two
    wheels' uniform draws, as the simulator slows the wheels (apply_slip) — no expectation
    taken in closed form."""
    eta, x_icr, radius, track, _ = field.kernel_arrays(robot)
    commands = commanded_wheel_speeds(action, robot.wheel_speed)
    draws = (np.arange(points) + 0.5) / points
    total = np.zeros(3)
    for u_left in draws:
        left = apply_slip(commands[0], u_left * eta[region])
        for u_right in draws:
            right = apply_slip(commands[1], u_right * eta[region])
            total += body_velocities(left, right, x_icr[region], radius[region], track[region])
    return total / points**2


@pytest.mark.parametrize("preset", ["slippery", "slippery-physics"])
def test_expected_velocities_are_the_mean_of_the_slipped_motion(preset: str) -> None:
    robot = RobotParams()
    field = make_slip_field(preset, np.random.default_rng(3))
    table = field.expected_velocities(robot)
    assert table.shape == (49, 4, 3)
    patch = int(np.argmax(field.eta.ravel()))  # the most slippery region, and an ordinary one
    for region in (patch, int(np.argmin(field.eta.ravel()))):
        for action in range(4):
            mean = _quadrature_velocities(field, robot, region, action)
            np.testing.assert_allclose(table[region, action], mean, atol=1e-9, rtol=1e-4)
    assert table[patch, 0, 0] < table[int(np.argmin(field.eta.ravel())), 0, 0]


def test_expected_speed_when_the_loss_can_exceed_the_wheel_speed() -> None:
    """η beyond the wheel speed: the wheel stops rather than reverses (ω²/2η, not ω − η/2)."""
    field = SlipField(eta=np.full((1, 1), 4.0), x_icr=np.full((1, 1), 0.03),
                      drift_phase=np.zeros((1, 1)))  # fmt: skip
    robot = RobotParams()
    mean = _quadrature_velocities(field, robot, 0, 2)
    np.testing.assert_allclose(field.expected_velocities(robot)[0, 2], mean, atol=1e-9, rtol=1e-4)
    assert expected_slipped_speed(-1.7, 4.0) == pytest.approx(-(1.7**2) / 8.0)


def test_a_drifting_floor_averages_its_expected_velocities_over_a_period() -> None:
    """While η(t) stays below the wheel speed the expected velocities are linear in η, and η's
    mean over a period (amplitude ≤ 1) is η₀: the drifting floor's average is the still one's.
    Where the drift pushes η past the wheel speed, where the expected speed is convex in η, the
    average is faster than that."""
    robot = RobotParams()
    still = make_slip_field("slippery", np.random.default_rng(5))
    drifting = make_slip_field("slippery", np.random.default_rng(5), drift_amplitude=0.5)
    np.testing.assert_array_equal(still.eta, drifting.eta)
    ordinary = still.eta.ravel() < 1.0
    averaged, fixed = drifting.expected_velocities(robot), still.expected_velocities(robot)
    np.testing.assert_allclose(averaged[ordinary], fixed[ordinary], rtol=1e-12, atol=1e-15)
    assert (averaged[~ordinary, 0, 0] > fixed[~ordinary, 0, 0]).all()
