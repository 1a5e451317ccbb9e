"""The skid-steer robot: physical parameters, kinematics and slip fields (no Gymnasium here)."""

from skidnav.robot.kinematics import (
    ACTION_NAMES,
    N_ACTIONS,
    body_velocities,
    commanded_wheel_speeds,
    euler_step,
    exact_step,
    pose_step,
)
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SLIP_PRESETS, SlipField, make_slip_field

__all__ = [
    "ACTION_NAMES",
    "N_ACTIONS",
    "SLIP_PRESETS",
    "RobotParams",
    "SlipField",
    "body_velocities",
    "commanded_wheel_speeds",
    "euler_step",
    "exact_step",
    "make_slip_field",
    "pose_step",
]
