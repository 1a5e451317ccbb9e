"""The one map builder (world/maps.py) behind a config's ``[[maps]]`` entry (experiments.trial),
the real-time arena and the skid-steer env: identical maps for one description and seed,
one-line errors."""

import numpy as np
import pytest

from skidnav.envs.navigation import SkidSteerNavEnv
from skidnav.errors import UserError
from skidnav.experiments.config import MapSpec
from skidnav.experiments.trial import config_map
from skidnav.realtime.arena import arena_map
from skidnav.seeding import ARENA_ROLES, child_sequences
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap, generate_map
from skidnav.world.mapfile import MapFileError, save_map
from skidnav.world.maps import build_map

GRID = Discretization()


def same(a: GridMap, b: GridMap) -> bool:
    return np.array_equal(a.occupancy, b.occupancy) and a.start == b.start and a.goal == b.goal


def map_rng(seed: int) -> np.random.Generator:
    return np.random.default_rng(child_sequences(seed, ARENA_ROLES)["map"])


@pytest.mark.parametrize("kind", ["free", "obstacles", "maze"])
@pytest.mark.parametrize("seed", [0, 5])
def test_the_three_users_build_the_same_map_for_one_seed(kind: str, seed: int) -> None:
    arena = arena_map(kind, seed, GRID)
    env = SkidSteerNavEnv(map_kind=kind, world_seed=seed, discretization=GRID).grid_map
    trial = config_map(MapSpec(kind, kind), map_rng(seed))
    direct = generate_map(kind, map_rng(seed), (GRID.n_x, GRID.n_y))
    assert same(arena, env) and same(env, trial) and same(trial, direct)
    if kind != "free":  # another seed, another layout
        assert not np.array_equal(arena.occupancy, arena_map(kind, seed + 1, GRID).occupancy)


def test_options_and_shape_reach_the_generator() -> None:
    built = build_map(map_rng(1), kind="obstacles", options={"shape": (12, 9), "min_distance": 3})
    assert same(built, generate_map("obstacles", map_rng(1), (12, 9), min_distance=3))
    sized = build_map(map_rng(1), kind="maze", shape=(11, 13))
    assert sized.shape == (11, 13)


def test_a_file_is_read_by_all_three_and_checked_against_the_size(tmp_path) -> None:
    grid_map = generate_map("obstacles", np.random.default_rng(3), (GRID.n_x, GRID.n_y))
    path = tmp_path / "m.txt"
    save_map(grid_map, path)
    rng = np.random.default_rng(0)
    env = SkidSteerNavEnv(map_file=path, discretization=GRID).grid_map
    entry = MapSpec("m", file=str(path))
    for built in (arena_map(str(path), 9, GRID), env, config_map(entry, rng)):
        assert same(built, grid_map)
    with pytest.raises(MapFileError, match=r"^\S*m.txt: map is \(25, 25\), expected \(10, 10\)$"):
        build_map(rng, file=path, shape=(10, 10))
    with pytest.raises(UserError, match=r"map is \(25, 25\), expected \(12, 25\)"):
        arena_map(str(path), 0, Discretization(n_x=12))


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ({"kind": "free", "file": "m.txt"}, "expected a map kind or a map file, got both"),
        ({"file": "m.txt", "options": {"max_tries": 3}}, "expected no options for a map file"),
        ({"kind": "free", "shape": (9, 9), "options": {"shape": (8, 8)}}, "map shape once"),
        ({"kind": "spiral"}, "expected map kind one of free, obstacles, maze, got 'spiral'"),
        ({"kind": "free", "options": {"max_tries": 0}}, "max_tries to be an integer"),
    ],
)
def test_bad_descriptions_are_one_line_value_errors(arguments: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message) as caught:
        build_map(np.random.default_rng(0), **arguments)
    assert "\n" not in str(caught.value)


def test_arena_errors_stay_one_line_user_errors(tmp_path) -> None:
    with pytest.raises(UserError, match=r"^map 'spiral' is neither one of free, obstacles, maze"):
        arena_map("spiral", 0, GRID)
    missing = tmp_path / "none.txt"
    with pytest.raises(UserError, match=r"nor a file$"):
        arena_map(str(missing), 0, GRID)
    with pytest.raises(MapFileError, match=r"no such map file|cannot read"):
        build_map(np.random.default_rng(0), file=missing)
