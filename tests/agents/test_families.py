"""Every agent name through the public API with its defaults: make → train one episode → save →
load from what ``save_agent`` returned (and from the path given) → act the same; and every door
reads the families' descriptors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import skidnav
from skidnav.agents import catalog
from skidnav.agents.greedy import start_rollout
from skidnav.agents.saved import load_policy
from skidnav.errors import CorruptFileError, UserError

WHEEL_SPEED_AGENTS = {"ppo", "sac"}
"""Deep agents that drive wheel speeds (the deep family's other, DQN, takes discrete actions)."""


def env_for(name: str) -> object:
    """A small world for agent ``name``: its observation, its actions, 15 actions per episode."""
    described = catalog.entry(name)
    wheels = described.family.actions == "wheel-speeds" or name in WHEEL_SPEED_AGENTS
    options = {"action": "continuous"} if wheels else {}
    return skidnav.make_env(
        "free", seed=1, observation=described.env_observation(None), max_episode_steps=15,
        **options,
    )  # fmt: skip


def small(name: str) -> dict[str, object]:
    """Settings that keep one episode of ``name`` short (its defaults otherwise)."""
    return (
        {"population": 4, "episodes_per_candidate": 1, "eval_episodes": 1}
        if name == "cmaes"
        else {}
    )


@pytest.mark.parametrize("name", catalog.agent_names())
def test_every_agent_round_trips_through_the_api(name: str, tmp_path: Path) -> None:
    described = catalog.entry(name)
    if described.family.extra == "deep":
        pytest.importorskip("stable_baselines3")
    env = env_for(name)
    agent = skidnav.make_agent(name, env, seed=0, **small(name))
    log = skidnav.train(agent, env, 1, rollouts=1)
    assert len(log.lengths) >= 1 and log.greedy_lengths.shape[1] == 1
    observation, _ = env.reset(seed=3)
    start_rollout(agent)  # a planner with a state of its own starts each rollout afresh
    before = np.asarray(agent.greedy_action(observation))
    stem = tmp_path / "not-yet" / "agent"  # a folder that does not exist yet
    returned = skidnav.save_agent(agent, stem)
    for where in (returned, stem, returned[0]):
        loaded = skidnav.load_agent(where, env)
        assert loaded.name == name
        start_rollout(loaded)
        np.testing.assert_array_equal(np.asarray(loaded.greedy_action(observation)), before)
    if described.family.policy is not None and name != "dqn":
        policy = load_policy(returned)
        assert np.isfinite(policy.wheel_speeds(np.asarray(observation, np.float64))).all()


def test_every_name_belongs_to_exactly_one_family() -> None:
    names = catalog.agent_names()
    assert len(names) == len(set(names)) >= 18
    assert {"cmaes", "goal-tracker", "mppi-kinematic", "dyna-full"} <= set(names)
    formats = [f for family in catalog.families() for f in family.save_formats]
    assert len(formats) == len(set(formats))
    for name in names:
        assert catalog.entry(name).family.agents.count(name) == 1


def test_a_file_of_no_family_is_refused_in_one_line(tmp_path: Path) -> None:
    (tmp_path / "x.json").write_text('{"format": "other"}', encoding="utf-8")
    with pytest.raises(CorruptFileError, match="format 'other'"):
        skidnav.load_agent(tmp_path / "x")
    with pytest.raises(UserError, match="its two files"):
        skidnav.load_agent((tmp_path / "x.npz", tmp_path / "y.npz"))


def test_a_tabular_agent_is_no_wheel_speed_policy(tmp_path: Path) -> None:
    env = skidnav.make_env("free", seed=1)
    saved = skidnav.save_agent(skidnav.make_agent("q-learning", env), tmp_path / "q")
    with pytest.raises(UserError, match="does not drive by wheel speeds"):
        load_policy(saved)
