"""Closed-form checks of the ICR skid-steer kinematics and the two integrators."""

import math

import numpy as np
import pytest

from skidnav.robot.kinematics import (
    apply_slip,
    body_velocities,
    commanded_wheel_speeds,
    euler_step,
    exact_step,
)
from skidnav.robot.params import RobotParams

R, C, X_ICR, W = 0.0225, 0.06, 0.05, 1.7


def integrate(step, velocities, duration, dt, pose=(0.0, 0.0, 0.0)):
    x, y, heading = pose
    for _ in range(round(duration / dt)):
        x, y, heading = step(x, y, heading, *velocities, dt)
    return np.array([x, y, heading])


def test_straight_run_covers_r_times_wheel_speed_times_t():
    velocities = body_velocities(W, W, X_ICR, R, C)
    for step in (euler_step, exact_step):
        pose = integrate(step, velocities, 1.0, 0.1, pose=(0.1, 0.2, math.pi / 3))
        travelled = math.hypot(pose[0] - 0.1, pose[1] - 0.2)
        assert travelled == pytest.approx(R * W * 1.0, rel=1e-12)
        assert pose[2] == pytest.approx(math.pi / 3)


def test_spin_in_place_drifts_sideways_by_minus_x_icr_times_yaw_rate():
    v_x, v_y, yaw_rate = body_velocities(-W, W, X_ICR, R, C)
    assert v_x == 0.0
    assert yaw_rate == pytest.approx(R * 2 * W / (2 * C))  # 0.6375 rad/s
    assert v_y == pytest.approx(-X_ICR * yaw_rate)
    # constant body twist (0, v_y, ω) from the origin: X = v_y/ω (cos ωT − 1), Y = v_y/ω sin ωT
    duration = 1.0
    expected = np.array(
        [
            v_y / yaw_rate * (math.cos(yaw_rate * duration) - 1.0),
            v_y / yaw_rate * math.sin(yaw_rate * duration),
            yaw_rate * duration,
        ]
    )
    exact = integrate(exact_step, (v_x, v_y, yaw_rate), duration, 0.1)
    np.testing.assert_allclose(exact, expected, atol=1e-12)
    assert math.hypot(exact[0], exact[1]) == pytest.approx(0.0314, abs=5e-4)  # ≈ 3.2 cm slide


def test_euler_converges_to_the_exact_step_at_first_order():
    twist = body_velocities(W, 0.3 * W, X_ICR, R, C)
    exact = integrate(exact_step, twist, 1.0, 0.1)
    errors = [
        np.linalg.norm(integrate(euler_step, twist, 1.0, dt)[:2] - exact[:2])
        for dt in (0.1, 0.01, 0.001)
    ]
    assert errors[0] > errors[1] > errors[2] > 0
    assert 5 < errors[0] / errors[1] < 20 and 5 < errors[1] / errors[2] < 20


def test_exact_step_straight_line_limit_is_continuous():
    near = exact_step(0.0, 0.0, 0.4, 0.03, 0.0, 1e-7, 0.1)
    straight = exact_step(0.0, 0.0, 0.4, 0.03, 0.0, 0.0, 0.1)
    np.testing.assert_allclose(near, straight, atol=1e-9)


def test_actions_and_slip_only_ever_slow_the_wheels():
    assert commanded_wheel_speeds(0, W) == (W, W)
    assert commanded_wheel_speeds(1, W) == (-W, -W)
    assert commanded_wheel_speeds(2, W) == (-W, W)
    assert commanded_wheel_speeds(3, W) == (W, -W)
    assert apply_slip(1.7, 0.5) == pytest.approx(1.2)
    assert apply_slip(-1.7, 0.5) == pytest.approx(-1.2)
    assert apply_slip(1.7, 3.0) == 0.0
    assert apply_slip(-1.7, 3.0) == 0.0


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("x_icr", 0.06, "x_icr"),
        ("wheel_radius", 0.0, "wheel_radius"),
        ("half_track", -1.0, "half_track"),
        ("substeps", 0, "substeps"),
        ("integrator", "rk4", "integrator"),
    ],
)
def test_robot_params_are_validated(field, value, message):
    with pytest.raises(ValueError, match=message):
        RobotParams(**{field: value})
