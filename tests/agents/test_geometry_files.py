"""A saved agent's robot: the footprint round-trips, and files saved before it load."""

from __future__ import annotations

import pytest

from skidnav.agents.geometry import geometry_from_json, geometry_json
from skidnav.robot.params import RobotParams
from skidnav.robot.presets import JACKAL
from skidnav.world.discretization import Discretization


def test_the_jackals_footprint_round_trips():
    robot, grid = geometry_from_json(geometry_json(JACKAL, Discretization()))
    assert robot == JACKAL and grid == Discretization()


def test_a_robot_saved_before_footprints_loads_as_a_point():
    saved = geometry_json(RobotParams(), None)
    for key in ("footprint_length", "footprint_width"):
        del saved["robot"][key]
    robot, _ = geometry_from_json(saved)
    assert robot == RobotParams() and not robot.has_footprint


def test_any_other_missing_or_extra_field_is_refused():
    saved = geometry_json(RobotParams(), None)
    del saved["robot"]["wheel_radius"]
    with pytest.raises(ValueError, match="expected the robot fields"):
        geometry_from_json(saved)
    saved = geometry_json(RobotParams(), None)
    saved["robot"]["colour"] = "red"
    with pytest.raises(ValueError, match="expected the robot fields"):
        geometry_from_json(saved)
