"""The catalog describes each agent once (:func:`skidnav.agents.catalog.entry`): its family, the
observation it learns over, its config, how it is built and trained; each family's agents
answer their protocol (:mod:`skidnav.agents.interface`)."""

from __future__ import annotations

import sys
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import skidnav.envs  # noqa: F401  (registers the env)
from skidnav.agents.catalog import agent_names, entry
from skidnav.agents.deep.dqn import DQNConfig
from skidnav.agents.interface import Agent, EpisodeTrainingAgent, StepLearningAgent
from skidnav.agents.linear.config import LinearConfig
from skidnav.agents.tabular.config import DynaQConfig
from skidnav.agents.training import TrainingLog
from skidnav.envs.mazes import dyna_maze
from skidnav.errors import UserError

DQN_PARAMS = {"learning_starts": 50, "buffer_size": 1000, "hidden": [16]}


def _pose_env() -> gym.Env[Any, Any]:
    return gym.make(
        "skidnav/SkidSteerNav-v0", map_kind="free", world_seed=0, observation="pose",
        max_episode_steps=30,
    )  # fmt: skip


def test_each_name_is_described_once_with_its_family_observation_and_config() -> None:
    described = {name: entry(name) for name in ("dyna-q", "linear-q", "dqn")}
    assert [(e.family.name, e.observation) for e in described.values()] == [
        ("tabular", "discrete"), ("linear", "box"), ("deep", "box"),
    ]  # fmt: skip
    assert described["dyna-q"].config_class is DynaQConfig
    assert described["linear-q"].config_class is LinearConfig
    assert described["dqn"].config_class is DQNConfig  # the deep module, not PyTorch, imported
    assert described["dyna-q"].config({"planning_steps": 3}) == DynaQConfig(planning_steps=3)
    assert {"q-learning", "linear-dyna-kinematic", "sac"} <= set(agent_names())


def test_an_unknown_name_is_refused_naming_the_known_agents() -> None:
    with pytest.raises(
        UserError, match=r"unknown agent 'dyna-z'; expected one of q-learning, "
    ) as e:
        entry("dyna-z")
    assert "linear-q" in str(e.value) and "dqn" in str(e.value) and "\n" not in str(e.value)


@pytest.mark.parametrize(
    ("name", "params", "message"),
    [
        (
            "dyna-q",
            {"planning_steps": -1},
            r"^expected an integer planning_steps .* in agent 'dyna-q'$",
        ),
        ("linear-q", {"n_tilings": 0}, r"^expected an integer n_tilings .* in agent 'linear-q'$"),
        ("dqn", {"bogus": 1}, "unknown key 'bogus' in agent 'dqn': dqn"),
    ],
)
def test_bad_parameters_are_refused_in_one_line_naming_the_agent(
    name: str, params: dict[str, Any], message: str
) -> None:
    with pytest.raises(UserError, match=message) as error:
        entry(name).config(params)
    assert "\n" not in str(error.value)


def test_the_observation_each_agent_learns_over() -> None:
    assert entry("q-learning").env_observation("pose") == "discrete"  # always the discrete state
    assert entry("linear-q").env_observation(None) == "features"
    assert entry("dqn").env_observation("pose") == "pose"
    with pytest.raises(UserError, match="'linear-q' learns over a Box observation"):
        entry("linear-q").env_observation("discrete")
    with pytest.raises(UserError, match="'linear-q' learns over a Box observation, the env"):
        entry("linear-q").build(dyna_maze(), {}, np.random.SeedSequence(0), 10)


def _trained_linear_q(bound_again: bool) -> tuple[Any, TrainingLog]:
    """linear-q built by the catalog and trained 3 episodes, as built or bound again to its
    entry (as an agent loaded from a file is)."""
    env = _pose_env().unwrapped
    built = entry("linear-q").build(env, {"tiles": [3]}, np.random.SeedSequence(2), 30)
    env.reset(seed=5)
    if bound_again:
        bound = entry("linear-q").bind(built.agent)
        return bound.agent, bound.train(env, 3, max_steps=30)
    return built.agent, built.train(env, 3, max_steps=30)


def test_step_learners_answer_their_protocol_and_train_alike_when_bound_again() -> None:
    (linear, log), (_, bound_log) = _trained_linear_q(False), _trained_linear_q(True)
    np.testing.assert_array_equal(log.returns, bound_log.returns)
    assert log.lengths.sum() > 3
    assert isinstance(linear, StepLearningAgent) and not isinstance(linear, EpisodeTrainingAgent)
    tabular = entry("dyna-q").build(dyna_maze(), {}, np.random.SeedSequence(0), 10).agent
    assert isinstance(tabular, StepLearningAgent) and isinstance(tabular, Agent)
    with pytest.raises(TypeError, match="expected a DynaQAgent agent, got LinearQAgent"):
        entry("dyna-q").bind(linear)


def test_a_deep_agent_trains_by_episodes() -> None:
    pytest.importorskip("stable_baselines3")
    env = _pose_env()
    built = entry("dqn").build(env.unwrapped, DQN_PARAMS, np.random.SeedSequence(1), 30)
    assert isinstance(built.agent, EpisodeTrainingAgent)
    assert not isinstance(built.agent, StepLearningAgent)
    log = built.train(env.unwrapped, 2, max_steps=30)
    assert log.returns.shape == (2,) and (log.lengths >= 1).all()


def test_a_deep_agent_without_the_deep_extra_is_refused_in_one_line(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setitem(sys.modules, "torch", None)  # import torch: ModuleNotFoundError
    env = _pose_env()
    with pytest.raises(UserError, match=r"^agent 'dqn' needs the deep extra .*'torch'") as e:
        entry("dqn").build(env.unwrapped, DQN_PARAMS, np.random.SeedSequence(1), 30)
    assert "\n" not in str(e.value)
