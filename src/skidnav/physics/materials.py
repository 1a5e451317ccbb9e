"""Floor materials of the physical robot, and which material covers each slip region.

A material is the friction of the rubber wheel on that floor, as MuJoCo's three coefficients of
a contact (MuJoCo documentation, "Contact" → friction): sliding μ (dimensionless), torsional
[m] (the spin torque per newton of normal force) and rolling [m] (the rolling-resistance torque
per newton). Values (typical figures, not measurements of the thesis arena):

- ``rubber-mat``: μ = 1.0. Rubber on rubber is the grippiest pair of the usual tables (The
  Engineering ToolBox, "Friction and friction coefficients": rubber–rubber ≈ 1.16; rubber on dry
  concrete 0.6–0.85). A soft mat resists rolling more: rolling 5·10⁻⁴ m, i.e. a rolling-resistance
  coefficient C_rr ≈ 0.02 for the 2.25 cm wheel (C_rr ≈ rolling / r).
- ``laminate``: μ = 0.5, a dry laminate floor; EN 13893 asks ≥ 0.30 of a dry floor covering.
  Torsional 0.005 m is MuJoCo's default; rolling 2·10⁻⁴ m (C_rr ≈ 0.01, a small hard-rubber
  wheel on a hard floor).
- ``wet-tile``: μ = 0.2, wet glazed ceramic tile, a floor that fails ANSI A326.3's wet dynamic
  coefficient of friction of 0.42 for level interior floors; torsional and rolling scaled down
  with μ.
- ``ice``: μ = 0.05, of the order of rubber on wet ice (friction tables give a few hundredths
  up to about 0.1 for tyres on ice); torsional and rolling scaled down with μ. A floor where
  the wheels spin and skid: the "BARN on ice" of ``ice-physics`` (:mod:`skidnav.robot.floors`).

Which region gets which material (:func:`region_materials`) follows the slip presets of
:mod:`skidnav.robot.slip`: ``thesis`` laminate everywhere, ``rough`` rubber mat everywhere,
``slippery`` laminate with wet-tile patches where the preset's η is the full wheel speed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from skidnav.robot.floors import (
    CALIBRATED_PRESETS,
    PRESET_FLOORS,
    calibrated_floor,
    calibrated_robot,
)
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SlipField


@dataclass(frozen=True)
class Material:
    """Friction of the wheels on one floor (MuJoCo's contact coefficients).

    Attributes:
        name: the material's name.
        sliding: sliding friction μ (dimensionless), > 0.
        torsional: torsional friction [m], ≥ 0.
        rolling: rolling friction [m], ≥ 0.
        rgba: colour drawn for the floor (red, green, blue, alpha in [0, 1]).
    """

    name: str
    sliding: float
    torsional: float
    rolling: float
    rgba: tuple[float, float, float, float]

    def __post_init__(self) -> None:
        if not self.sliding > 0:
            raise ValueError(f"expected sliding friction > 0, got {self.sliding}")
        if not (self.torsional >= 0 and self.rolling >= 0):
            raise ValueError(
                f"expected torsional and rolling friction >= 0, got {self.torsional}, "
                f"{self.rolling}"
            )

    @property
    def friction(self) -> tuple[float, float, float]:
        """(sliding, torsional, rolling), MuJoCo's ``friction`` attribute order."""
        return (self.sliding, self.torsional, self.rolling)


MATERIALS: dict[str, Material] = {
    material.name: material
    for material in (
        Material("rubber-mat", 1.0, 0.01, 5e-4, (0.25, 0.25, 0.28, 1.0)),
        Material("laminate", 0.5, 0.005, 2e-4, (0.72, 0.58, 0.40, 1.0)),
        Material("wet-tile", 0.2, 0.002, 1e-4, (0.62, 0.78, 0.86, 1.0)),
        Material("ice", 0.05, 0.0005, 2.5e-5, (0.88, 0.94, 0.98, 1.0)),
    )
}
"""The named materials (see the module docstring for values and sources)."""

PATCH_MATERIAL = str(PRESET_FLOORS["slippery"][1])
"""The material of the slippery floor's patches (:data:`skidnav.robot.floors.PRESET_FLOORS`)."""


def material(name: str) -> Material:
    """The material called ``name``.

    >>> material("wet-tile").sliding
    0.2
    """
    try:
        return MATERIALS[name]
    except KeyError:
        raise ValueError(
            f"expected a floor material in {', '.join(MATERIALS)}, got {name!r}"
        ) from None


def region_materials(preset: str, field: SlipField, robot: RobotParams | None = None) -> np.ndarray:
    """Material name of each slip region, object array of shape ``field.shape``.

    The field's own materials when it names them (the calibrated presets); otherwise the
    preset's floor (:data:`~skidnav.robot.floors.PRESET_FLOORS`), with its patch material on the
    patches: the regions whose η reaches the robot's wheel speed (``slippery``) or, for a
    calibrated preset's field rebuilt from its η alone (a saved run), equals the patch
    material's calibrated η.
    """
    if field.materials is not None:
        return np.array(field.materials, dtype=object)
    if preset not in PRESET_FLOORS:
        raise ValueError(f"expected a slip preset in {', '.join(PRESET_FLOORS)}, got {preset!r}")
    floor, patch = PRESET_FLOORS[preset]
    names = np.full(field.shape, floor, dtype=object)
    if patch is not None and preset in CALIBRATED_PRESETS:
        fit = calibrated_floor(patch, robot)
        names[field.eta == fit.simulated_eta(calibrated_robot(robot))] = patch
    elif patch is not None:
        names[field.eta >= (robot or RobotParams()).wheel_speed] = patch
    return names
