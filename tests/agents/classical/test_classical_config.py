"""The classical navigator's settings from a config (a bad one is one line), and its saved file
(.npz + .json): loaded back, the same navigator; damaged, one line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import skidnav
from skidnav.agents import catalog
from skidnav.agents.classical.agent import ClassicalAgent
from skidnav.agents.saved import load_policy
from skidnav.errors import CorruptFileError, UserError
from tests.agents.classical.support import JACKAL, barn_env


@pytest.mark.parametrize(
    ("params", "message"),
    [
        ({"horizont": 1.0}, "unknown key 'horizont'"),
        ({"horizon": 0}, "expected horizon to be a finite number in"),
        ({"yaw_rate_samples": 4}, "expected yaw_rate_samples to be odd"),
        ({"footprint_width": -0.1}, "expected footprint_width"),
        ({"ray_stride": 1.5}, "expected ray_stride to be an integer"),
        ({"speed_weight": "fast"}, "expected speed_weight to be a number, got 'fast'"),
    ],
)
def test_a_bad_setting_is_one_line_naming_the_agent(
    params: dict[str, object], message: str
) -> None:
    with pytest.raises(UserError, match=message) as caught:
        catalog.entry("classical").config(params)
    assert "agent 'classical'" in str(caught.value) and "\n" not in str(caught.value)
    with pytest.raises(UserError, match=message):
        skidnav.make_agent("classical", barn_env(1), **params)


def test_it_refuses_an_env_of_discrete_actions() -> None:
    with pytest.raises(UserError, match=r"agent 'classical'.*action"):
        skidnav.make_agent("classical", skidnav.make_env("free", observation="features"))


def test_saved_and_loaded_it_is_the_same_navigator(tmp_path: Path) -> None:
    env = barn_env(299)
    agent = skidnav.make_agent("classical", env, horizon=1.2, **JACKAL)
    _, json_path = skidnav.save_agent(agent, tmp_path / "nav" / "agent")
    loaded = skidnav.load_agent(json_path, env)
    assert isinstance(loaded, ClassicalAgent) and loaded.config == agent.config
    policy = load_policy(json_path)
    observation, _ = env.reset(seed=0)
    for _ in range(20):
        action = agent.act(observation)
        np.testing.assert_array_equal(loaded.act(observation), action)
        assert policy.wheel_speeds(observation) == tuple(action)
        observation, *_ = env.step(action)
    meta = json.loads(json_path.read_text(encoding="utf-8"))
    meta["laser"]["field_of_view"] = 7.0
    json_path.write_text(json.dumps(meta), encoding="utf-8")
    with pytest.raises(CorruptFileError, match="field of view") as caught:
        skidnav.load_agent(json_path, env)
    assert "\n" not in str(caught.value)
