"""Physical parameters of the skid-steer robot and its arena.

Defaults are the thesis robot (Alhawary (2020), App. A.1.1; docs/simulator.md): a small
four-wheel skid-steer platform in a 0.62 m × 0.505 m arena, driven by four discrete wheel-speed
actions of ±1.7 rad/s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple


class KinematicConstants(NamedTuple):
    """The scalars the compiled kernels need, as a numba-friendly named tuple (SI units)."""

    wheel_radius: float
    half_track: float
    wheel_speed: float
    dt: float
    substeps: int
    arena_width: float
    arena_height: float
    exact_integration: bool
    footprint_length: float
    footprint_width: float


@dataclass(frozen=True)
class RobotParams:
    """Geometry and timing of the robot, validated on construction.

    Attributes:
        wheel_radius: r, wheel radius [m].
        half_track: c, half the distance between left and right wheels [m].
        front_axle: a, centre of mass to front axle [m].
        rear_axle: b, centre of mass to rear axle [m].
        x_icr: nominal longitudinal offset of the instantaneous centre of rotation [m]; must lie
            in [-front_axle, rear_axle] (Kozłowski & Pazderski 2004). Slip fields may override it
            per region.
        body_length: drawn length of the body [m].
        wheel_speed: magnitude of the wheel angular speed of every action [rad/s].
        dt: one integration sub-step [s].
        substeps: sub-steps per action; one action lasts ``dt * substeps`` seconds.
        arena_width: arena extent along x [m]; poses are clipped to [0, arena_width].
        arena_height: arena extent along y [m]; poses are clipped to [0, arena_height].
        integrator: ``"euler"`` (explicit Euler, as the thesis) or ``"exact"`` (closed-form
            constant-twist step).
        footprint_length, footprint_width: the rectangle the robot occupies [m], along and across
            its heading, centred on its position; both 0 (the default, the thesis robot) for a
            point robot, which collides when its position enters a wall cell. With a footprint
            it collides when the rectangle touches a wall cell's inscribed disc
            (:mod:`skidnav.sim.footprint`).

    >>> RobotParams().action_duration
    1.0
    >>> RobotParams(x_icr=0.2)
    Traceback (most recent call last):
    ...
    ValueError: expected x_icr in [-0.05, 0.05] m, got 0.2
    """

    wheel_radius: float = 0.0225
    half_track: float = 0.06
    front_axle: float = 0.05
    rear_axle: float = 0.05
    x_icr: float = 0.05
    body_length: float = 0.10
    wheel_speed: float = 1.7
    dt: float = 0.1
    substeps: int = 10
    arena_width: float = 0.62
    arena_height: float = 0.505
    integrator: str = "euler"
    footprint_length: float = 0.0
    footprint_width: float = 0.0

    def __post_init__(self) -> None:
        positive = {
            "wheel_radius": self.wheel_radius,
            "half_track": self.half_track,
            "body_length": self.body_length,
            "wheel_speed": self.wheel_speed,
            "dt": self.dt,
            "arena_width": self.arena_width,
            "arena_height": self.arena_height,
        }
        for name, value in positive.items():
            if not value > 0:
                raise ValueError(f"expected {name} > 0, got {value}")
        for name, value in {"front_axle": self.front_axle, "rear_axle": self.rear_axle}.items():
            if not value >= 0:
                raise ValueError(f"expected {name} >= 0, got {value}")
        if not -self.front_axle <= self.x_icr <= self.rear_axle:
            raise ValueError(
                f"expected x_icr in [{-self.front_axle}, {self.rear_axle}] m, got {self.x_icr}"
            )
        if not (isinstance(self.substeps, int) and self.substeps >= 1):
            raise ValueError(f"expected substeps to be an integer >= 1, got {self.substeps!r}")
        self._check_footprint()
        if self.integrator not in ("euler", "exact"):
            raise ValueError(f"expected integrator 'euler' or 'exact', got {self.integrator!r}")

    def _check_footprint(self) -> None:
        """ValueError unless the footprint is a point (both 0) or a rectangle (both > 0)."""
        size = (self.footprint_length, self.footprint_width)
        if not (size == (0.0, 0.0) or all(math.isfinite(v) and v > 0 for v in size)):
            raise ValueError(
                f"expected footprint_length and footprint_width both 0 (a point robot) or both "
                f"> 0 m, got {size[0]} and {size[1]}"
            )

    @property
    def has_footprint(self) -> bool:
        """True when the robot collides by its rectangle rather than its position."""
        return self.footprint_length > 0.0

    @property
    def action_duration(self) -> float:
        """Duration of one action [s]."""
        return self.dt * self.substeps

    @property
    def exact_integration(self) -> bool:
        """True for the closed-form constant-twist step, False for explicit Euler."""
        return self.integrator == "exact"

    def kernel_constants(self) -> KinematicConstants:
        """The parameters as the named tuple the compiled kernels take."""
        return KinematicConstants(
            wheel_radius=float(self.wheel_radius),
            half_track=float(self.half_track),
            wheel_speed=float(self.wheel_speed),
            dt=float(self.dt),
            substeps=int(self.substeps),
            arena_width=float(self.arena_width),
            arena_height=float(self.arena_height),
            exact_integration=self.exact_integration,
            footprint_length=float(self.footprint_length),
            footprint_width=float(self.footprint_width),
        )
