"""DQN (Stable-Baselines3) on a tiny map: it learns; its saved files round-trip or are refused."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

import skidnav.envs  # noqa: F401  (registers the env)
from skidnav.agents.deep.dqn import DQNAgent, DQNConfig, load_dqn
from skidnav.errors import CorruptFileError
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization
from skidnav.world.mapfile import parse_map

TINY = """skidnav-map 1
width 8
height 8
map
########
#......#
#......#
#.S..G.#
#......#
#......#
#......#
########
"""
"""A 0.2 m arena: the goal 3 cells (7.5 cm, two forward actions) ahead of the start."""

CONFIG = DQNConfig(
    learning_starts=200, exploration_steps=2000, target_update_interval=200, learning_rate=5e-4
)


def tiny_env(observation: str = "pose", slip: str = "thesis") -> gym.Env[Any, Any]:
    return gym.make(
        "skidnav/SkidSteerNav-v0", grid_map=parse_map(TINY), observation=observation, slip=slip,
        robot=RobotParams(arena_width=0.2, arena_height=0.2),
        discretization=Discretization(n_x=8, n_y=8, n_headings=10, arena_width=0.2,
                                      arena_height=0.2),
        max_episode_steps=30,
    )  # fmt: skip


def greedy_episode(agent: DQNAgent, env: gym.Env[Any, Any], seed: int) -> tuple[bool, int]:
    """(goal reached, actions) of one greedy episode."""
    observation, _ = env.reset(seed=seed)
    for step in range(1, 31):
        observation, _, terminated, truncated, _ = env.step(agent.greedy_action(observation))
        if terminated or truncated:
            return terminated, step
    return False, 30


@pytest.fixture(scope="module")
def trained() -> tuple[DQNAgent, Any]:
    agent = DQNAgent(tiny_env(), CONFIG, seed=0)
    return agent, agent.train_episodes(150)


def test_dqn_learns_to_reach_a_near_goal(trained: tuple[DQNAgent, Any]) -> None:
    agent, log = trained
    assert len(log.returns) == 150 and agent.episodes == 150
    assert log.successes[-20:].mean() >= 0.8 > log.successes[:20].mean() - 0.2  # measured 0.95, 0.6
    reached, actions = greedy_episode(agent, tiny_env(), seed=5)
    assert reached and actions <= 4


def test_a_saved_dqn_acts_the_same_after_loading(
    trained: tuple[DQNAgent, Any], tmp_path: Path
) -> None:
    agent, _ = trained
    agent.save(tmp_path / "dqn")
    loaded = load_dqn(tmp_path / "dqn", tiny_env())
    for name, value in agent.weights().items():
        assert np.array_equal(loaded.weights()[name], value)
    observations = tiny_env().observation_space.sample()[None].repeat(1, 0)
    assert loaded.greedy_action(observations[0]) == agent.greedy_action(observations[0])


def test_a_damaged_or_foreign_dqn_file_is_one_line(
    trained: tuple[DQNAgent, Any], tmp_path: Path
) -> None:
    agent, _ = trained
    agent.save(tmp_path / "dqn")
    (tmp_path / "dqn.npz").write_bytes(b"not a zip archive")
    with pytest.raises(CorruptFileError, match=r"dqn\.npz") as error:
        load_dqn(tmp_path / "dqn", tiny_env())
    assert "\n" not in str(error.value)
    agent.save(tmp_path / "other")
    with pytest.raises(CorruptFileError, match="another observation space"):
        load_dqn(tmp_path / "other", tiny_env(observation="discrete"))


def test_bad_settings_are_one_line() -> None:
    with pytest.raises(ValueError, match=r"dqn: gamma = 1\.5 is out of range"):
        DQNConfig(gamma=1.5)
    with pytest.raises(ValueError, match="unknown key 'alpha' in dqn"):
        DQNConfig.from_mapping({"alpha": 0.1})
    with pytest.raises(ValueError, match="expected a Box observation"):
        DQNAgent(tiny_env(observation="discrete"))


def test_a_seeded_call_resets_its_first_episode_with_the_seed() -> None:
    """On a slippery floor the noise follows the reset seed: the same seed gives the same
    episodes whatever the call before left in the env, another seed others."""
    returns = []
    for seed in (3, 3, 4):
        agent = DQNAgent(tiny_env(slip="slippery"), CONFIG, seed=0)
        agent.train_episodes(2)
        returns.append(agent.train_episodes(3, seed=seed).returns.tolist())
    assert returns[0] == returns[1] != returns[2]
