"""The Jackal preset on the kinematic simulator, its floors, and the UST-10-like laser."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import skidnav.envs  # noqa: F401  (registers the env)
from skidnav.robot.datasheet import Datasheet, floor_gap
from skidnav.robot.params import RobotParams
from skidnav.robot.presets import JACKAL, ROBOT_PRESETS, robot_preset, robot_preset_name
from skidnav.sim.lidar import HOKUYO_UST10, LaserSpec, lidar_ranges, lidar_scan
from skidnav.world.barn import load_barn_world
from skidnav.world.grid import GridMap, border_walls

ENV_ID = "skidnav/SkidSteerNav-v0"
FORWARD, LEFT = 0, 2


def test_the_jackal_has_its_published_geometry():
    assert JACKAL.wheel_radius == 0.098
    assert 2 * JACKAL.half_track == pytest.approx(0.37559, abs=1e-15)
    assert JACKAL.front_axle + JACKAL.rear_axle == pytest.approx(0.262, abs=1e-15)
    assert JACKAL.body_length == 0.42 and JACKAL.x_icr == 0.0
    assert Datasheet.of(JACKAL).forward_speed() == pytest.approx(2.0, abs=1e-12)
    assert robot_preset("jackal") is JACKAL and set(ROBOT_PRESETS) == {"thesis", "jackal"}
    assert robot_preset_name(JACKAL) == "jackal"
    with pytest.raises(ValueError, match="expected a robot in thesis, jackal, got 'husky'"):
        robot_preset("husky")


def open_arena() -> GridMap:
    """The Jackal's 4.5 m × 15 m arena in 0.15 m cells, walls on the border only."""
    return GridMap(border_walls((31, 101)), start=(3, 50), goal=(25, 90))


def make_env(**options):
    return gym.make(ENV_ID, grid_map=open_arena(), robot="jackal", slip="nominal", **options)


def test_the_kinematic_jackal_drives_straight_at_its_top_speed():
    env = make_env()
    env.reset(seed=0)
    assert env.unwrapped.robot == JACKAL
    x, y, heading = env.unwrapped.pose
    _, _, _, _, info = env.step(FORWARD)  # one 1-s action, both wheels at 2.0/0.098 rad/s
    assert not info["collision"]
    # tolerance: floating point only (the nominal floor loses no wheel speed)
    assert info["pose"][0] - x == pytest.approx(2.0, abs=1e-9)
    assert info["pose"][1] == pytest.approx(y, abs=1e-12)
    assert info["pose"][2] == pytest.approx(heading, abs=1e-12)


def test_the_kinematic_jackal_turns_at_the_rate_of_its_geometry():
    env = make_env(control_period=0.1)
    env.reset(seed=0)
    x, y, heading = env.unwrapped.pose
    _, _, _, _, info = env.step(LEFT)
    rate = JACKAL.wheel_radius * JACKAL.wheel_speed / JACKAL.half_track  # r Ω / c, 10.65 rad/s
    assert rate == pytest.approx(10.6499, abs=1e-4)
    assert (info["pose"][2] - heading) / 0.1 == pytest.approx(rate, abs=1e-9)
    # x_ICR = 0: turning in place does not move the centre
    assert info["pose"][:2] == pytest.approx((x, y), abs=1e-12)


def test_the_nominal_floor_is_the_datasheet_and_ice_is_not():
    nominal = floor_gap("nominal", JACKAL)
    assert (nominal.forward, nominal.turn, nominal.x_icr) == pytest.approx((1.0, 1.0, 0.0))
    ice = floor_gap("ice-physics", JACKAL)
    # fitted on the MuJoCo Jackal on ice: 1-s actions move it a small fraction of the datasheet
    assert ice.forward < 0.2 and ice.turn < 0.3


def test_a_string_robot_must_be_a_preset():
    with pytest.raises(ValueError, match="expected a robot in"):
        gym.make(ENV_ID, map_kind="free", robot="rover")


def test_the_ust10_laser_spans_270_degrees():
    angles = HOKUYO_UST10.angles(heading=0.0)
    assert len(angles) == 1081 and HOKUYO_UST10.max_range == 10.0
    assert math.degrees(angles[0]) == pytest.approx(-135.0)
    assert math.degrees(angles[-1]) == pytest.approx(135.0)
    assert math.degrees(angles[540]) == pytest.approx(0.0, abs=1e-12)
    assert np.diff(angles) == pytest.approx(np.full(1080, math.radians(0.25)))


def test_the_laser_reads_the_distance_to_a_cylinder_in_front():
    occupancy = border_walls((31, 101)).astype(np.uint8)
    occupancy[15, 30] = 1  # a cylinder of radius 0.075 m centred at (2.325, 4.575) m
    pose = (2.325, 3.075, math.pi / 2)  # facing +y, 1.5 m from the cylinder's centre
    ranges = HOKUYO_UST10.scan(occupancy, (4.5, 15.0), pose)
    assert ranges[540] == pytest.approx(1.5 - 0.075, abs=1e-9)
    # the sector's edges look back-right and back-left, at 45° to the right border (x = 4.5 m)
    # and to the left border wall (x = 0.15 m), both 2.175 m away
    diagonal = 2.175 / math.cos(math.radians(45))
    assert (ranges[0], ranges[-1]) == pytest.approx((diagonal, diagonal), abs=1e-9)
    assert ranges.min() > 0 and ranges.max() <= 10.0


def test_a_full_turn_scan_is_the_lidar_of_the_features():
    occupancy = border_walls((11, 11)).astype(np.uint8)
    full, scan = np.empty(16), np.empty(16)
    lidar_ranges(occupancy, 1.0, 1.0, 0.3, 0.6, 0.2, 2.0, full)
    lidar_scan(occupancy, 1.0, 1.0, 0.3, 0.6, 0.2, 2.0, 2 * math.pi, scan)
    assert np.array_equal(full, scan)
    assert LaserSpec(rays=16, max_range=2.0).angles(0.2) == pytest.approx(
        0.2 + np.arange(16) * math.pi / 8
    )


def test_the_laser_sees_a_barn_world_from_its_start():
    world = load_barn_world(0)
    occupancy = world.map.grid.as_uint8()
    arena = (world.discretization.arena_width, world.discretization.arena_height)
    ranges = HOKUYO_UST10.scan(occupancy, arena, world.start_pose)
    # straight ahead up the empty corridor to the obstacle field, which starts at y = 5.1 m
    assert 5.1 - 3.0 <= ranges[540] <= 10.0
    assert ranges.min() > 0.3  # the start is clear of every cylinder by more than a body


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"rays": 0, "max_range": 1.0}, "expected rays to be an integer >= 1"),
        ({"rays": 3, "max_range": 0.0}, "expected max_range > 0 m"),
        ({"rays": 3, "max_range": 1.0, "field_of_view": 7.0}, "expected field_of_view in"),
    ],
)
def test_a_bad_laser_is_refused(options, message):
    with pytest.raises(ValueError, match=message):
        LaserSpec(**options)


def test_the_thesis_robot_is_still_the_default():
    assert robot_preset("thesis") == RobotParams()
