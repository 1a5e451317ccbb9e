"""Named robots: the thesis robot and a Clearpath Jackal, selectable by name.

``thesis``: :class:`~skidnav.robot.params.RobotParams`'s defaults (Alhawary (2020), App. A.1.1).

``jackal``: the Clearpath Jackal UGV, the robot of the BARN benchmark (Perille et al. (2020);
:mod:`skidnav.world.barn`), from Clearpath's published specifications: wheel radius 0.098 m, track
0.37559 m (half track c = 0.187795 m), wheelbase 0.262 m (axles at ±0.131 m from the centre),
chassis 0.42 m × 0.31 m, 17 kg, top speed 2.0 m/s, so a top wheel speed of 2.0 / 0.098 ≈ 20.41
rad/s. It collides by its footprint (:data:`JACKAL_FOOTPRINT`, :mod:`skidnav.sim.footprint`), the
thesis robot by its centre. The centre of mass is taken at the geometric centre, so the datasheet's
ICR offset is 0 (Kozłowski & Pazderski (2004)). Its arena is a converted BARN world's (4.5 m × 15
m); its actions integrate with the exact constant-twist step, as one 1-s action at 2 m/s covers 13
cells of 0.15 m.
"""

from __future__ import annotations

from skidnav.robot.params import RobotParams

JACKAL_TOP_SPEED = 2.0
"""The Jackal's top speed [m/s]."""
JACKAL_WHEEL_WIDTH = 0.04
"""Width of a Jackal wheel [m] (Clearpath's published description)."""
JACKAL_FOOTPRINT = (0.262 + 2 * 0.098, 0.37559 + JACKAL_WHEEL_WIDTH)
"""The rectangle the Jackal occupies [m]: along the heading, the wheelbase plus a wheel's
diameter (0.458; the wheels reach beyond the 0.42 m chassis); across, the track plus a wheel's
width (0.416; beyond the 0.31 m chassis). The envelope of chassis and wheels, which is what
meets an obstacle."""

JACKAL = RobotParams(
    wheel_radius=0.098,
    half_track=0.37559 / 2,
    front_axle=0.262 / 2,
    rear_axle=0.262 / 2,
    x_icr=0.0,
    body_length=0.42,
    wheel_speed=JACKAL_TOP_SPEED / 0.098,
    arena_width=4.5,
    arena_height=15.0,
    integrator="exact",
    footprint_length=JACKAL_FOOTPRINT[0],
    footprint_width=JACKAL_FOOTPRINT[1],
)
"""The Clearpath Jackal (see the module docstring)."""

ROBOT_PRESETS: dict[str, RobotParams] = {"thesis": RobotParams(), "jackal": JACKAL}
"""Robot name → its parameters."""

GEOMETRY = ("wheel_radius", "half_track", "front_axle", "rear_axle", "body_length")
"""The fields that make a robot's body: two robots with the same are the same build."""


def robot_preset(name: str) -> RobotParams:
    """The robot called ``name`` (:data:`ROBOT_PRESETS`).

    >>> round(robot_preset("jackal").wheel_speed * robot_preset("jackal").wheel_radius, 12)
    2.0
    """
    if name not in ROBOT_PRESETS:
        raise ValueError(f"expected a robot in {', '.join(ROBOT_PRESETS)}, got {name!r}")
    return ROBOT_PRESETS[name]


def robot_preset_name(robot: RobotParams) -> str | None:
    """The name of the preset whose body (:data:`GEOMETRY`) ``robot`` has, whatever its timing,
    arena or integrator; None for a robot of another build.

    >>> robot_preset_name(RobotParams(integrator="exact"))
    'thesis'
    >>> print(robot_preset_name(RobotParams(wheel_radius=1.0)))
    None
    """
    for name, preset in ROBOT_PRESETS.items():
        if all(getattr(robot, key) == getattr(preset, key) for key in GEOMETRY):
            return name
    return None
