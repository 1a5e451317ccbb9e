"""MapSetEnv: one Gymnasium env whose episodes are drawn from a set of worlds."""

from __future__ import annotations

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from skidnav.envs.mapset import MapSetEnv

SEEDS = (11, 12, 13)


def test_check_env_passes() -> None:
    check_env(MapSetEnv(SEEDS, observation="features"), skip_render_check=True)


def test_one_seed_fixes_the_worlds_starts_and_steps() -> None:
    def episode_starts(seed: int) -> list[tuple[int, tuple[float, ...]]]:
        env = MapSetEnv(SEEDS, observation="features")
        starts = []
        for k in range(12):
            observation, info = env.reset(seed=seed if k == 0 else None)
            observation, *_ = env.step(0)
            starts.append((info["world"], tuple(observation)))
        return starts

    first, again, other = episode_starts(4), episode_starts(4), episode_starts(5)
    assert first == again and first != other
    assert {world for world, _ in first} == {0, 1, 2}  # every world of the set is drawn


def test_each_world_is_its_own_map_and_the_episode_runs_on_it() -> None:
    env = MapSetEnv(SEEDS, observation="features")
    maps = {(w.grid_map.occupancy.tobytes(), w.grid_map.start, w.grid_map.goal) for w in env.worlds}
    assert len(maps) == len(SEEDS)
    _, info = env.reset(seed=2)
    poses = [world.pose.copy() for world in env.worlds]
    env.step(0)
    moved = [
        not np.array_equal(world.pose, pose) for world, pose in zip(env.worlds, poses, strict=True)
    ]
    assert moved == [k == info["world"] for k in range(len(SEEDS))]


@pytest.mark.parametrize(
    "seeds, options, message",
    [((), {}, "world seeds"), ((1,), {"world_seed": 2}, "world_seed")],
)
def test_bad_sets_are_refused(
    seeds: tuple[int, ...], options: dict[str, int], message: str
) -> None:
    with pytest.raises(ValueError, match=message):
        MapSetEnv(seeds, **options)


def test_discrete_observation_has_one_count() -> None:
    env = MapSetEnv(SEEDS)
    state, _ = env.reset(seed=1)
    assert env.observation_space.contains(state) and isinstance(int(state), int)
    assert np.all([w.observation_space == env.observation_space for w in env.worlds])
