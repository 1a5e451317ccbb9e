"""The classical navigator reaches the goal on a free map and through BARN worlds without its
footprint touching a cylinder, from an empty map every episode, reading only what every agent
gets."""

from __future__ import annotations

import numpy as np

import skidnav
from skidnav.agents import catalog
from skidnav.agents.classical.agent import ClassicalAgent
from tests.agents.classical.support import JACKAL, barn_env, drive
from tests.agents.mpc.support import SealedEnv


def test_it_reaches_the_goal_on_a_free_map() -> None:
    env = skidnav.make_env(
        "free", seed=1, observation="features", action="continuous", control_period=0.1,
        lidar_rays=16, lidar_range=0.5, max_episode_steps=600,
    )  # fmt: skip
    agent = skidnav.make_agent("classical", env)
    reached, steps, _ = drive(agent, env)
    assert reached and steps < 600


def test_it_drives_the_jackal_through_barn_worlds_without_touching_a_cylinder() -> None:
    """Worlds 0 and 230 (not among the tuning worlds): the goal 10 m away in about 6–10 s."""
    for world in (0, 230):
        env = barn_env(world)
        agent = skidnav.make_agent("classical", env, **JACKAL)
        reached, steps, touching = drive(agent, env)
        assert reached and steps <= 150 and touching == 0, (world, steps, touching)


def test_it_trains_through_an_env_that_exposes_only_the_gymnasium_api() -> None:
    """Made from the env's robot, cells and lidar layout; then every episode through a wrapper
    on which anything but reset, step and the spaces raises. Two episodes, the same actions:
    the second starts from an empty map again (nothing learned)."""
    env = barn_env(76)
    agent = ClassicalAgent.from_env(env, ClassicalAgent.config_class(**JACKAL))
    log = catalog.entry("classical").bind(agent).train(SealedEnv(env), 2, seed=0)
    assert log.successes.all() and log.lengths[0] == log.lengths[1]
    assert (log.collisions == 0).all() and agent.navigator.replans == 0  # forgotten


def test_greedy_rollouts_act_as_training_episodes() -> None:
    env = barn_env(151)
    agent = skidnav.make_agent("classical", env, **JACKAL)
    trained = drive(agent, env)
    agent.end_episode()
    agent.start_greedy_rollout()
    assert drive(agent, env, greedy=True) == trained
    observation, _ = env.reset(seed=0)
    agent.start_greedy_rollout()
    np.testing.assert_array_equal(agent.greedy_action(observation), agent.act(observation))
