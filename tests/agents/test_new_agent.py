"""Adding an agent touches its own module and the registry, nothing else: the tiny agent of
``sample_average_agent.py``, registered here, runs step by step and fused with the same numbers,
learns the Dyna Maze, and saves and loads like the built-in agents."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import skidnav.envs  # noqa: F401  (registers the envs)
from skidnav.agents import catalog
from skidnav.agents.catalog import entry
from skidnav.agents.tabular import family as tabular_family
from skidnav.agents.tabular import registry
from skidnav.agents.tabular.agent import TabularAgent
from skidnav.agents.tabular.fast_training import train_agent_fast, train_for_steps_fast
from skidnav.agents.training import train_agent, train_for_steps
from skidnav.envs.mazes import dyna_maze


@pytest.fixture(autouse=True)
def _registered(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """The agent in the registry and in its family's descriptor (the line its module adds)."""
    monkeypatch.setitem(
        registry.AGENT_MODULES, "sample-average-q", "tests.agents.sample_average_agent"
    )
    described = dataclasses.replace(tabular_family.FAMILY, agents=tuple(registry.AGENT_MODULES))
    monkeypatch.setattr(tabular_family, "FAMILY", described)
    catalog.families.cache_clear()
    yield
    catalog.families.cache_clear()


def _agent(seed: int) -> registry.TabularAgent:
    return registry.make_agent(
        "sample-average-q", 54, 4, {"epsilon": 0.2}, np.random.default_rng(seed)
    )


def test_the_new_agent_runs_fused_with_the_numbers_of_the_step_by_step_loop() -> None:
    runs = []
    for trainer in (train_agent, train_agent_fast):
        agent = _agent(3)
        log = trainer(agent, dyna_maze(max_episode_steps=400), 40, max_steps=300, seed=3)
        runs.append((log, agent))
    (slow, slow_agent), (fast, fast_agent) = runs
    np.testing.assert_array_equal(fast.lengths, slow.lengths)
    np.testing.assert_array_equal(fast_agent.q, slow_agent.q)
    np.testing.assert_array_equal(fast_agent.visits, slow_agent.visits)
    assert fast_agent.visits.sum() == fast_agent.steps == slow.lengths.sum()
    assert slow.lengths[-10:].mean() < slow.lengths[:5].mean() / 3  # it learns the maze


def test_the_new_agent_on_the_navigation_env_and_a_step_budget() -> None:
    cumulative = [trainer(_agent(4), dyna_maze(), 2000, seed=4)
                  for trainer in (train_for_steps, train_for_steps_fast)]  # fmt: skip
    np.testing.assert_array_equal(cumulative[0], cumulative[1])
    env = gym.make("skidnav/SkidSteerNav-v0", map_kind="free", world_seed=0, max_episode_steps=60)
    n_states = env.observation_space.n  # type: ignore[attr-defined]
    logs = []
    for trainer in (train_agent, train_agent_fast):
        agent = registry.make_agent("sample-average-q", n_states, 4, None, np.random.default_rng(5))
        logs.append((trainer(agent, env, 3, seed=5), agent))
    np.testing.assert_array_equal(logs[0][0].returns, logs[1][0].returns)
    np.testing.assert_array_equal(logs[0][1].q, logs[1][1].q)


def test_the_new_agent_saves_and_loads(tmp_path: Path) -> None:
    agent = _agent(6)
    train_agent(agent, dyna_maze(max_episode_steps=200), 3, seed=6)
    npz_path, _ = agent.save(tmp_path / "tiny")
    loaded = registry.load_agent(npz_path)
    assert type(loaded).__name__ == "SampleAverageAgent"
    np.testing.assert_array_equal(loaded.visits, agent.visits)  # type: ignore[attr-defined]
    assert loaded.steps == agent.steps > 0


def test_the_catalog_describes_the_new_agent_from_the_registry() -> None:
    described = entry("sample-average-q")
    assert (described.family.name, described.observation) == ("tabular", "discrete")
    env = dyna_maze(max_episode_steps=400)
    built = described.build(env, {"epsilon": 0.2}, np.random.SeedSequence(3), 300)
    log = built.train(env, 5, max_steps=300)
    assert isinstance(built.agent, TabularAgent)
    assert built.agent.visits.sum() == built.agent.steps == log.lengths.sum() > 0
