"""Floors calibrated on the physical robot: the ICR model fitted per material.

``skidnav world floors calibrate --out src/skidnav/data/floors.json`` drives the MuJoCo robot
(:mod:`skidnav.physics.calibration`, docs/physics.md) over each floor material and writes, per
material, the effective wheel radius r, half track c and x_ICR of the ICR model that fits it, and
the η of the U(0, η) wheel-speed loss with the same residual v_x variance. The package ships that
file (60 s per material, seed 0, the thesis robot of :class:`RobotParams`); the tests calibrate
again and compare. This module reads it without MuJoCo, so the fast simulator's
``rough-physics`` and ``slippery-physics`` presets (:func:`skidnav.robot.slip.make_slip_field`)
are built from it on any machine.

Which material covers which region of a preset (:data:`PRESET_FLOORS`), for the MuJoCo floor and
for the calibrated presets alike: ``thesis`` laminate; ``rough`` rubber mat; ``slippery``
laminate with wet-tile patches (the preset's seeded patches of lost wheel speed).
"""

from __future__ import annotations

import json
import math
from functools import cache
from importlib import resources
from typing import NamedTuple

from skidnav.robot.params import RobotParams

FLOORS_FILE = ("data", "floors.json")
"""The calibration file inside the ``skidnav`` package."""

CALIBRATED_PRESETS = {"rough-physics": "rough", "slippery-physics": "slippery"}
"""The slip presets whose regions take the calibrated floor of their material → the hand-set
preset whose materials (and patches) they have."""

PRESET_FLOORS: dict[str, tuple[str, str | None]] = {
    "thesis": ("laminate", None),
    "rough": ("rubber-mat", None),
    "slippery": ("laminate", "wet-tile"),
}
PRESET_FLOORS.update({name: PRESET_FLOORS[base] for name, base in CALIBRATED_PRESETS.items()})
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

    def scales(self, robot: RobotParams | None = None) -> tuple[float, float]:
        """The fast simulator's (r, c) on this floor relative to the calibrated robot's
        geometric ones (the thesis robot), chosen so that an action's mean twist is the fit's.

        The simulator slows each wheel by U(0, η), on average η/2, and the fit's r already
        holds the mean loss; so r is raised by ω/(ω − η/2) at the actions' wheel speed ω: a
        forward action then moves r_fit·ω on average and a turn yaws r_fit·ω/c_fit (c is the
        fit's, both wheels losing alike).
        """
        robot = robot or RobotParams()
        speed = robot.wheel_speed
        radius = self.wheel_radius * speed / (speed - self.eta / 2.0)
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


@cache
def calibrated_floors() -> dict[str, CalibratedFloor]:
    """The package's calibrated floors by material name (read once)."""
    path = resources.files("skidnav").joinpath(*FLOORS_FILE)
    try:
        return parse_floors(path.read_text(encoding="utf-8"))
    except ValueError as error:
        raise ValueError(f"skidnav/{'/'.join(FLOORS_FILE)}: {error}") from None


def calibrated_floor(material: str) -> CalibratedFloor:
    """The calibrated floor of ``material``; ValueError if it was not calibrated."""
    floors = calibrated_floors()
    if material not in floors:
        raise ValueError(f"expected a calibrated material in {', '.join(floors)}, got {material!r}")
    return floors[material]
