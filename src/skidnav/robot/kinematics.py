"""Skid-steer kinematics as pure, compiled functions.

Instantaneous-centre-of-rotation model of Kozłowski & Pazderski (2004), "Modeling and control of
a 4-wheel skid-steering mobile robot", Int. J. Appl. Math. Comput. Sci. 14(4). With wheel angular
speeds ω_L, ω_R [rad/s], wheel radius r [m], half track c [m] and ICR offset x_ICR [m]:

    yaw_rate = r (ω_R − ω_L) / (2c)      [rad/s]
    v_x      = r (ω_R + ω_L) / 2         [m/s]   (body frame, forward)
    v_y      = −x_ICR · yaw_rate         [m/s]   (body frame, left; the skid)

World-frame rates: Ẋ = v_x cos ψ − v_y sin ψ, Ẏ = v_x sin ψ + v_y cos ψ, ψ̇ = yaw_rate.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from skidnav._jit import inline_jit, jit

N_ACTIONS = 4
"""Number of discrete actions: 0 forward, 1 backward, 2 turn left, 3 turn right."""

ACTION_NAMES = ("forward", "backward", "left", "right")


@inline_jit
def wrap_angle(angle: float) -> float:
    """``angle`` [rad] wrapped to [−π, π] (compiled and plain Python alike).

    >>> round(wrap_angle(3 * math.pi / 2), 6)
    -1.570796
    """
    return math.atan2(math.sin(angle), math.cos(angle))


@jit
def body_velocities(
    omega_left: float, omega_right: float, x_icr: float, wheel_radius: float, half_track: float
) -> tuple[float, float, float]:
    """Body-frame velocities of the ICR model.

    Args:
        omega_left, omega_right: wheel angular speeds [rad/s].
        x_icr: longitudinal ICR offset [m].
        wheel_radius: r [m]. half_track: c [m].

    Returns:
        (v_x [m/s], v_y [m/s], yaw_rate [rad/s]).

    >>> v_x, v_y, yaw_rate = body_velocities(1.7, 1.7, 0.05, 0.0225, 0.06)
    >>> round(v_x, 5), v_y, yaw_rate
    (0.03825, -0.0, 0.0)
    """
    yaw_rate = wheel_radius * (omega_right - omega_left) / (2.0 * half_track)
    v_x = wheel_radius * (omega_right + omega_left) / 2.0
    v_y = -x_icr * yaw_rate
    return v_x, v_y, yaw_rate


@jit
def euler_step(
    x: float, y: float, heading: float, v_x: float, v_y: float, yaw_rate: float, dt: float
) -> tuple[float, float, float]:
    """One explicit-Euler step of the world-frame pose (the thesis's scheme).

    Position advances with the heading at the start of the step; then the heading advances.

    Args:
        x, y: position [m]. heading: ψ [rad] (unwrapped).
        v_x, v_y: body-frame velocity [m/s]. yaw_rate: [rad/s]. dt: step [s].

    Returns:
        The new (x, y, heading), not clipped.
    """
    cos_h = math.cos(heading)
    sin_h = math.sin(heading)
    new_x = x + dt * (v_x * cos_h - v_y * sin_h)
    new_y = y + dt * (v_x * sin_h + v_y * cos_h)
    return new_x, new_y, heading + dt * yaw_rate


@jit
def exact_step(
    x: float, y: float, heading: float, v_x: float, v_y: float, yaw_rate: float, dt: float
) -> tuple[float, float, float]:
    """The exact pose after ``dt`` of constant body twist (v_x, v_y, yaw_rate).

    Integrates the world-frame rates in closed form: with Δψ = yaw_rate·dt,
    the body-frame displacement is (v_x S − v_y C, v_x C + v_y S)·dt with
    S = sin Δψ / Δψ and C = (1 − cos Δψ)/Δψ, rotated by the initial heading. For |Δψ| < 1e-9 it
    falls back to the straight-line limit (S = 1, C = 0).

    Args and returns as :func:`euler_step`.
    """
    turn = yaw_rate * dt
    if abs(turn) < 1e-9:
        sinc = 1.0
        cosc = 0.0
    else:
        sinc = math.sin(turn) / turn
        cosc = (1.0 - math.cos(turn)) / turn
    forward = (v_x * sinc - v_y * cosc) * dt
    lateral = (v_x * cosc + v_y * sinc) * dt
    cos_h = math.cos(heading)
    sin_h = math.sin(heading)
    new_x = x + forward * cos_h - lateral * sin_h
    new_y = y + forward * sin_h + lateral * cos_h
    return new_x, new_y, heading + turn


@jit
def pose_step(
    x: float,
    y: float,
    heading: float,
    v_x: float,
    v_y: float,
    yaw_rate: float,
    dt: float,
    exact: bool,
) -> tuple[float, float, float]:
    """One step of the robot's integrator: :func:`exact_step` if ``exact``, else
    :func:`euler_step` (``RobotParams.integrator``). Args and returns as :func:`euler_step`.

    >>> pose_step(0.0, 0.0, 0.0, 0.1, 0.0, 0.0, 0.5, False)
    (0.05, 0.0, 0.0)
    """
    if exact:
        return exact_step(x, y, heading, v_x, v_y, yaw_rate, dt)
    return euler_step(x, y, heading, v_x, v_y, yaw_rate, dt)


@jit
def commanded_wheel_speeds(action: int, wheel_speed: float) -> tuple[float, float]:
    """Nominal (ω_L, ω_R) [rad/s] of a discrete action, before slip.

    0 forward (+, +), 1 backward (−, −), 2 turn left (−, +), 3 turn right (+, −).

    >>> commanded_wheel_speeds(2, 1.7)
    (-1.7, 1.7)
    """
    if action == 0:
        return wheel_speed, wheel_speed
    if action == 1:
        return -wheel_speed, -wheel_speed
    if action == 2:
        return -wheel_speed, wheel_speed
    return wheel_speed, -wheel_speed


@jit
def apply_slip(commanded: float, loss: float) -> float:
    """Reduce the magnitude of a commanded wheel speed by ``loss`` ≥ 0 [rad/s], never past zero.

    The thesis's slip only ever slows a wheel: +ω becomes ω − loss and −ω becomes −ω + loss.
    """
    if commanded >= 0.0:
        return max(commanded - loss, 0.0)
    return min(commanded + loss, 0.0)


@jit
def expected_slipped_speed(commanded: float, eta: float) -> float:
    """Expected wheel speed [rad/s] of :func:`apply_slip` with a loss drawn from U(0, η), η ≥ 0
    [rad/s] (the thesis's slip): |ω| − η/2 while η ≤ |ω|, ω²/(2η) beyond (the loss cannot
    reverse the wheel), with the sign of ``commanded``.

    >>> expected_slipped_speed(1.7, 0.3), expected_slipped_speed(-1.0, 4.0)
    (1.55, -0.125)
    """
    magnitude = abs(commanded)
    mean = magnitude - eta / 2.0 if eta <= magnitude else magnitude * magnitude / (2.0 * eta)
    return mean if commanded >= 0.0 else -mean


@jit
def expected_body_velocities(
    omega_left: float,
    omega_right: float,
    eta: float,
    x_icr: float,
    wheel_radius: float,
    half_track: float,
) -> tuple[float, float, float]:
    """Expected body velocities of commanded wheel speeds on a floor that slows each wheel by an
    independent U(0, η) [rad/s]: the ICR model is linear in the wheel speeds, so its expectation
    is :func:`body_velocities` of the :func:`expected_slipped_speed` of each wheel.

    Args:
        omega_left, omega_right: commanded wheel speeds [rad/s]. eta: loss scale η [rad/s].
        x_icr, wheel_radius, half_track: the floor's ICR offset, r and c [m].

    Returns:
        (v_x [m/s], v_y [m/s], yaw_rate [rad/s]).
    """
    return body_velocities(
        expected_slipped_speed(omega_left, eta), expected_slipped_speed(omega_right, eta),
        x_icr, wheel_radius, half_track,
    )  # fmt: skip


def real_values(action: Any) -> np.ndarray | None:
    """``action`` as a float64 array, or None unless it holds real numbers: a complex number
    (whose imaginary part a cast would drop), a string, or a ragged or non-numeric sequence
    gives None.

    >>> real_values([1.7, -1]), real_values(np.array([1.7 + 0j, 1.0])), real_values("17")
    (array([ 1.7, -1. ]), None, None)
    """
    try:
        values = np.asarray(action)
        if values.dtype.kind not in "biufO":
            return None
        return values.astype(np.float64, copy=False)
    except (TypeError, ValueError):  # ragged, or an object that is not a real number
        return None


def clipped_wheel_speeds(action: Any, limit: float) -> tuple[float, float]:
    """A continuous action (ω_L, ω_R) [rad/s] as two floats clipped to ± ``limit``; ValueError
    unless it holds two finite real numbers."""
    values = real_values(action)
    if values is None:
        raise ValueError(f"expected an action of two wheel speeds, got {action!r}")
    if values.shape != (2,) or not np.isfinite(values).all():
        raise ValueError(f"expected an action of two finite wheel speeds, got {action!r}")
    left, right = values.tolist()
    return min(max(left, -limit), limit), min(max(right, -limit), limit)
