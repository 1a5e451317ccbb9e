"""The goal tracker: a WheelSpeedPolicy reaching the goal of a free map in the continuous env."""

from __future__ import annotations

import math

import gymnasium
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import skidnav  # noqa: F401  (registers the env)
from skidnav.agents.policies.goal_tracker import GoalTracker, GoalTrackerConfig
from skidnav.agents.wheel_policy import WheelSpeedPolicy
from skidnav.robot.kinematics import body_velocities
from skidnav.robot.params import RobotParams

ENV_ID = "skidnav/SkidSteerNav-v0"


def observation(distance: float, bearing: float, rays: int = 8) -> np.ndarray:
    """A feature observation with the goal ``distance`` [m] away at ``bearing`` [rad]."""
    pose = [0.3, 0.25, 1.0, 0.0, distance, math.cos(bearing), math.sin(bearing)]
    return np.array(pose + [0.3] * rays)


@pytest.mark.parametrize(
    ("world_seed", "control_period", "limit"), [(0, 1.0, 20), (2, 1.0, 20), (5, 0.1, 200)]
)
def test_reaches_the_goal_of_a_free_map_in_the_continuous_env(
    world_seed: int, control_period: float, limit: int
) -> None:
    """Without touching the border: from world 0's start the goal lies behind and the border
    5 cm ahead, where turning in place would swing the body into it; world 5 with 0.1 s actions
    ends next to a goal that plain sin-bearing steering circles."""
    env = gymnasium.make(
        ENV_ID, map_kind="free", world_seed=world_seed, slip="slippery", action="continuous",
        observation="features", control_period=control_period, max_episode_steps=limit,
    )  # fmt: skip
    tracker = GoalTracker()
    assert isinstance(tracker, WheelSpeedPolicy)
    features, _ = env.reset(seed=world_seed)
    start_distance = features[4]
    for _ in range(limit):
        action = np.array(tracker.wheel_speeds(features), dtype=np.float32)
        features, reward, terminated, truncated, info = env.step(action)
        assert not info["collision"]
        if terminated or truncated:
            break
    assert terminated and reward == 10.0
    assert features[4] < 0.02 < start_distance  # inside the goal cell (2.5 cm × 2 cm)


def test_turns_towards_a_goal_ahead_of_the_pivot_and_reverses_to_one_behind() -> None:
    tracker = GoalTracker()
    left, right = tracker.wheel_speeds(observation(0.2, 0.2))
    assert right > left > 0  # forward, curving left
    left, right = tracker.wheel_speeds(observation(0.2, -0.2))
    assert left > right > 0
    left, right = tracker.wheel_speeds(observation(0.2, 0.5))
    assert right > 0 > left  # the turn first: little left for the speed
    left, right = tracker.wheel_speeds(observation(0.03, 0.3))  # between centre and pivot
    assert left > right  # turning away: the skid slides the centre towards the goal
    left, right = tracker.wheel_speeds(observation(0.2, math.pi))
    assert left == pytest.approx(-1.7) and right == pytest.approx(-1.7)
    assert tracker.wheel_speeds(observation(0.2, -2.0)) == (-1.7, 1.7)  # rear towards the goal
    assert tracker.wheel_speeds(observation(0.0, 0.0)) == (0.0, 0.0)  # on the goal: stand still


@given(
    distance=st.floats(0.0, 0.8),
    bearing=st.floats(-math.pi, math.pi),
    distance_gain=st.floats(0.01, 100.0),
    turn_gain=st.floats(0.01, 100.0),
)
def test_wheel_speeds_stay_within_the_limit_and_follow_the_twist(
    distance: float, bearing: float, distance_gain: float, turn_gain: float
) -> None:
    robot = RobotParams()
    tracker = GoalTracker(GoalTrackerConfig(distance_gain, turn_gain), robot)
    left, right = tracker.wheel_speeds(observation(distance, bearing))
    assert max(abs(left), abs(right)) <= robot.wheel_speed
    speed, yaw_rate = tracker.twist(observation(distance, bearing))
    v_x, _, turn = body_velocities(left, right, 0.0, robot.wheel_radius, robot.half_track)
    assert v_x == pytest.approx(speed, abs=1e-12) and turn == pytest.approx(yaw_rate, abs=1e-12)
    assert speed * math.cos(bearing) >= 0.0  # towards the goal, forwards or backwards
    lateral = distance * math.sin(bearing)  # the goal's e_y, and its rate ψ̇ (x_ICR − e_x)
    assert lateral * yaw_rate * (robot.x_icr - distance * math.cos(bearing)) <= 0.0


def test_lidar_layout_and_bad_inputs() -> None:
    tracker = GoalTracker(GoalTrackerConfig(lidar_rays=0, lidar_range=1.0))
    assert (tracker.lidar_rays, tracker.lidar_range) == (0, 1.0)
    assert tracker.wheel_speeds(observation(0.1, 0.0, rays=0))[0] > 0
    with pytest.raises(ValueError, match=r"expected an observation of shape \(7,\)"):
        tracker.wheel_speeds(observation(0.1, 0.0, rays=8))
    with pytest.raises(ValueError, match="expected finite goal distance"):
        tracker.wheel_speeds(observation(math.nan, 0.0, rays=0))
    for bad in ({"turn_gain": 0.0}, {"distance_gain": math.inf}, {"distance_gain": True}):
        with pytest.raises(ValueError, match=r"expected .*_gain to be a finite number > 0"):
            GoalTrackerConfig(**bad)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="lidar_rays"):
        GoalTrackerConfig(lidar_rays=-1)
