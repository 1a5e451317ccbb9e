"""The MuJoCo Jackal: its model from the published numbers, its speed on the nominal floor, its
calibrated floors."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("mujoco")

import skidnav.envs  # noqa: F401  (registers the env)
from skidnav.physics.calibration import calibrate
from skidnav.physics.materials import MATERIALS
from skidnav.physics.mjcf import JACKAL_PHYSICS, PhysicsParams, physics_for, uniform_floor
from skidnav.physics.mujoco_robot import PhysicsRobot
from skidnav.robot.floors import calibrated_floors
from skidnav.robot.params import RobotParams
from skidnav.robot.presets import JACKAL
from skidnav.world.grid import GridMap, border_walls


def test_the_model_is_built_from_the_jackals_numbers():
    body = PhysicsRobot(JACKAL, uniform_floor("rubber-mat"))
    assert body.physics == JACKAL_PHYSICS and physics_for(RobotParams()) == PhysicsParams()
    model = body.model
    assert float(model.body_mass.sum()) == pytest.approx(17.0)
    assert model.geom("chassis").size.tolist() == pytest.approx([0.21, 0.155, 0.09])
    wheel = model.geom("front_left")
    assert float(wheel.size[0]) == 0.098
    assert model.body("front_left").pos.tolist() == pytest.approx([0.131, 0.187795, 0.0])
    assert model.body("rear_right").pos.tolist() == pytest.approx([-0.131, -0.187795, 0.0])


def test_the_mujoco_jackal_drives_straight_at_its_top_speed_on_the_nominal_floor():
    grid = GridMap(border_walls((31, 101)), start=(15, 10), goal=(15, 90))
    env = gym.make(
        "skidnav/SkidSteerNav-v0", grid_map=grid, robot="jackal", slip="nominal", dynamics="mujoco"
    )
    env.reset(seed=0)
    env.unwrapped.pose[2] = np.pi / 2  # face +y, up the long arena
    env.unwrapped.physics_robot.reset(*env.unwrapped.pose)
    env.step(0)  # 1 s from rest: the servos and the tyres bring it up to speed
    before = np.array(env.unwrapped.pose)
    _, _, _, _, info = env.step(0)
    after = np.array(info["pose"])
    # tolerance 2 %: rolling resistance and the servo's lag, nothing else, slow it
    assert after[1] - before[1] == pytest.approx(2.0, rel=0.02)
    assert abs(after[0] - before[0]) < 0.01 and abs(after[2] - before[2]) < 0.01


def test_on_ice_the_datasheet_is_wrong():
    body = PhysicsRobot(JACKAL, uniform_floor("ice"))
    body.reset(2.25, 3.0, np.pi / 2)
    body.drive(JACKAL.wheel_speed, JACKAL.wheel_speed, 1.0)
    # from rest, μ = 0.05 lets it gain at most 0.49 m/s in 1 s: it covers about 0.25 m, not 2
    assert body.pose[1] - 3.0 < 0.3


def test_the_shipped_jackal_floors_are_those_a_new_calibration_gives():
    """``src/skidnav/data/floors-jackal.json`` is ``skidnav world floors calibrate --robot
    jackal`` (60 s, seed 0): recalibrate after changing a material or the Jackal's model."""
    shipped = calibrated_floors(JACKAL)
    fits = calibrate(list(MATERIALS), np.random.default_rng(0), segments=60, robot=JACKAL)
    assert sorted(shipped) == sorted(MATERIALS)
    for fit in fits:
        new = (fit.wheel_radius, fit.half_track, fit.x_icr, fit.eta)
        assert tuple(shipped[fit.material]) == pytest.approx(new, rel=1e-6, abs=1e-9)
