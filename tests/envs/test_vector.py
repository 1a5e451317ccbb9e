"""The native vector env of SkidSteerNav-v0 (``gymnasium.make_vec``) against N single envs."""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
import pytest

import skidnav.envs  # noqa: F401  (registers the env)
from skidnav.envs.registration import ENV_ID
from skidnav.envs.vector import (
    GatheredInfo,
    SkidSteerNavVectorEnv,
    make_vector_env,
    robot_bytes,
)
from skidnav.world.grid import GridMap, border_walls

NEAR_GOAL = GridMap(occupancy=border_walls((25, 25)), start=(5, 8), goal=(7, 8))
"""A goal two cells ahead of the start: random actions reach it now and then."""


def _pair(n: int, **kwargs: Any) -> tuple[Any, Any]:
    """(the native vector env, a SyncVectorEnv of single envs) of the same arguments."""
    native = gymnasium.make_vec(ENV_ID, num_envs=n, **kwargs)
    single = gymnasium.make_vec(
        ENV_ID, num_envs=n, vectorization_mode="sync", wrappers=[GatheredInfo], **kwargs
    )
    assert isinstance(native.unwrapped, SkidSteerNavVectorEnv)
    return native, single


def _assert_same(got: Any, expected: Any) -> None:
    """The outputs of a reset or step equal, infos' pose and collision included."""
    *arrays, info = got
    *expected_arrays, expected_info = expected
    for value, expected_value in zip(arrays, expected_arrays, strict=True):
        assert value.dtype == np.asarray(expected_value).dtype
        assert np.array_equal(value, expected_value)
    mask = expected_info["_pose"]  # the sub-envs the infos are of (a partial reset: some)
    assert np.array_equal(info["_pose"], mask)
    poses = np.array([list(pose) for pose in expected_info["pose"][mask]])
    assert info["pose"][mask].tobytes() == poses.tobytes()
    assert np.array_equal(info["collision"][mask], expected_info["collision"][mask].astype(bool))
    assert np.array_equal(info["region"][mask], expected_info["region"][mask])


def _actions(envs: Any, rng: np.random.Generator) -> np.ndarray:
    """A batch of random actions, continuous ones partly outside the box."""
    if envs.unwrapped.template.action_kind == "continuous":
        return rng.uniform(-2.0, 2.0, (envs.num_envs, 2)).astype(np.float32)
    return rng.integers(0, 4, envs.num_envs)


CASES = [
    {"grid_map": NEAR_GOAL, "max_episode_steps": 12},
    {"grid_map": NEAR_GOAL, "action": "continuous", "observation": "features",
     "max_episode_steps": 12, "control_period": 0.5},
    {"map_kind": "obstacles", "world_seed": 3, "slip": "slippery", "observation": "features",
     "action": "continuous", "max_episode_steps": 25, "drift_amplitude": 0.4,
     "drift_period": 9.0, "variance": "observed"},
    {"map_kind": "maze", "world_seed": 2, "observation": "pose", "max_episode_steps": 15,
     "variance": "observed"},
]  # fmt: skip


@pytest.mark.parametrize("kwargs", CASES)
def test_the_vector_env_is_n_single_envs_step_for_step(kwargs: dict[str, Any]) -> None:
    native, single = _pair(5, **kwargs)
    _assert_same(native.reset(seed=7), single.reset(seed=7))
    rng, ends = np.random.default_rng(0), 0
    for step in range(150):
        actions = _actions(native, rng)
        got = native.step(actions)
        _assert_same(got, single.step(actions))
        ends += int(got[2].sum() + got[3].sum())
        if step == 70:  # reseed a few mid-episode, leave the others running
            mask = np.array([True, False, True, False, False])
            seeds = [3, None, 4, None, None]
            options = {"reset_mask": mask}
            _assert_same(
                native.reset(seed=seeds, options=options),
                single.reset(seed=seeds, options=options),
            )
    assert ends >= 10  # episodes ended and were reset on the way
    if "grid_map" in kwargs:
        assert native.unwrapped._terminated.any() or ends > 0


def test_goals_are_reached_and_the_next_step_resets() -> None:
    envs = gymnasium.make_vec(ENV_ID, num_envs=64, grid_map=NEAR_GOAL, max_episode_steps=12)
    start, _ = envs.reset(seed=1)
    rng, reached = np.random.default_rng(2), False
    for _ in range(30):
        _, rewards, terminated, _, _ = envs.step(rng.integers(0, 4, 64))
        if terminated.any():
            reached = True
            observations, rewards_after, terminated_after, truncated_after, _ = envs.step(
                np.zeros(64, dtype=np.int64)
            )
            assert (rewards[terminated] == 10.0).all()
            assert np.array_equal(observations[terminated], start[terminated])
            assert (rewards_after[terminated] == 0.0).all()
            assert not (terminated_after[terminated] | truncated_after[terminated]).any()
            break
    assert reached


def test_the_same_seed_gives_the_same_run_and_another_seed_another() -> None:
    def run(seed: int) -> bytes:
        envs = gymnasium.make_vec(ENV_ID, num_envs=8, map_kind="obstacles", world_seed=3,
                                  slip="slippery", action="continuous")  # fmt: skip
        envs.reset(seed=seed)
        rewards = [envs.step(np.full((8, 2), 1.0))[1] for _ in range(20)]
        return np.concatenate(rewards).tobytes() + envs.unwrapped._poses.tobytes()

    assert run(4) == run(4)
    assert run(4) != run(5)


def test_what_the_compiled_step_does_not_simulate_gets_single_envs() -> None:
    pytest.importorskip("mujoco")
    envs = gymnasium.make_vec(ENV_ID, num_envs=2, map_kind="free", dynamics="mujoco")
    assert isinstance(envs.unwrapped, gymnasium.vector.SyncVectorEnv)
    envs.reset(seed=0)
    _, rewards, _, _, infos = envs.step(np.array([0, 2]))
    assert rewards.shape == (2,) and set(infos) >= {"pose", "collision"}


@pytest.mark.parametrize(
    ("kwargs", "actions", "match"),
    [
        ({}, np.array([0, 1, 4]), "actions in 0..3"),
        ({}, np.array([[0, 1, 2]]), "actions in 0..3"),
        ({}, np.array([0.0, 1.0, 2.0]), "integer actions"),  # as the single env refuses them
        ({}, np.array([True, False, True]), "integer actions"),
        ({"action": "continuous"}, {"a": 1}, "finite wheel speeds"),
        ({"action": "continuous"}, [[0.0, 1.0], [0.0], [1.0, 1.0]], "finite wheel speeds"),
        ({"action": "continuous"}, np.ones((3, 3)), "finite wheel speeds"),
        ({"action": "continuous"}, np.array([[0.0, np.nan]] * 3), "finite wheel speeds"),
        ({"action": "continuous"}, np.array([[1.0 + 2.0j, 1.0]] * 3), "finite wheel speeds"),
        ({"action": "continuous"}, np.ones((3, 2), dtype=np.complex128), "finite wheel speeds"),
        ({"action": "continuous"}, [["1", "1"]] * 3, "finite wheel speeds"),
        ({}, np.array([0, 1, 2], dtype=np.complex128), "integer actions"),
    ],
)
def test_bad_actions_are_refused(kwargs: dict[str, Any], actions: Any, match: str) -> None:
    envs = gymnasium.make_vec(ENV_ID, num_envs=3, map_kind="free", **kwargs)
    envs.reset(seed=0)
    with pytest.raises(ValueError, match=match):
        envs.step(actions)


def test_a_refused_batch_is_quoted_in_one_short_line() -> None:
    envs = gymnasium.make_vec(ENV_ID, num_envs=256, map_kind="free", action="continuous")
    envs.reset(seed=0)
    with pytest.raises(ValueError, match="finite wheel speeds") as refused:
        envs.step(np.full((256, 2), np.nan))
    assert "\n" not in str(refused.value) and len(str(refused.value)) < 120


def test_bad_construction_and_resets_are_refused() -> None:
    with pytest.raises(ValueError, match="num_envs"):
        SkidSteerNavVectorEnv(0)
    with pytest.raises(ValueError, match="max_episode_steps"):
        SkidSteerNavVectorEnv(2, max_episode_steps=0)
    envs = SkidSteerNavVectorEnv(2, map_kind="free")
    with pytest.raises(gymnasium.error.ResetNeeded):
        envs.step(np.zeros(2, dtype=np.int64))
    with pytest.raises(ValueError, match="seed"):
        envs.reset(seed=[1, 2, 3])
    with pytest.raises(ValueError, match="reset_mask"):
        envs.reset(options={"reset_mask": np.ones(3, dtype=bool)})


@pytest.mark.parametrize("render_mode", [None, "ansi"])  # the native env, the SyncVectorEnv
def test_max_episode_steps_means_what_it_means_for_gymnasium_make(
    render_mode: str | None,
) -> None:
    """None: the registered 500 actions; −1: no limit; on either path of ``make_vec``."""
    for limit, expected in ((None, 1), (-1, 0), (200, 2)):
        envs = gymnasium.make_vec(
            ENV_ID, num_envs=1, map_kind="free", max_episode_steps=limit, render_mode=render_mode
        )
        envs.reset(seed=0)
        truncations = sum(int(envs.step(np.array([2]))[3][0]) for _ in range(501))
        assert truncations == expected, (limit, render_mode)


@pytest.mark.parametrize("vectorization_mode", [None, "vector_entry_point"])
def test_num_envs_is_range_checked_before_anything_is_allocated(
    vectorization_mode: str | None,
) -> None:
    mode = {} if vectorization_mode is None else {"vectorization_mode": vectorization_mode}
    with pytest.raises(
        ValueError, match=r"^expected num_envs to be an integer in \[1, 16777216\], "
    ):
        gymnasium.make_vec(ENV_ID, num_envs=10**9, map_kind="free", **mode)
    with pytest.raises(ValueError, match=r"^expected num_envs"):  # the MuJoCo path too
        make_vector_env(10**9, dynamics="mujoco")
    with pytest.raises(ValueError, match=r"^expected a vector env of at most 4 GiB, got about 69"):
        gymnasium.make_vec(ENV_ID, num_envs=10**7, map_kind="free", **mode)


def test_the_memory_estimate_covers_the_arrays() -> None:
    envs = SkidSteerNavVectorEnv(64, map_kind="free", observation="features", lidar_rays=16)
    arrays = [value for value in vars(envs).values() if isinstance(value, np.ndarray)]
    per_robot = sum(a.nbytes for a in arrays if a.shape[:1] == (64,)) / 64
    assert per_robot <= robot_bytes(envs.template) <= per_robot + 1024 + 200
