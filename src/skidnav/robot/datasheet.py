"""What a user knows about a robot before it drives: its datasheet, and how far a floor is from it.

A builder publishes a skid-steer robot's wheel radius r, its track 2c and its top wheel speed, and
the geometry that places the instantaneous centre of rotation (ICR) where a rigid body without slip
would turn (x_ICR; the thesis robot's table gives 5 cm). Nothing about the floor. Every learner
that models the robot's kinematics starts from this robot without slip — the prior of its
regression (:func:`skidnav.models.kinematic_regression.nominal_coefficients`), the controller's
model before its first fit — and learns the rest from driving.

A floor moves the truth away from the datasheet: wheels that lose part of their speed (η), a track
that behaves wider when the wheels scrub sideways (effective c), an ICR that moves (x_ICR). The
kinematic simulator's floors state this per region (:class:`~skidnav.robot.slip.SlipField`); the
MuJoCo robot's materials were fitted to it (:mod:`skidnav.robot.floors`). :func:`floor_gap` and
:func:`material_gap` say how far the truth is from the datasheet, as the ratios a user would
measure on the two actions that matter: the forward speed and the turn rate (truth over datasheet,
1 where the datasheet is right), and the ICR offset.

>>> gap = floor_gap("rough-physics")
>>> round(gap.forward, 2), round(gap.turn, 2), round(gap.x_icr * 1000)
(0.98, 0.51, 0)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from skidnav.robot.floors import calibrated_floor
from skidnav.robot.kinematics import ACTION_NAMES
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import make_slip_field

FORWARD, LEFT = ACTION_NAMES.index("forward"), ACTION_NAMES.index("left")
"""The actions whose twists the gap compares: full speed ahead, turning in place."""
GAP_WORLDS = 10
"""World seeds a floor's gap is averaged over (a slippery floor's patches are seeded)."""


@dataclass(frozen=True)
class Datasheet:
    """A robot as its datasheet gives it (SI units): the prior of every kinematic learner.

    Attributes:
        wheel_radius: r [m]. half_track: c, half the distance between the wheels [m].
        wheel_speed: the top wheel speed Ω the actions command [rad/s].
        x_icr: the ICR offset the geometry states [m] (0 where it states none).
    """

    wheel_radius: float
    half_track: float
    wheel_speed: float
    x_icr: float

    @classmethod
    def of(cls, robot: RobotParams) -> Datasheet:
        """The datasheet of a robot built as ``robot``: its geometry and top wheel speed, never
        its floor."""
        return cls(robot.wheel_radius, robot.half_track, robot.wheel_speed, robot.x_icr)

    def forward_speed(self) -> float:
        """v_x [m/s] of full speed ahead without slip: r Ω."""
        return self.wheel_radius * self.wheel_speed

    def turn_rate(self) -> float:
        """Yaw rate [rad/s] of turning in place without slip: r Ω / c."""
        return self.wheel_radius * self.wheel_speed / self.half_track


class PriorGap(NamedTuple):
    """How far a floor's truth is from the datasheet.

    Attributes:
        forward: true forward speed / the datasheet's (1: right).
        turn: true turn rate / the datasheet's.
        x_icr: the true ICR offset [m] (the datasheet's is :attr:`Datasheet.x_icr`).
    """

    forward: float
    turn: float
    x_icr: float


def floor_gap(preset: str, robot: RobotParams | None = None, worlds: int = GAP_WORLDS) -> PriorGap:
    """The gap of the kinematic simulator's slip preset ``preset`` for the robot ``robot`` (the
    thesis robot by default): the floor's expected twists of full speed ahead and of a turn in
    place (:meth:`~skidnav.robot.slip.SlipField.expected_velocities`), averaged over its regions
    and over the fields of world seeds 0 … ``worlds`` − 1, against the datasheet's."""
    robot = robot or RobotParams()
    sheet = Datasheet.of(robot)
    twists = np.array(
        [
            make_slip_field(preset, np.random.default_rng(seed), robot=robot)
            .expected_velocities(robot)
            .mean(axis=0)
            for seed in range(worlds)
        ]
    ).mean(axis=0)
    forward, turn = twists[FORWARD, 0], twists[LEFT, 2]
    return PriorGap(
        float(forward / sheet.forward_speed()),
        float(turn / sheet.turn_rate()),
        float(-twists[LEFT, 1] / turn),
    )


def material_gap(material: str, robot: RobotParams | None = None) -> PriorGap:
    """The gap of the MuJoCo robot on ``material``, from its calibration
    (:func:`~skidnav.robot.floors.calibrated_floor`: the ICR model fitted to the physical robot,
    whose fitted r already holds the mean wheel-speed loss) against the datasheet of ``robot``
    (the floors fitted on its build, :func:`~skidnav.robot.floors.calibrated_floors`)."""
    sheet = Datasheet.of(robot or RobotParams())
    fit = calibrated_floor(material, robot)
    return PriorGap(
        fit.wheel_radius / sheet.wheel_radius,
        (fit.wheel_radius / fit.half_track) / (sheet.wheel_radius / sheet.half_track),
        fit.x_icr,
    )
