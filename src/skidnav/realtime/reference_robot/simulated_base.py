"""A robot without hardware: skid-steer kinematics in plain ``math``, so the reference robot runs
out of the box (and on a board before its motors are wired).

The body twist of wheel speeds ω_L, ω_R [rad/s] follows the instantaneous-centre-of-rotation
model: yaw rate ω = r (ω_R − ω_L) / (2c), forward speed v_x = r (ω_R + ω_L) / 2, lateral speed
v_y = −x_ICR · ω, with wheel radius r [m], half track c [m] and ICR offset x_ICR [m]. Between two
readings of the pose the twist is constant and the pose advances by the exact constant-twist
step (the closed-form integral of the rotating body velocity), so the result does not depend on
how often the pose is read. A new wheel speed counts from the previous reading of the pose.
"""

import math

from .interfaces import Robot


class SimulatedBase(Robot):
    """A skid-steer robot moving by its kinematics alone (see module doc).

    Args:
        x, y: the start position [m]. heading: the start heading [rad, counter-clockwise
            from +x].
        wheel_radius: r [m]. half_track: c [m]. x_icr: the ICR offset [m].
        wheel_limit: the largest wheel speed it accepts [rad/s].
    """

    def __init__(
        self,
        x: float = 0.3,
        y: float = 0.25,
        heading: float = 0.0,
        wheel_radius: float = 0.0225,
        half_track: float = 0.06,
        x_icr: float = 0.0,
        wheel_limit: float = 1.7,
    ) -> None:
        self.x, self.y, self.heading = x, y, heading
        self.wheel_radius, self.half_track, self.x_icr = wheel_radius, half_track, x_icr
        self.wheel_limit = wheel_limit
        self.wheels = (0.0, 0.0)  # (ω_L, ω_R) [rad/s]
        self._time: float | None = None  # when the pose was last advanced [s]

    def set_wheels(self, omega_left: float, omega_right: float) -> None:
        self.wheels = (omega_left, omega_right)

    def stop(self) -> None:
        self.wheels = (0.0, 0.0)

    def twist(self) -> tuple[float, float, float]:
        """The body twist of the current wheel speeds: (v_x [m/s], v_y [m/s], ω [rad/s])."""
        left, right = self.wheels
        r, c = self.wheel_radius, self.half_track
        omega = r * (right - left) / (2 * c)
        return r * (right + left) / 2, -self.x_icr * omega, omega

    def advance(self, duration: float) -> None:
        """Move for ``duration`` [s] with the current twist (the exact constant-twist step)."""
        v_x, v_y, omega = self.twist()
        turned = omega * duration
        if abs(turned) < 1e-12:
            forward, lateral = v_x * duration, v_y * duration
        else:
            forward = (v_x * math.sin(turned) + v_y * (math.cos(turned) - 1)) / omega
            lateral = (v_x * (1 - math.cos(turned)) + v_y * math.sin(turned)) / omega
        cos_h, sin_h = math.cos(self.heading), math.sin(self.heading)
        self.x += forward * cos_h - lateral * sin_h
        self.y += forward * sin_h + lateral * cos_h
        heading = self.heading + turned
        if not -math.pi < heading <= math.pi:
            heading = math.atan2(math.sin(heading), math.cos(heading))
        self.heading = heading

    def pose(self, now: float) -> tuple[float, float, float]:
        """The pose at ``now`` [s], advanced from the previous reading (see :class:`Robot`)."""
        if self._time is not None and now > self._time:
            self.advance(now - self._time)
        self._time = now
        return self.x, self.y, self.heading
