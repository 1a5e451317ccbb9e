"""A saved agent of discrete actions as a frozen wheel-speed policy
(:mod:`skidnav.agents.discrete_policy`): the env's action table, what it observes read from its
saved bounds, and a policy the robot cannot run refused in one line."""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from gymnasium.spaces import Box

from skidnav.agents.discrete_policy import DiscreteActionPolicy, feature_lidar
from skidnav.agents.linear.registry import make_linear_agent
from skidnav.agents.saved import load_policy
from skidnav.agents.wheel_policy import WheelSpeedPolicy
from skidnav.errors import UserError
from skidnav.realtime.policies import check_policy
from skidnav.robot.kinematics import N_ACTIONS, commanded_wheel_speeds
from skidnav.sim.features import PoseFeatures, feature_bounds
from skidnav.world.discretization import Discretization
from skidnav.world.maps import build_map

SMALL = {"tiles": [3], "n_tilings": 2, "dimensions": [4, 5, 6]}
"""A linear agent's tiles, small."""


class Answers:
    """A stand-in agent answering ``action`` whatever it observes."""

    def __init__(self, action: Any) -> None:
        self.action = action

    def greedy_action(self, observation: np.ndarray) -> Any:
        return self.action


def test_its_wheel_speeds_are_those_of_the_env_s_action_table() -> None:
    for action in range(N_ACTIONS):
        policy = DiscreteActionPolicy(Answers(np.int64(action)), 8, 0.3, 1.7, (0.62, 0.505))
        assert isinstance(policy, WheelSpeedPolicy)
        assert policy.wheel_speeds(np.zeros(15)) == commanded_wheel_speeds(action, 1.7)
    for wrong in (N_ACTIONS, -1, 1.0, True, None):
        with pytest.raises(ValueError, match="expected"):
            DiscreteActionPolicy(Answers(wrong), 8, 0.3, 1.7, (0.62, 0.505)).wheel_speeds(
                np.zeros(15)
            )


@pytest.mark.parametrize(("rays", "reach"), [(0, 0.3), (1, 0.2), (8, 0.3)])
def test_the_observation_is_read_from_the_saved_bounds(rays: int, reach: float) -> None:
    grid_map = build_map(np.random.default_rng(0), kind="free", shape=(25, 25))
    space = PoseFeatures(grid_map, Discretization(), rays, reach).space()
    found = feature_lidar(space.low, space.high)
    assert found[0] == rays
    assert found[1] == (reach if rays else pytest.approx(np.hypot(0.62, 0.505)))


def test_bounds_of_the_pose_or_of_another_env_are_refused() -> None:
    with pytest.raises(ValueError, match="it observes the pose"):
        feature_lidar(np.array([0.0, 0.0, -np.pi]), np.array([0.62, 0.505, np.pi]))
    low, high = feature_bounds((0.62, 0.505), 2, 0.3)
    for changed in (low[:5], np.where(np.arange(9) == 2, -2.0, low)):
        with pytest.raises(ValueError, match="expected the bounds of the feature observation"):
            feature_lidar(changed, high[: changed.size])


def saved_linear(folder: Path, arena: tuple[float, float], n_actions: int = N_ACTIONS) -> Path:
    """A linear-q agent over the features of ``arena`` (W, H) [m], two rays, saved in a new
    folder under ``folder``."""
    space = Box(*feature_bounds(arena, 2, 0.1), dtype=np.float64)
    agent = make_linear_agent("linear-q", space, n_actions, SMALL, np.random.default_rng(0))
    return agent.save(Path(tempfile.mkdtemp(dir=folder)) / "linear")[1]


def test_a_linear_agent_of_other_actions_or_another_arena_is_refused(tmp_path: Path) -> None:
    with pytest.raises(UserError, match="it takes 3 actions, the robot's are 4") as error:
        load_policy(saved_linear(tmp_path, (0.62, 0.505), n_actions=3))
    assert "linear.json" in str(error.value)
    policy = load_policy(saved_linear(tmp_path, (0.2, 0.2)))
    grid = Discretization()
    grid_map = build_map(np.random.default_rng(0), kind="free", shape=(25, 25))
    with pytest.raises(UserError, match=r"it observes an arena of 0\.2 × 0\.2 m, the run's is"):
        check_policy(policy, "file:linear.json", grid_map, grid, 1.0)
    check_policy(load_policy(saved_linear(tmp_path, (0.62, 0.505))), "ok", grid_map, grid, 1.0)
