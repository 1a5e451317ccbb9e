"""The ``observation="features"`` vector: lidar ranges against hand-placed walls, the goal's
distance and bearing, the Box contract, determinism, and the same ranges without the JIT."""

import math
import os
import subprocess
import sys
from pathlib import Path

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from hypothesis import given, settings
from hypothesis import strategies as st

import skidnav  # noqa: F401  (registers the env)
from skidnav.envs.navigation import SkidSteerNavEnv
from skidnav.sim.features import POSE_GOAL_NAMES, goal_features
from skidnav.sim.lidar import cast_ray, lidar_ranges
from skidnav.world.discretization import Discretization

SIDE = 1.0
"""The hand-made maps: 11 × 11 levels over 1 m × 1 m, so cells of 0.1 m: cell i is
x in [0.1·i, 0.1·(i + 1)), the last level the border line x = 1 m."""


def hand_map(**walls: tuple[int | slice, int | slice]) -> np.ndarray:
    """An 11 × 11 uint8 occupancy with the named wall blocks (``walls[name] = (i, j)``)."""
    occupancy = np.zeros((11, 11), dtype=np.uint8)
    for index in walls.values():
        occupancy[index] = 1
    return occupancy


def ray(occupancy: np.ndarray, x: float, y: float, angle: float, max_range: float = 2.0) -> float:
    return float(cast_ray(occupancy, SIDE, SIDE, x, y, angle, max_range))


def test_forward_ray_reads_the_distance_to_a_wall_column_face():
    walls = hand_map(column=(7, slice(None)))  # x in [0.7, 0.8)
    assert ray(walls, 0.25, 0.55, 0.0) == pytest.approx(0.45, abs=1e-12)
    assert ray(walls, 0.9, 0.55, math.pi) == pytest.approx(0.1, abs=1e-12)  # the far face 0.8
    # at 60° from +x the face x = 0.7 is 0.45 / cos 60° = 0.9 away
    assert ray(walls, 0.25, 0.05, math.pi / 3) == pytest.approx(0.9, abs=1e-12)


def test_diagonal_ray_enters_a_single_wall_cell_through_its_face():
    # from (0.22, 0.35) at 45° the ray (y = x + 0.13) crosses y = 0.5 at x = 0.37, into cell
    # (3, 5), then x = 0.4 into the wall cell (4, 5): 0.18·√2 from the origin.
    walls = hand_map(cell=(4, 5))
    assert ray(walls, 0.22, 0.35, math.pi / 4) == pytest.approx(0.18 * math.sqrt(2), abs=1e-12)
    # a wall row j = 7 (y in [0.7, 0.8)): reached at y = 0.7, 0.35·√2 away
    walls = hand_map(row=(slice(None), 7))
    assert ray(walls, 0.22, 0.35, math.pi / 4) == pytest.approx(0.35 * math.sqrt(2), abs=1e-12)


def test_ray_that_hits_nothing_reads_the_maximum_range():
    walls = hand_map(column=(7, slice(None)))
    assert ray(walls, 0.25, 0.55, 0.0, max_range=0.3) == 0.3
    assert ray(walls, 0.25, 0.55, 0.0, max_range=0.45 + 1e-9) == pytest.approx(0.45, abs=1e-12)


def test_arena_border_stops_a_ray_like_a_wall():
    walls = hand_map()  # no wall cell at all
    ranges = np.empty(4)
    lidar_ranges(walls, SIDE, SIDE, 0.25, 0.6, 0.0, 2.0, ranges)
    np.testing.assert_allclose(ranges, [0.75, 0.4, 0.25, 0.6], atol=1e-12)  # ahead, left, …
    assert ray(walls, 1.0, 0.55, 0.0) == 0.0  # on the border x = W facing out
    assert ray(walls, 1.0, 0.55, math.pi) == pytest.approx(1.0, abs=1e-12)
    assert ray(walls, 0.0, 0.55, math.pi) == 0.0
    assert ray(hand_map(cell=(2, 5)), 0.25, 0.55, 1.0) == 0.0  # inside a wall


def test_rays_start_at_the_heading_and_turn_counter_clockwise():
    walls = hand_map(column=(7, slice(None)))
    ranges = np.empty(3)
    lidar_ranges(walls, SIDE, SIDE, 0.25, 0.55, math.pi / 2, 2.0, ranges)  # facing +y
    # 0: +y to the top border; 1: 210° to the border x = 0; 2: 330° to the wall face x = 0.7
    expected = [0.45, 0.25 / math.cos(math.pi / 6), 0.45 / math.cos(math.pi / 6)]
    np.testing.assert_allclose(ranges, expected, atol=1e-12)
    lidar_ranges(walls, SIDE, SIDE, 0.25, 0.55, 0.0, 2.0, np.empty(0))  # no rays: no work


@settings(max_examples=200, deadline=None)
@given(
    x=st.floats(0.0, 0.62),
    y=st.floats(0.0, 0.505),
    angle=st.floats(-4.0, 4.0),
    seed=st.integers(0, 1000),
)
def test_ray_stops_where_the_mdp_cells_turn_to_wall(x, y, angle, seed):
    """Points just short of the reading lie in free cells of the arena (as the MDP's
    ``cell_of`` sees them); the point just past it is in a wall cell or off the arena, whose
    border lines x = 0 and y = 0 stop a ray (a ray along θ = −5e-324 from y = 0 reads 0, and
    its point just past still has y = 0 in floating point)."""
    disc = Discretization()
    walls = (np.random.default_rng(seed).random((25, 25)) < 0.15).astype(np.uint8)
    walls[disc.cell(x, y)] = 0
    reading = float(cast_ray(walls, 0.62, 0.505, x, y, angle, 0.5))
    direction = np.array([math.cos(angle), math.sin(angle)])
    for t in np.linspace(0.0, reading - 1e-9, 50):
        px, py = np.array([x, y]) + max(t, 0.0) * direction
        if 0.0 < px < 0.62 and 0.0 < py < 0.505:
            assert walls[disc.cell(px, py)] == 0
    if reading < 0.5:
        px, py = np.array([x, y]) + (reading + 1e-9) * direction
        off_arena = not (0.0 < px < 0.62 and 0.0 < py < 0.505)
        assert off_arena or walls[disc.cell(px, py)] == 1


def test_goal_distance_and_bearing_by_hand():
    assert goal_features(0.1, 0.1, 0.0, 0.1, 0.4) == pytest.approx((0.3, 0.0, 1.0))  # to the left
    # facing −x, the goal 0.4 m along +x and 0.3 m along +y: behind and to the right
    assert goal_features(0.1, 0.1, math.pi, 0.5, 0.4) == pytest.approx((0.5, -0.8, -0.6))
    assert goal_features(0.2, 0.2, 1.0, 0.2, 0.2) == (0.0, 1.0, 0.0)  # on the goal
    env = SkidSteerNavEnv(map_kind="free", world_seed=1, observation="features")
    observation, _ = env.reset(seed=0)
    disc, (si, sj), (gi, gj) = env.discretization, env.grid_map.start, env.grid_map.goal
    dx, dy = (gi - si) * disc.cell_width, (gj - sj) * disc.cell_height  # centre to centre
    distance = math.hypot(dx, dy)
    expected = [*env.start_pose()[:2], 1.0, 0.0, distance, dx / distance, dy / distance]
    np.testing.assert_allclose(observation[:7], expected, atol=1e-12)


def test_space_layout_and_exact_bounds():
    env = SkidSteerNavEnv(observation="features", lidar_rays=5, lidar_range=0.25)
    space = env.observation_space
    assert space.shape == (12,) and space.dtype == np.float64
    assert env.features.names() == (*POSE_GOAL_NAMES, *(f"range_{r}" for r in range(5)))
    assert space.low.tolist() == [0.0, 0.0, -1.0, -1.0, 0.0, -1.0, -1.0] + [0.0] * 5
    diagonal = math.sqrt(0.62**2 + 0.505**2)
    assert space.high.tolist() == [0.62, 0.505, 1.0, 1.0, diagonal, 1.0, 1.0] + [0.25] * 5
    no_rays = SkidSteerNavEnv(observation="features", lidar_rays=0)
    assert no_rays.observation_space.shape == (7,)
    assert no_rays.observation_space.contains(no_rays.reset(seed=0)[0])


@pytest.mark.filterwarnings("ignore:.*different from the unwrapped")
def test_check_env_passes_with_features():
    env = gymnasium.make(
        "skidnav/SkidSteerNav-v0", map_kind="maze", world_seed=2, observation="features"
    )
    check_env(env.unwrapped)
    check_env(env)
    assert env.observation_space.shape == (15,)


def rollout(seed: int, n: int = 400, **kwargs) -> tuple[SkidSteerNavEnv, np.ndarray]:
    env = SkidSteerNavEnv(observation="features", slip="slippery", **kwargs)
    observations = [env.reset(seed=seed)[0]]
    for action in np.random.default_rng(seed).integers(0, 4, n):
        observation, _, terminated, _, _ = env.step(int(action))
        observations.append(observation)
        if terminated:
            observations.append(env.reset()[0])
    return env, np.array(observations)


def test_every_observation_lies_in_the_box_and_the_same_seed_repeats():
    kwargs = {"world_seed": 4, "lidar_rays": 12, "lidar_range": 0.5}
    env, observations = rollout(3, **kwargs)
    assert all(env.observation_space.contains(o) for o in observations)
    assert observations[:, 7:].min() < 0.05 and observations[:, 7:].max() == 0.5  # walls seen
    np.testing.assert_array_equal(observations, rollout(3, **kwargs)[1])
    assert not np.array_equal(observations, rollout(5, **kwargs)[1])


def test_the_discrete_default_is_unchanged():
    env = SkidSteerNavEnv(world_seed=1)
    state, _ = env.reset(seed=0)
    assert isinstance(state, int) and env.observation_space.n == 12_500
    assert state == env.state()


DIGEST_SCRIPT = """
import hashlib, numpy as np
from skidnav.envs.navigation import SkidSteerNavEnv
parts = []
for kind in ("obstacles", "maze"):
    env = SkidSteerNavEnv(map_kind=kind, world_seed=7, observation="features", lidar_rays=16)
    parts.append(env.reset(seed=1)[0].tobytes())
    for a in np.random.default_rng(2).integers(0, 4, 300):
        parts.append(env.step(int(a))[0].tobytes())
print(hashlib.sha256(b"".join(parts)).hexdigest())
"""


def _digest(disable_jit: bool) -> str:
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).parents[2] / "src"))
    env["NUMBA_DISABLE_JIT"] = "1" if disable_jit else "0"
    result = subprocess.run(
        [sys.executable, "-c", DIGEST_SCRIPT], env=env, capture_output=True, text=True, check=True
    )
    return result.stdout.strip()


def test_features_are_bit_identical_with_and_without_jit():
    compiled = _digest(disable_jit=False)
    assert len(compiled) == 64
    assert compiled == _digest(disable_jit=True)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"lidar_rays": -1}, r"^expected lidar_rays to be an integer in \[0, 1024\], got -1$"),
        (
            {"lidar_rays": 10**7},
            r"^expected lidar_rays to be an integer in \[0, 1024\], got 10000000$",
        ),
        ({"lidar_rays": 2.0}, "lidar_rays"),
        ({"lidar_rays": True}, "lidar_rays"),
        ({"lidar_range": 0.0}, "^expected lidar_range to be a finite number > 0 m, got 0.0$"),
        ({"lidar_range": math.inf}, "lidar_range"),
        ({"lidar_range": "far"}, "lidar_range"),
        ({"observation": "lidar"}, "observation"),
    ],
)
def test_bad_arguments(kwargs, message):
    with pytest.raises(ValueError, match=message):
        SkidSteerNavEnv(**{"observation": "features", **kwargs})
