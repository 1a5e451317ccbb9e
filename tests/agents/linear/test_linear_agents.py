"""The linear agents: hand-computed updates, Linear Dyna without planning = linear Q-learning,
learning a tiny task, their configs."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.spaces import Box

from skidnav.agents.linear.agent import LinearAgent
from skidnav.agents.linear.config import LinearConfig, LinearDynaConfig
from skidnav.agents.linear.dyna import LinearDynaAgent
from skidnav.agents.linear.q_learning import LinearQAgent
from skidnav.agents.linear.registry import CONTINUOUS_AGENT_MODULES, make_linear_agent
from skidnav.agents.linear.sarsa import LinearSarsaAgent
from skidnav.agents.linear.updates import model_update
from skidnav.agents.training import train_agent
from skidnav.errors import UserError

from .support import make, small_pose_env

UNIT = (np.array([0.0]), np.array([1.0]))
"""A 1-D observation in [0, 1]; with 1 tile and 2 tilings (offsets 0 and 1/2) there are 2 × 2
features: x = 0.2 activates {0, 2} (⌊0.2⌋, 2 + ⌊0.7⌋), x = 0.8 activates {0, 3}."""


def unit_agent(cls: type, **options: object) -> LinearQAgent:
    config = cls.config_class(alpha=0.5, gamma=0.9, tiles=(1,), n_tilings=2, **options)
    return cls(*UNIT, 2, config, np.random.default_rng(0))  # type: ignore[no-any-return]


def test_a_linear_q_update_by_hand() -> None:
    agent = unit_agent(LinearQAgent)
    assert agent.features([0.2]).tolist() == [0, 2] and agent.features([0.8]).tolist() == [0, 3]
    agent.w[0, 0], agent.w[1, 3] = 1.0, 4.0
    # q(s, 0) = 1; max_a q(s', a) = q(s', 1) = 4; δ = 1 + 0.9 · 4 − 1 = 3.6; step α/2 = 0.25
    agent.observe([0.2], 0, 1.0, [0.8], terminated=False)
    assert agent.w[0].tolist() == pytest.approx([1.9, 0.0, 0.9, 0.0])
    assert agent.q_values([0.2])[0] == pytest.approx(1.0 + 0.5 * 3.6)
    # terminated: the target is the reward alone: δ = −1 − 2.8, each weight −0.95
    agent.observe([0.2], 0, -1.0, [0.8], terminated=True)
    assert agent.w[0].tolist() == pytest.approx([0.95, 0.0, -0.05, 0.0])
    assert agent.w[1].tolist() == [0.0, 0.0, 0.0, 4.0]


def test_sarsa_uses_and_then_takes_the_action_it_chose() -> None:
    agent = unit_agent(LinearSarsaAgent, lam=0.5, epsilon=0.0)
    agent.w[1, 3] = 4.0  # greedy in s' = 0.8: action 1, q(s', 1) = 4
    agent.observe([0.2], 0, 1.0, [0.8], terminated=False)
    # δ = 1 + 0.9 · 4 − 0 = 4.6, z[0, {0, 2}] = 1: w[0, {0, 2}] = 0.25 · 4.6; then z ← γλ z
    assert agent.w[0].tolist() == pytest.approx([1.15, 0.0, 1.15, 0.0])
    assert agent.traces[0].tolist() == pytest.approx([0.45, 0.0, 0.45, 0.0])
    agent.w[0, 3] = 10.0  # the greedy action in s' is now 0, but Sarsa committed to 1
    assert agent.act([0.8]) == 1
    agent.end_episode()
    assert not agent.traces.any()


def test_the_model_is_exact_after_one_update_with_unit_step() -> None:
    # Normalised LMS on binary features: with step 1 / n_tilings, F_a x = x' and b_aᵀ x = r.
    next_model, reward_model, predicted = np.zeros((2, 4, 4)), np.zeros((2, 4)), np.zeros(4)
    tiles, next_tiles = np.array([0, 2]), np.array([0, 3])
    model_update(next_model, reward_model, tiles, 1, -1.0, next_tiles, False, 0.5, predicted)
    assert next_model[1, [0, 2]].sum(axis=0).tolist() == [1.0, 0.0, 0.0, 1.0]
    assert reward_model[1, tiles].sum() == -1.0 and not next_model[0].any()
    model_update(next_model, reward_model, tiles, 1, 10.0, next_tiles, True, 0.5, predicted)
    assert next_model[1, [0, 2]].sum(axis=0).tolist() == [0.0, 0.0, 0.0, 0.0]  # x' = 0
    assert reward_model[1, tiles].sum() == 10.0


def test_linear_dyna_without_planning_is_linear_q_learning_bit_for_bit() -> None:
    env_q, env_dyna = small_pose_env(), small_pose_env()
    q_agent = make("linear-q", env_q, 3)
    dyna = make("linear-dyna", env_dyna, 3, planning_steps=0)
    log_q = train_agent(q_agent, env_q, 20, max_steps=30, seed=3)
    log_dyna = train_agent(dyna, env_dyna, 20, max_steps=30, seed=3)
    assert q_agent.w.tobytes() == dyna.w.tobytes() and q_agent.w.any()
    assert log_q.lengths.tolist() == log_dyna.lengths.tolist()
    assert q_agent.rng.bit_generator.state == dyna.rng.bit_generator.state
    assert dyna.planning_updates == 0 and dyna.reward_model.any()


@pytest.mark.parametrize("name", list(CONTINUOUS_AGENT_MODULES))
def test_each_agent_learns_to_reach_the_goal(name: str) -> None:
    # 80 episodes of at most 12 actions (the goal is 5 forward actions away), seed 0.
    env = small_pose_env()
    agent = make(name, env, 0)
    log = train_agent(agent, env, 80, max_steps=12, seed=0)
    first, last = log.successes[:20].mean(), log.successes[-20:].mean()
    assert last >= 0.8 and last > first  # measured: q 0.25 → 1.0, sarsa 0.6 → 0.85, dyna 0.2 → 1.0
    assert log.lengths[-20:].mean() < log.lengths[:20].mean()
    assert greedy_length(agent, env, 12) <= 9  # shortest: 5


def greedy_length(agent: LinearAgent, env: gym.Env[Any, Any], limit: int) -> int:
    """Actions of the greedy policy to the goal (limit + 1 if it does not get there)."""
    observation, _ = env.reset(seed=1)
    for step in range(1, limit + 1):
        observation, _, terminated, _, _ = env.step(agent.greedy_action(observation))
        if terminated:
            return step
    return limit + 1


def test_planning_counts_its_updates() -> None:
    env = small_pose_env()
    agent = make("linear-dyna", env, 0, planning_steps=7)
    train_agent(agent, env, 2, max_steps=10, seed=0)
    assert agent.steps == 20 and agent.planning_updates == 140


def test_a_model_too_large_is_refused_before_allocation() -> None:
    space = Box(low=np.zeros(3), high=np.ones(3), dtype=np.float64)
    with pytest.raises(UserError, match=r"at most 134,217,728 bytes .* got 2,048,000,000") as error:
        make_linear_agent("linear-dyna", space, 4, {"tiles": [9], "n_tilings": 8})
    assert "\n" not in str(error.value)
    agent = make_linear_agent("linear-q", space, 4, {"tiles": [9], "n_tilings": 8})
    assert agent.n_features == 8000  # the model-free agents take it


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"tiles": []}, "tiles as a non-empty list"),
        ({"tiles": [4, 0]}, "tiles as a non-empty list"),
        ({"n_tilings": 0}, "n_tilings in"),
        ({"alpha": 2.0}, "alpha in"),
        ({"tiles": [4, 4]}, "1 or 3 tile counts for 3 tiled"),
        ({"stray": 1}, "unknown"),
    ],
)
def test_bad_configs_are_one_line_errors(options: dict[str, object], message: str) -> None:
    space = Box(low=np.zeros(3), high=np.ones(3), dtype=np.float64)
    with pytest.raises(UserError, match=message) as error:
        make_linear_agent("linear-q", space, 4, options)
    assert "\n" not in str(error.value) and "linear-q" in str(error.value)


def test_configs_are_validated_and_frozen() -> None:
    with pytest.raises(ValueError, match="planning_memory"):
        LinearDynaConfig(planning_memory=0)
    config = LinearConfig(tiles=[2, 3, 4])
    assert config.tiles == (2, 3, 4) and LinearConfig.from_mapping(config.to_dict()) == config
    assert LinearDynaAgent.config_class is LinearDynaConfig


def test_observations_are_checked() -> None:
    agent = unit_agent(LinearQAgent)
    with pytest.raises(ValueError, match=r"finite observation of shape \(1,\)"):
        agent.act([np.nan])
    with pytest.raises(ValueError, match="shape"):
        agent.observe([0.1, 0.2], 0, 0.0, [0.3], False)


def test_a_few_dimensions_of_a_wide_observation_are_tiled() -> None:
    # 15 dimensions: all of them jointly would be 8 · 5¹⁵ features; three take 8 · 5³.
    space = Box(low=-np.ones(15), high=np.ones(15), dtype=np.float64)
    with pytest.raises(UserError, match="features"):
        make_linear_agent("linear-q", space, 4)
    agent = make_linear_agent("linear-dyna", space, 4, {"dimensions": [4, 5, 6]})
    assert agent.n_features == 1000
    observation = np.zeros(15)
    observation[[4, 5, 6]] = [0.3, -0.2, 0.9]
    noise = np.where(np.isin(np.arange(15), [4, 5, 6]), 0.0, 0.7)
    assert agent.features(observation).tolist() == agent.features(observation + noise).tolist()
    with pytest.raises(UserError, match="dimensions below 15"):
        make_linear_agent("linear-q", space, 4, {"dimensions": [15]})
