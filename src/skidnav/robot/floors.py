"""Floors calibrated on the physical robot: the ICR model fitted per material.

``skidnav world floors calibrate --out src/skidnav/data/floors.json`` drives the MuJoCo robot
(:mod:`skidnav.physics.calibration`, docs/physics.md) over each floor material and writes, per
material, the effective wheel radius r, half track c and x_ICR of the ICR model that fits it, and
the η of the U(0, η) wheel-speed loss with the same residual v_x variance. The package ships that
file (60 s per material, seed 0, the thesis robot of :class:`RobotParams`), and the Jackal's
(``--robot jackal``, :data:`FLOORS_FILES`); the tests calibrate again and compare. A robot of
another build takes the thesis robot's floors. This module reads them without MuJoCo, so the
fast simulator's calibrated presets (``rough-physics``, ``slippery-physics``, ``ice-physics``;
:func:`skidnav.robot.slip.make_slip_field`) are built from them on any machine.

Which material covers which region of a preset (:data:`PRESET_FLOORS`), for the MuJoCo floor and
for the calibrated presets alike: ``thesis`` laminate; ``rough`` and ``nominal`` rubber mat;
``slippery`` laminate with wet-tile patches (the preset's seeded patches of lost wheel speed);
``ice-physics`` ice everywhere (it has no hand-set twin).
"""

from __future__ import annotations

import json
import math
from functools import cache
from importlib import resources
from typing import NamedTuple

from skidnav.robot.params import RobotParams
from skidnav.robot.presets import robot_preset, robot_preset_name

FLOORS_FILE = ("data", "floors.json")
"""The thesis robot's calibration file inside the ``skidnav`` package."""
FLOORS_FILES = {"thesis": FLOORS_FILE, "jackal": ("data", "floors-jackal.json")}
"""Robot preset → its calibration file inside the package."""

CALIBRATED_PRESETS: dict[str, str | None] = {
    "rough-physics": "rough",
    "slippery-physics": "slippery",
    "ice-physics": None,
}
"""The slip presets whose regions take the calibrated floor of their material → the hand-set
preset whose materials (and patches) they have, None for one without a hand-set twin."""

PRESET_FLOORS: dict[str, tuple[str, str | None]] = {
    "thesis": ("laminate", None),
    "rough": ("rubber-mat", None),
    "slippery": ("laminate", "wet-tile"),
    "nominal": ("rubber-mat", None),
    "ice-physics": ("ice", None),
}
PRESET_FLOORS.update(
    {name: PRESET_FLOORS[base] for name, base in CALIBRATED_PRESETS.items() if base is not None}
)
"""Slip preset → (material of the floor, material of its patches or None); a calibrated preset
has its hand-set preset's."""


class CalibratedFloor(NamedTuple):
    """The ICR model fitted on one material (SI units).

    Attributes:
        wheel_radius: effective wheel radius r [m]. half_track: effective half track c [m].
        x_icr: ICR offset [m]. eta: wheel-speed loss scale η [rad/s] of the same v_x variance.
    """

    wheel_radius: float
    half_track: float
    x_icr: float
    eta: float

    def simulated_eta(self, robot: RobotParams | None = None) -> float:
        """The fast simulator's η [rad/s] on this floor: the fit's, at most the actions' wheel
        speed of ``robot`` (the calibrated robot, the thesis robot by default). A loss of
        U(0, η) with η above the wheel speed would stop a wheel more often than not; a floor
        noisier than that (the Jackal's, whose 17 kg lag 1-s commands, most on ice) keeps the
        fit's mean twist and the simulator's largest noise."""
        return min(self.eta, (robot or RobotParams()).wheel_speed)

    def scales(self, robot: RobotParams | None = None) -> tuple[float, float]:
        """The fast simulator's (r, c) on this floor relative to the geometric ones of
        ``robot``, the calibrated robot (the thesis robot by default), chosen so that an
        action's mean twist is the fit's.

        The simulator slows each wheel by U(0, η), on average η/2, and the fit's r already
        holds the mean loss; so r is raised by ω/(ω − η/2) at the actions' wheel speed ω: a
        forward action then moves r_fit·ω on average and a turn yaws r_fit·ω/c_fit (c is the
        fit's, both wheels losing alike). η is :meth:`simulated_eta`'s.
        """
        robot = robot or RobotParams()
        speed = robot.wheel_speed
        radius = self.wheel_radius * speed / (speed - self.simulated_eta(robot) / 2.0)
        return radius / robot.wheel_radius, self.half_track / robot.half_track


def parse_floors(text: str) -> dict[str, CalibratedFloor]:
    """The floors of a ``skidnav world floors calibrate --out`` document; ValueError naming the
    first problem (not JSON, a missing or non-finite field, r or c not > 0, a material twice)."""
    try:
        document = json.loads(text)
        fits = document["fits"]
        floors: dict[str, CalibratedFloor] = {}
        for fit in fits:
            name = str(fit["material"])
            values = [float(fit[key]) for key in CalibratedFloor._fields]
            floor = CalibratedFloor(*values)
            if not all(math.isfinite(v) for v in values) or min(floor[:2]) <= 0 or floor.eta < 0:
                raise ValueError(f"{name}: expected finite r, c > 0 and eta >= 0")
            if name in floors:
                raise ValueError(f"{name}: calibrated twice")
            floors[name] = floor
    except (KeyError, TypeError) as error:
        raise ValueError(f"expected a floors calibration document, missing {error}") from None
    return floors


def calibration_robot(robot: RobotParams | None = None) -> str:
    """The preset whose calibration file serves ``robot``: its own build's if one was
    calibrated, else the thesis robot's."""
    name = robot_preset_name(robot) if robot is not None else None
    return name if name in FLOORS_FILES else "thesis"


@cache
def _floors_of(name: str) -> dict[str, CalibratedFloor]:
    path = resources.files("skidnav").joinpath(*FLOORS_FILES[name])
    try:
        return parse_floors(path.read_text(encoding="utf-8"))
    except ValueError as error:
        raise ValueError(f"skidnav/{'/'.join(FLOORS_FILES[name])}: {error}") from None


def calibrated_floors(robot: RobotParams | None = None) -> dict[str, CalibratedFloor]:
    """The package's calibrated floors by material name for ``robot`` (the thesis robot by
    default; :func:`calibration_robot`), each file read once."""
    return _floors_of(calibration_robot(robot))


def calibrated_floor(material: str, robot: RobotParams | None = None) -> CalibratedFloor:
    """The calibrated floor of ``material`` for ``robot``; ValueError if it was not
    calibrated."""
    floors = calibrated_floors(robot)
    if material not in floors:
        raise ValueError(f"expected a calibrated material in {', '.join(floors)}, got {material!r}")
    return floors[material]


def calibrated_robot(robot: RobotParams | None = None) -> RobotParams:
    """The robot whose geometry the floors of ``robot`` were fitted on
    (:meth:`CalibratedFloor.scales` is relative to it)."""
    return robot_preset(calibration_robot(robot))
