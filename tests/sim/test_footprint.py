"""A robot with a footprint collides by its rectangle against the wall cells' discs."""

from __future__ import annotations

import math
import zipfile
from importlib import resources

import numpy as np
import pytest

from skidnav.envs.navigation import SkidSteerNavEnv
from skidnav.robot.params import RobotParams
from skidnav.robot.presets import JACKAL, JACKAL_FOOTPRINT
from skidnav.sim.footprint import footprint_collides
from skidnav.sim.lidar import HOKUYO_UST10
from skidnav.world.barn import CYLINDER_RADIUS, load_barn_world
from skidnav.world.discretization import Discretization

# 1 m × 1 m in cells of 0.1 m: a wall cell's disc has radius 0.05 m
GRID = Discretization(n_x=11, n_y=11, arena_width=1.0, arena_height=1.0).grid_shape()
LENGTH, WIDTH = 0.4, 0.2


def one_wall(i: int, j: int) -> np.ndarray:
    walls = np.zeros((11, 11), dtype=np.uint8)
    walls[i, j] = 1
    return walls


def test_the_rectangle_meets_the_disc_where_its_edge_reaches_it():
    walls = one_wall(7, 5)  # disc centred at (0.75, 0.55), radius 0.05
    # heading +x: the front edge is at x + 0.2; it touches the disc when x + 0.2 = 0.70
    assert not footprint_collides(walls, GRID, 0.499, 0.55, 0.0, LENGTH, WIDTH)
    assert footprint_collides(walls, GRID, 0.501, 0.55, 0.0, LENGTH, WIDTH)
    # heading +y: the side edge is at x + 0.1, so the robot may come 0.1 m closer
    assert not footprint_collides(walls, GRID, 0.599, 0.55, math.pi / 2, LENGTH, WIDTH)
    assert footprint_collides(walls, GRID, 0.601, 0.55, math.pi / 2, LENGTH, WIDTH)


def test_a_corner_meets_the_disc_by_distance_not_by_its_bounding_box():
    walls = one_wall(7, 7)  # disc centred at (0.75, 0.75)
    # the corner (x + 0.2, y + 0.1) at 0.06 m from the centre along the diagonal: a miss
    corner = 0.75 - 0.06 / math.sqrt(2)
    assert not footprint_collides(walls, GRID, corner - 0.2, corner - 0.1, 0.0, LENGTH, WIDTH)
    corner = 0.75 - 0.04 / math.sqrt(2)
    assert footprint_collides(walls, GRID, corner - 0.2, corner - 0.1, 0.0, LENGTH, WIDTH)


def test_a_point_robot_keeps_the_cell_rule_and_a_footprint_is_two_positive_sides():
    assert not RobotParams().has_footprint and JACKAL.has_footprint
    assert (JACKAL.footprint_length, JACKAL.footprint_width) == JACKAL_FOOTPRINT
    expected = r"both 0 \(a point robot\) or both > 0 m, got 0.5 and 0.0"
    with pytest.raises(ValueError, match=expected):
        RobotParams(footprint_length=0.5)
    with pytest.raises(ValueError, match=r"got nan and 0\.2"):
        RobotParams(footprint_length=float("nan"), footprint_width=0.2)


def barn_env(number: int, tmp_path, **options) -> SkidSteerNavEnv:
    archive = resources.files("skidnav").joinpath("data", "barn", "worlds.zip")
    with archive.open("rb") as stream, zipfile.ZipFile(stream) as worlds:
        text = worlds.read(f"world_{number}.txt").decode()
    path = tmp_path / f"world_{number}.txt"
    path.write_text(text)
    return SkidSteerNavEnv(
        map_file=path, robot="jackal", slip="nominal", control_period=0.1, action="continuous",
        **options,
    )  # fmt: skip


def test_the_jackal_stops_where_its_body_meets_a_cylinder_of_a_barn_world(tmp_path):
    env = barn_env(0, tmp_path)
    env.reset(seed=0)
    world = load_barn_world(0)
    assert tuple(env.start_pose()) == world.start_pose
    assert env.goal_point == world.goal and env.goal_radius == world.goal_radius == 1.0
    full = env.robot.wheel_speed
    for _ in range(100):
        _, reward, terminated, _, info = env.step(np.array([full, full]))
        if info["collision"]:
            break
    assert info["collision"] and reward == -10.0 and not terminated
    x, y, _ = info["pose"]
    walls = env.grid_map.occupancy
    assert not walls[env.discretization.cell(x, y)]  # the centre is in a free cell
    # a cylinder lies within half the footprint's diagonal plus its radius of the centre
    d = env.discretization
    centres = [d.cell_centre(i, j) for i, j in zip(*np.nonzero(walls), strict=True)]
    nearest = min(math.dist((x, y), c) for c in centres)
    assert nearest <= math.hypot(*JACKAL_FOOTPRINT) / 2 + CYLINDER_RADIUS
    assert nearest > JACKAL_FOOTPRINT[1] / 2  # and the body, not the centre, met it


def test_a_barn_episode_ends_within_a_metre_of_the_goal_point(tmp_path):
    env = barn_env(0, tmp_path, goal_disc=(2.25, 4.5, 1.0))  # an open stretch ahead
    env.reset(seed=0)
    full = env.robot.wheel_speed
    distances = []
    for _ in range(20):
        _, reward, terminated, _, info = env.step(np.array([full, full]))
        distances.append(math.dist(info["pose"][:2], (2.25, 4.5)))
        if terminated:
            break
    assert terminated and reward == 10.0
    assert distances[-1] <= 1.0 < distances[-2]  # the first action that ends within 1 m


def test_the_features_read_a_laser_of_the_benchmarks_field_of_view(tmp_path):
    fov = HOKUYO_UST10.field_of_view
    env = barn_env(3, tmp_path, observation="features", lidar_rays=271, lidar_range=10.0,
                   lidar_fov=fov)  # fmt: skip
    observation, _ = env.reset(seed=0)
    scan = type(HOKUYO_UST10)(rays=271, max_range=10.0, field_of_view=fov).scan(
        env.grid_map.as_uint8(), (4.5, 15.0), tuple(env.start_pose())
    )
    np.testing.assert_array_equal(observation[7:], scan)
    assert observation[4] == pytest.approx(10.0, abs=1e-12)  # to the goal point, 10 m ahead
    with pytest.raises(ValueError, match="field_of_view"):
        barn_env(3, tmp_path, observation="features", lidar_fov=7.0)
