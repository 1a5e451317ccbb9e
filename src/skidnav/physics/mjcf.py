"""A skid-steer robot, its arena and its floor as an MJCF model (MuJoCo's XML format).

The robot (frame: x forward, y left, z up; its origin is the centre of mass, at wheel-axle
height): a box chassis of ``body_length`` × ``body_width`` × ``body_height`` and four wheels,
front axle at x = a, rear axle at x = −b, at y = ±c (:class:`~skidnav.robot.params.RobotParams`).
Each wheel is a sphere of radius r on a hinge about the body's y axis, driven by a velocity servo
(``<velocity>`` actuator: torque = k_v (ω_cmd − ω), clipped to the motor's limit), so the
commanded ω_L, ω_R are set points, as on a robot whose motor controller closes a speed loop.
A sphere touches the floor at one point: the cheapest wheel contact MuJoCo has, and with
``condim`` 6 its contact carries sliding, torsional and rolling friction.

The floor: one collision plane, and one flat box per slip region drawn in its material's
colour (drawn only). Each wheel's contact takes the wheel geom's friction (its ``priority`` is
higher than the plane's), which :class:`~skidnav.physics.mujoco_robot.PhysicsRobot` sets to the
material of the region under the wheel; walls are boxes over the occupancy map's wall cells,
drawn only: the navigation MDP's own collision rule (the centre entering a wall cell) decides
collisions, as in the kinematic simulator.

Assumed (not measured on the thesis robot; :class:`PhysicsParams`): the masses, the motor's
gain, torque limit and reflected inertia, and the timestep, which the convergence test of
``tests/physics/test_integration.py`` chose (docs/physics.md).

The same generator builds the Clearpath Jackal from its own numbers (:data:`JACKAL_PHYSICS`
with :data:`skidnav.robot.presets.JACKAL`): :func:`physics_for` picks the physics of a robot's
build.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from skidnav.physics.materials import MATERIALS, Material
from skidnav.robot.params import RobotParams
from skidnav.robot.presets import robot_preset_name

WHEELS = ("front_left", "rear_left", "front_right", "rear_right")
"""Wheel names, in actuator order: the two left wheels, then the two right ones."""


@dataclass(frozen=True)
class PhysicsParams:
    """What the physics needs beyond the kinematic geometry (assumptions, SI units).

    Attributes:
        body_mass: chassis mass [kg] (a small four-wheel platform with battery).
        wheel_mass: mass of one wheel [kg].
        body_height: chassis height [m] (drawn; the inertia of a box of this size).
        motor_gain: velocity-servo gain k_v [N·m·s/rad].
        motor_torque: motor torque limit per wheel [N·m] (a micro gear motor's stall torque).
        armature: reflected rotor inertia of motor and gearbox per wheel [kg·m²].
        timestep: physics timestep [s] (see the module docstring).
        body_width: chassis width [m] (drawn, and the inertia of the box); None: 1.5 c, the
            thesis robot's body between its wheels.
    """

    body_mass: float = 0.35
    wheel_mass: float = 0.02
    body_height: float = 0.03
    motor_gain: float = 0.5
    motor_torque: float = 0.02
    armature: float = 1e-4
    timestep: float = 0.002
    body_width: float | None = None

    def __post_init__(self) -> None:
        for name in ("body_mass", "wheel_mass", "body_height", "motor_gain", "motor_torque"):
            value = getattr(self, name)
            if not (isinstance(value, float | int) and np.isfinite(value) and value > 0):
                raise ValueError(f"expected {name} > 0, got {value}")
        if not (np.isfinite(self.armature) and self.armature >= 0):
            raise ValueError(f"expected armature >= 0, got {self.armature}")
        if not (np.isfinite(self.timestep) and 0 < self.timestep <= 0.01):
            raise ValueError(f"expected timestep in (0, 0.01] s, got {self.timestep}")
        if self.body_width is not None and not (
            np.isfinite(self.body_width) and self.body_width > 0
        ):
            raise ValueError(f"expected body_width > 0 m or None, got {self.body_width}")


JACKAL_PHYSICS = PhysicsParams(
    body_mass=17.0 - 4 * 0.5,
    wheel_mass=0.5,
    body_height=0.18,
    motor_gain=2.0,
    motor_torque=6.0,
    armature=5e-3,
    timestep=0.002,
    body_width=0.31,
)
"""The Jackal's physics: 17 kg in all (Clearpath), of which 0.5 kg per wheel (assumed), a
0.42 m × 0.31 m chassis (Clearpath) 0.18 m high (drawn; assumed), and motors assumed strong
enough for its published top speed and a brisk start: 6 N·m per wheel is 4 × 6 / 0.098 ≈ 245 N,
about 1.5 g on 17 kg, so on a grippy floor the tyres, not the motors, limit the acceleration; the
servo gain 2 N·m·s/rad tracks a set point within ~0.02 s (the wheel's share of the robot's
inertia over the gain)."""

PHYSICS_PRESETS = {"thesis": PhysicsParams(), "jackal": JACKAL_PHYSICS}
"""Robot preset (:data:`skidnav.robot.presets.ROBOT_PRESETS`) → its physics."""


def physics_for(robot: RobotParams) -> PhysicsParams:
    """The physics of ``robot``'s build (:func:`~skidnav.robot.presets.robot_preset_name`); the
    thesis robot's for a robot of another build."""
    return PHYSICS_PRESETS.get(robot_preset_name(robot) or "thesis", PhysicsParams())


def _numbers(*values: float) -> str:
    """Values as an MJCF attribute (``repr`` keeps every digit)."""
    return " ".join(repr(float(value)) for value in values)


def _wheels_xml(robot: RobotParams, physics: PhysicsParams) -> str:
    """The four wheel bodies (hinge, sphere geom)."""
    c, r = robot.half_track, robot.wheel_radius
    places = {
        "front_left": (robot.front_axle, c),
        "rear_left": (-robot.rear_axle, c),
        "front_right": (robot.front_axle, -c),
        "rear_right": (-robot.rear_axle, -c),
    }
    friction = MATERIALS["laminate"].friction
    return "".join(
        f'<body name="{name}" pos="{_numbers(x, y, 0.0)}">'
        f'<joint name="{name}" type="hinge" axis="0 1 0" armature="{physics.armature!r}"/>'
        f'<geom name="{name}" type="sphere" size="{r!r}" mass="{physics.wheel_mass!r}" '
        f'friction="{_numbers(*friction)}" condim="6" priority="1" rgba="0.1 0.1 0.1 1"/>'
        "</body>"
        for name, (x, y) in places.items()
    )


def level_box(index: int, extent: float, levels: int) -> tuple[float, float]:
    """(centre, half size) [m] along one axis of level ``index`` of ``levels`` over ``extent``,
    as :mod:`skidnav.world.discretization` cuts it: levels of extent/(levels − 1) from 0. The
    last level is the boundary line itself; it is drawn one level wide beyond it, as the 2-D
    renderer draws it."""
    size = extent / (levels - 1)
    return (index + 0.5) * size, size / 2


def _floor_xml(robot: RobotParams, materials: np.ndarray, drawn: bool) -> str:
    """The collision plane and, if ``drawn``, one drawn box per slip region."""
    width, height = robot.arena_width, robot.arena_height
    n_x, n_y = materials.shape
    tiles = []
    for i in range(n_x if drawn else 0):
        for j in range(n_y):
            rgba = MATERIALS[str(materials[i, j])].rgba
            (x, half_x), (y, half_y) = level_box(i, width, n_x), level_box(j, height, n_y)
            tiles.append(
                f'<geom name="region_{i}_{j}" type="box" contype="0" conaffinity="0" '
                f'size="{_numbers(half_x, half_y, 0.001)}" '
                f'pos="{_numbers(x, y, -0.001)}" rgba="{_numbers(*rgba)}"/>'
            )
    plane = (
        f'<geom name="floor" type="plane" pos="{_numbers(width / 2, height / 2, 0.0)}" '
        f'size="{_numbers(width, height, 0.1)}" rgba="0 0 0 0"/>'
    )
    return plane + "".join(tiles)


def _walls_xml(robot: RobotParams, occupancy: np.ndarray) -> str:
    """One drawn box per wall cell of ``occupancy`` (uint8 (n_x, n_y), 1 = wall), named
    ``wall_i_j``."""
    n_x, n_y = occupancy.shape
    boxes = []
    for i, j in np.argwhere(occupancy != 0):
        (x, half_x) = level_box(int(i), robot.arena_width, n_x)
        (y, half_y) = level_box(int(j), robot.arena_height, n_y)
        boxes.append(
            f'<geom name="wall_{i}_{j}" type="box" contype="0" conaffinity="0" '
            f'rgba="0.35 0.35 0.4 1" size="{_numbers(half_x, half_y, 0.02)}" '
            f'pos="{_numbers(x, y, 0.02)}"/>'
        )
    return "".join(boxes)


def arena_mjcf(
    robot: RobotParams,
    physics: PhysicsParams,
    materials: np.ndarray,
    occupancy: np.ndarray | None = None,
) -> str:
    """The MJCF document of the robot in its arena.

    Args:
        robot: geometry (r, c, a, b, body length, arena size).
        physics: masses, motors, timestep.
        materials: material name per slip region, shape (regions_x, regions_y) (names of
            :data:`~skidnav.physics.materials.MATERIALS`).
        occupancy: uint8 (n_x, n_y) wall map to draw, or None for a model that is not drawn.
            A drawn model has a box per wall cell and a coloured tile per slip region; none of
            them collides (the MDP stops the robot at walls), so the motion is the same bit for
            bit without them (tested), and each physics step costs ~30 % less: MuJoCo places
            and sweeps every geom at every step, and the 49 tiles were 49 of its 55 geoms.
    """
    unknown = sorted({str(name) for name in materials.ravel()} - set(MATERIALS))
    if unknown:
        raise ValueError(f"expected floor materials in {', '.join(MATERIALS)}, got {unknown[0]!r}")
    width = physics.body_width if physics.body_width is not None else robot.half_track * 1.5
    half = (robot.body_length / 2, width / 2, physics.body_height / 2)
    actuators = "".join(
        f'<velocity name="{name}" joint="{name}" kv="{physics.motor_gain!r}" '
        f'forcerange="{_numbers(-physics.motor_torque, physics.motor_torque)}"/>'
        for name in WHEELS
    )
    walls = "" if occupancy is None else _walls_xml(robot, occupancy)
    light = _numbers(robot.arena_width / 2, robot.arena_height / 2, 1.5)
    return (
        '<mujoco model="skidnav-skid-steer">'
        f'<option timestep="{physics.timestep!r}" integrator="implicitfast" cone="elliptic"/>'
        '<visual><global offwidth="640" offheight="480"/></visual>'
        "<worldbody>"
        f'<light pos="{light}" dir="0 0 -1"/>'
        + _floor_xml(robot, materials, drawn=occupancy is not None)
        + walls
        + f'<body name="chassis" pos="{_numbers(0.0, 0.0, robot.wheel_radius)}">'
        '<freejoint name="chassis"/>'
        f'<geom name="chassis" type="box" size="{_numbers(*half)}" mass="{physics.body_mass!r}" '
        'contype="0" conaffinity="0" rgba="0.85 0.3 0.15 1"/>'
        + _wheels_xml(robot, physics)
        + "</body></worldbody>"
        f"<actuator>{actuators}</actuator></mujoco>"
    )


def uniform_floor(name: str, regions: tuple[int, int] = (7, 7)) -> np.ndarray:
    """A floor of one material: ``name`` in every region (object array of ``regions``)."""
    if name not in MATERIALS:
        raise ValueError(f"expected a floor material in {', '.join(MATERIALS)}, got {name!r}")
    return np.full(regions, name, dtype=object)


__all__ = [
    "JACKAL_PHYSICS",
    "PHYSICS_PRESETS",
    "WHEELS",
    "Material",
    "PhysicsParams",
    "arena_mjcf",
    "physics_for",
    "uniform_floor",
]
