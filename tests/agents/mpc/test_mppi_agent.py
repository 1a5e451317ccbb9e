"""mppi-kinematic: it reaches a goal behind a wall, learns the robot from its log, reads nothing
of the world but what every agent gets, and hands out a wheel-speed policy."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from skidnav.agents.greedy import greedy_run
from skidnav.agents.mpc.agent import MPPIKinematicAgent, make_mppi_agent
from skidnav.agents.mpc.training import train_mppi
from skidnav.agents.training import Evaluation
from skidnav.agents.wheel_policy import WheelSpeedPolicy
from skidnav.errors import UserError
from skidnav.world.discretization import Discretization
from tests.agents.mpc.support import (
    SAME_START_AND_GOAL,
    WALL_BETWEEN,
    SealedEnv,
    agent_for,
    nav_env,
)


def test_with_the_true_model_it_reaches_a_goal_behind_a_wall_in_its_first_episode() -> None:
    """The walls are learned (the map starts empty); only the kinematics are given. A straight
    line from the start runs into the wall; the route around it is about 55 cm, 150 actions of
    0.1 s at top speed."""
    env = nav_env(WALL_BETWEEN)
    agent = agent_for(env, seed=0, true=True)
    log = train_mppi(agent, SealedEnv(env), 1, max_steps=600, seed=0)
    assert log.successes[0] and log.lengths[0] < 600
    assert log.collisions[0] >= 1  # it found the wall by running into it
    assert agent.evidence.cost_map.blocked[6, 3:8].any()  # a cell of the real wall is blocked
    assert not agent.evidence.cost_map.blocked[~env.unwrapped.grid_map.occupancy].any()


def test_with_the_learned_model_it_gets_past_the_wall_and_its_policy_too() -> None:
    env = nav_env(WALL_BETWEEN)
    agent = agent_for(env, seed=1)
    evaluation = SealedEnv(nav_env(WALL_BETWEEN))
    log = train_mppi(
        agent, SealedEnv(env), 2, max_steps=600, evaluation=Evaluation(evaluation), seed=1
    )
    assert log.successes.all()
    assert (log.greedy_lengths[-1] > 0).all()  # the frozen planner reached the goal too
    assert (log.planning_updates == log.lengths * 64).all()  # K sequences per action
    assert agent.model.refits >= 1 and agent.steps == log.lengths.sum()


def test_it_reads_only_the_robot_the_discretization_the_goal_and_the_lidar_layout() -> None:
    real = nav_env().unwrapped
    facts = SimpleNamespace(
        robot=real.robot, discretization=real.discretization,
        grid_map=SimpleNamespace(goal=real.grid_map.goal), features=real.features,
    )  # fmt: skip
    agent = MPPIKinematicAgent.from_env(SimpleNamespace(unwrapped=facts))
    assert agent.goal == real.grid_map.goal
    with pytest.raises(AttributeError, match=r"env\.task"):
        SealedEnv(nav_env()).task  # noqa: B018  (the sealed env refuses what an agent may not read)


def test_two_worlds_it_cannot_tell_apart_get_the_same_actions() -> None:
    """Same start, goal and floor, different walls: until the robot meets a difference, an agent
    that does not read the map acts the same in both, draw for draw."""
    actions = []
    for text in (WALL_BETWEEN, SAME_START_AND_GOAL):
        env = nav_env(text)
        agent = agent_for(env, seed=3)
        observation, _ = env.reset(seed=3)
        taken = []
        for _ in range(15):
            action = agent.act(observation)
            next_observation, reward, terminated, truncated, info = env.step(action)
            agent.observe(
                observation, action, reward, next_observation, terminated, truncated, info
            )
            observation = next_observation
            taken.append(action)
        actions.append(np.array(taken))
    assert actions[0].tobytes() == actions[1].tobytes()


def test_the_learned_model_improves_with_data() -> None:
    """Where the robot starts on world 2's slippery floor a wheel loses U(0, 1.7) rad/s, half
    its top speed on average: the nominal prior overstates the speed twice over. After some
    driving the mean forward speed of the regions driven through is near the floor's expected
    one, the log's velocities are better predicted, and the posterior spread is below the
    prior's."""
    env = nav_env(SAME_START_AND_GOAL, slip="slippery", world_seed=2)
    agent = agent_for(env, seed=0)
    rng = np.random.default_rng(0)
    logs = []
    env.reset(seed=0)
    for _ in range(300):
        info = env.step(rng.uniform(-1.7, 1.7, 2))[4]
        logs.append(info["kinematic_log"])
    held_out, training = np.concatenate(logs[::2]), logs[1::2]
    driven = np.unique(held_out[:, 0].astype(int))
    expected = env.unwrapped.slip_field.expected_velocities(env.unwrapped.robot)[driven, 0, 0]
    before = twist_error(agent, held_out), forward_error(agent, driven, expected)
    prior_spread = agent.dynamics.factors.copy()
    observation, _ = env.reset(seed=0)
    for log in training:
        info = {"kinematic_log": log, "collision": False}
        agent.observe(observation, np.zeros(2), -1.0, observation, False, False, info)
    assert agent.model.refits >= 1
    after = twist_error(agent, held_out), forward_error(agent, driven, expected)
    assert after[0] < 0.8 * before[0] and after[1] < 0.4 * before[1]
    assert (agent.dynamics.factors[driven, 0] < prior_spread[driven, 0]).all()


def forward_error(agent: MPPIKinematicAgent, regions: np.ndarray, expected: np.ndarray) -> float:
    """Largest error [m/s] of the agent's mean v_x at full forward speed in ``regions``."""
    mean = agent.dynamics.mean[regions]
    return float(np.abs((mean[:, 0] + mean[:, 1]) * 1.7 + mean[:, 2] - expected).max())


def twist_error(agent: MPPIKinematicAgent, log: np.ndarray) -> float:
    """Mean absolute error [m/s] of the agent's mean v_x on kinematic-log rows."""
    mean = agent.dynamics.mean[log[:, 0].astype(int)]
    predicted = mean[:, 0] * log[:, 1] + mean[:, 1] * log[:, 2] + mean[:, 2]
    return float(np.abs(predicted - log[:, 3]).mean())


def test_the_frozen_policy_is_a_wheel_speed_policy_on_features_and_poses() -> None:
    env = nav_env()
    agent = agent_for(env, seed=0)
    policy = agent.policy(seed=4)
    assert isinstance(policy, WheelSpeedPolicy)
    pose = np.array([0.15, 0.25, 0.3])
    clear = np.full(agent.lidar_rays, agent.lidar_range)  # every ray at its limit: no wall
    features = np.concatenate([[0.15, 0.25, np.cos(0.3), np.sin(0.3)], np.zeros(3), clear])
    from_pose = policy.wheel_speeds(pose)
    policy.reset()
    policy.planner.rng = np.random.default_rng(4)
    assert policy.wheel_speeds(features) == pytest.approx(from_pose, abs=1e-12)
    assert all(abs(w) <= 1.7 for w in from_pose)
    agent.evidence.hits[6, 5] = 5  # later learning does not reach a frozen policy
    agent.evidence.reweigh(agent.dynamics.mean)
    assert not policy.evidence.cost_map.blocked[6, 5]
    rollout = greedy_run(agent, SealedEnv(env), 5, seed=0)
    assert rollout.length == -1  # five actions do not reach the goal


def test_bad_settings_are_one_line_errors() -> None:
    env = nav_env()
    for options, expected in [
        ({"samples": 1}, "samples"),
        ({"temperature": -1.0}, "temperature"),
        ({"noise_correlation": 1.0}, "noise_correlation"),
        ({"cost_to_go": "roads"}, "cost_to_go"),
        ({"lattice_durations": [0.05]}, "lattice duration"),
        ({"kinematic_model": "true"}, "true coefficients"),
        ({"samples": 65_536, "horizon": 1000}, "samples × horizon × model_draws"),
        ({"model_draws": 0}, "model_draws"),
        ({"risk": "hope"}, "risk"),
        ({"precision": "float16"}, "precision"),
        ({"colour": "red"}, "unknown"),
    ]:
        with pytest.raises(UserError, match=expected) as caught:
            make_mppi_agent(env, options)
        assert "\n" not in str(caught.value) and str(caught.value).startswith(
            "agent 'mppi-kinematic'"
        )


def test_a_lattice_duration_must_be_whole_sub_steps() -> None:
    with pytest.raises(ValueError, match="whole number"):
        agent_for(nav_env(), lattice_durations=(0.25,))
    grid = Discretization(n_x=13, n_y=11)
    env = nav_env(discretization=grid)
    assert agent_for(env, lattice_durations=(0.3,)).evidence.lattice.action_steps[0] == 3.0
