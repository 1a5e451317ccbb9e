"""Saving and loading the linear agents: a round trip, and damaged files refused in one line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from skidnav.agents.linear.agent import LinearAgent
from skidnav.agents.linear.registry import CONTINUOUS_AGENT_MODULES, load_linear_agent
from skidnav.agents.training import train_agent
from skidnav.errors import CorruptFileError
from tests.saved_file_support import arrays_of, write_npz

from .support import make, small_pose_env

SMALL = {"tiles": [2], "planning_memory": 50}


def trained(name: str) -> LinearAgent:
    """Agent ``name`` with a small coder after 3 episodes of the tiny arena."""
    env = small_pose_env()
    agent = make(name, env, 5, **(SMALL if name == "linear-dyna" else {"tiles": [2]}))
    train_agent(agent, env, 3, max_steps=12, seed=5)
    return agent


def saved(name: str, tmp_path: Path) -> tuple[Path, Path]:
    return trained(name).save(tmp_path / "agent")


@pytest.mark.parametrize("name", list(CONTINUOUS_AGENT_MODULES))
def test_a_loaded_agent_continues_as_the_saved_one(name: str, tmp_path: Path) -> None:
    agent = trained(name)
    agent.save(tmp_path / "agent")
    loaded = load_linear_agent(tmp_path / "agent.npz")
    assert type(loaded) is type(agent) and loaded.config == agent.config
    for key, array in agent.state_arrays().items():
        assert loaded.state_arrays()[key].tobytes() == array.tobytes(), key
    assert (loaded.steps, loaded.episodes, loaded.planning_updates) == (
        agent.steps, agent.episodes, agent.planning_updates,
    )  # fmt: skip
    train_agent(agent, small_pose_env(), 3, max_steps=12, seed=6)
    train_agent(loaded, small_pose_env(), 3, max_steps=12, seed=6)
    assert loaded.w.tobytes() == agent.w.tobytes()


def edit_json(path: Path, key: str, value: object) -> None:
    meta = json.loads(path.read_text())
    meta[key] = value
    path.write_text(json.dumps(meta))


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("agent", "linear-nothing", "unknown agent"),
        ("n_actions", 10**9, "n_actions in"),
        ("low", [0.0, 0.0], "one shape"),
        ("high", "x", "bounds as a list"),
        ("config", {"tiles": [10**6]}, "features"),
        ("version", 99, "not a skidnav linear agent file"),
    ],
)
def test_a_damaged_json_is_one_line(key: str, value: object, message: str, tmp_path: Path) -> None:
    _, json_path = saved("linear-dyna", tmp_path)
    edit_json(json_path, key, value)
    with pytest.raises(CorruptFileError, match=message) as error:
        load_linear_agent(json_path)
    assert "\n" not in str(error.value) and str(json_path) in str(error.value)


def test_a_damaged_archive_is_one_line(tmp_path: Path) -> None:
    npz_path, _ = saved("linear-dyna", tmp_path)
    arrays = arrays_of(npz_path)
    cases = {
        "shape": {**arrays, "w": arrays["w"][:, :-1]},
        "missing": {key: value for key, value in arrays.items() if key != "visited"},
        "non-finite": {**arrays, "w": np.full_like(arrays["w"], np.nan)},
        "out of range": {**arrays, "visited": np.full_like(arrays["visited"], 10**6)},
    }
    messages = {
        "shape": "array 'w' is float64 of shape",
        "missing": "missing array 'visited'",
        "non-finite": "NaN",
        "out of range": "visited features outside",
    }
    for case, members in cases.items():
        write_npz(npz_path, members)
        with pytest.raises(CorruptFileError, match=messages[case]) as error:
            load_linear_agent(npz_path)
        assert "\n" not in str(error.value) and str(npz_path) in str(error.value), case
    npz_path.write_bytes(npz_path.read_bytes()[:100])
    with pytest.raises(CorruptFileError, match=r"not a readable \.npz"):
        load_linear_agent(npz_path)
