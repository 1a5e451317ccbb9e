"""The shipped floor calibration against a new one, and the calibrated presets against physics."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco")

from skidnav.physics.calibration import calibrate
from skidnav.physics.materials import MATERIALS, region_materials
from skidnav.physics.mjcf import PhysicsParams, uniform_floor
from skidnav.physics.mujoco_robot import PhysicsRobot
from skidnav.robot.floors import PRESET_FLOORS, calibrated_floors
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SlipField, make_slip_field
from skidnav.sim.task import build_task, drive_substep
from skidnav.world.discretization import Discretization
from skidnav.world.grid import generate_map

ROBOT = RobotParams()


def test_the_shipped_floors_are_those_a_new_calibration_gives() -> None:
    """``src/skidnav/data/floors.json`` is ``skidnav world floors calibrate`` (60 s, seed 0) as the
    physics model stands: recalibrate after changing a material or the robot model."""
    shipped = calibrated_floors()
    fits = calibrate(list(MATERIALS), np.random.default_rng(0), segments=60)
    assert sorted(shipped) == sorted(MATERIALS)
    for fit in fits:
        new = (fit.wheel_radius, fit.half_track, fit.x_icr, fit.eta)
        assert tuple(shipped[fit.material]) == pytest.approx(new, rel=1e-6, abs=1e-9)


def _physics_turn(material: str) -> float:
    """Heading change [rad] of the MuJoCo robot turning left in place for 1 s on ``material``."""
    robot = PhysicsRobot(ROBOT, uniform_floor(material), PhysicsParams())
    robot.reset(0.3, 0.25, 0.0)
    start = robot.pose
    for _ in range(ROBOT.substeps):
        robot.drive(-ROBOT.wheel_speed, ROBOT.wheel_speed, ROBOT.dt)
    return float(robot.displacement(start)[2])


def _kinematic_turn(field: SlipField) -> float:
    """Heading change [rad] of the fast simulator's robot turning left in place for 1 s on
    ``field`` at the mean wheel-speed loss."""
    task = build_task(
        generate_map("free", np.random.default_rng(0)), field, ROBOT, Discretization()
    )
    pose = (0.3, 0.25, 0.0)
    for k in range(ROBOT.substeps):
        pose = drive_substep(
            task, pose, (-ROBOT.wheel_speed, ROBOT.wheel_speed), k * ROBOT.dt, 0.5, 0.5
        )
    return pose[2]


def test_a_calibrated_preset_turns_as_the_physics_robot_does_and_the_hand_set_one_does_not() -> (
    None
):
    """Measured: rubber mat 0.336 rad physics, 0.324 rough-physics, 0.604 rough (ICR model)."""
    physics = _physics_turn(PRESET_FLOORS["rough"][0])
    calibrated = _kinematic_turn(make_slip_field("rough-physics", np.random.default_rng(0)))
    hand_set = _kinematic_turn(make_slip_field("rough", np.random.default_rng(0)))
    assert calibrated == pytest.approx(physics, rel=0.08)
    assert hand_set > 1.5 * physics


def test_a_calibrated_presets_physics_floor_is_its_own_materials() -> None:
    field = make_slip_field("slippery-physics", np.random.default_rng(4))
    assert field.materials is not None
    assert np.array_equal(region_materials("slippery-physics", field), field.materials)
    rebuilt = SlipField(field.eta, np.zeros_like(field.eta), drift_phase=np.zeros_like(field.eta))
    assert np.array_equal(region_materials("slippery-physics", rebuilt), field.materials)
