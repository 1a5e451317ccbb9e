"""The continuous-action option of SkidSteerNav-v0: wheel speeds (ω_L, ω_R) as the action."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import skidnav.envs  # noqa: F401  (registers the env)
from skidnav.envs.registration import ENV_ID

DISCRETE_COMMANDS = [(1.7, 1.7), (-1.7, -1.7), (-1.7, 1.7), (1.7, -1.7)]


@pytest.mark.filterwarnings("ignore:.*symmetric and normalized")
def test_continuous_env_passes_check_env() -> None:
    env = gymnasium.make(ENV_ID, action="continuous", observation="features", control_period=0.2)
    check_env(env.unwrapped, skip_render_check=True)
    assert env.action_space == gymnasium.spaces.Box(-1.7, 1.7, (2,), np.float32)
    assert env.unwrapped.robot.substeps == 2


@pytest.mark.parametrize("variance", ["true", "observed"])
def test_the_four_corner_actions_are_the_discrete_ones(variance: str) -> None:
    discrete = gymnasium.make(ENV_ID, map_kind="obstacles", world_seed=4, slip="slippery",
                              variance=variance)  # fmt: skip
    continuous = gymnasium.make(ENV_ID, map_kind="obstacles", world_seed=4, slip="slippery",
                                variance=variance, action="continuous")  # fmt: skip
    discrete.reset(seed=9)
    continuous.reset(seed=9)
    for action in np.random.default_rng(1).integers(0, 4, 200).tolist():
        expected = discrete.step(action)
        got = continuous.step(np.array(DISCRETE_COMMANDS[action], dtype=np.float32))
        assert got[:4] == expected[:4]
        assert got[4]["pose"] == expected[4]["pose"]
        assert got[4]["kinematic_log"].tobytes() == expected[4]["kinematic_log"].tobytes()
        if expected[2]:
            discrete.reset()
            continuous.reset()
    stats = discrete.unwrapped.task.variance_stats
    assert stats.tobytes() == continuous.unwrapped.task.variance_stats.tobytes()
    assert stats.any() if variance == "observed" else not stats.any()


def test_any_wheel_speeds_drive_the_icr_model() -> None:
    env = gymnasium.make(ENV_ID, map_kind="free", world_seed=1, action="continuous")
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.array([0.5, 1.0], dtype=np.float32))
    log = info["kinematic_log"]
    assert np.allclose(log[:, 1:3], [0.5, 1.0])  # the commands logged as given
    assert (log[:, 5] > 0).all()  # right wheel faster: turning left
    assert info["pose"][2] > 0


def test_actions_outside_the_box_are_clipped_and_bad_ones_refused() -> None:
    clipped = gymnasium.make(ENV_ID, map_kind="free", world_seed=1, action="continuous")
    limit = gymnasium.make(ENV_ID, map_kind="free", world_seed=1, action="continuous")
    clipped.reset(seed=2)
    limit.reset(seed=2)
    assert clipped.step(np.array([9.0, -9.0]))[4]["pose"] == limit.step([1.7, -1.7])[4]["pose"]
    complex_ones = ([1.0 + 2.0j, 1.0], np.array([1.0, 1.0], dtype=np.complex64), ["1", "1"])
    for bad in ([np.nan, 0.0], [1.0], [[1.0, 1.0]], "fast", None, *complex_ones):
        with pytest.raises(ValueError, match="wheel speeds"):
            clipped.step(bad)


@pytest.mark.parametrize("period", [0.0, -0.1, 0.15, float("nan"), float("inf")])
def test_a_control_period_must_be_whole_sub_steps(period: float) -> None:
    with pytest.raises(ValueError, match="control_period"):
        gymnasium.make(ENV_ID, action="continuous", control_period=period)


def test_the_control_period_sets_the_action_duration() -> None:
    env = gymnasium.make(ENV_ID, map_kind="free", world_seed=1, action="continuous",
                         control_period=0.3)  # fmt: skip
    env.reset(seed=0)
    _, _, _, _, info = env.step([1.7, 1.7])
    assert info["kinematic_log"].shape == (3, 6)
    assert env.unwrapped.time == pytest.approx(0.3)


def test_an_unknown_action_kind_is_refused() -> None:
    with pytest.raises(ValueError, match="expected action in"):
        gymnasium.make(ENV_ID, action="wheels")
