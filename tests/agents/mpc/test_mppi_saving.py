"""Saving and loading mppi-kinematic: a round trip plans on as if never saved; a damaged file is
one line naming it."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from skidnav.agents.mpc.agent import MPPIKinematicAgent
from skidnav.agents.mpc.loading import load_mppi_agent, policy_from_file
from skidnav.agents.training import run_episode
from skidnav.agents.wheel_policy import WheelSpeedPolicy
from skidnav.errors import CorruptFileError
from tests.agents.mpc.support import agent_for, nav_env


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> tuple[MPPIKinematicAgent, Path]:
    """An agent that drove 250 actions into the wall (a refit, hits, blocked cells), saved."""
    env = nav_env()
    agent = agent_for(env, seed=2)
    observation, _ = env.reset(seed=2)
    run_episode(agent, env, observation, 250)
    assert agent.model.refits >= 1 and agent.evidence.hits.sum() >= 1
    path = tmp_path_factory.mktemp("saved") / "mppi"
    agent.save(path)
    return agent, path


def test_a_loaded_agent_plans_and_learns_on_as_the_saved_one(
    trained: tuple[MPPIKinematicAgent, Path],
) -> None:
    original, path = trained
    loaded = load_mppi_agent(path)
    saved, restored = original.state_arrays(), loaded.state_arrays()
    assert saved.keys() == restored.keys()
    for name in saved:
        assert saved[name].tobytes() == restored[name].tobytes(), name
    assert loaded.metadata() == original.metadata()
    for name, array in original.evidence.cost_map._asdict().items():
        assert array.tobytes() == getattr(loaded.evidence.cost_map, name).tobytes(), name
    env_a, env_b = nav_env(), nav_env()
    for agent, env in ((original, env_a), (loaded, env_b)):
        observation, _ = env.reset(seed=9)
        run_episode(agent, env, observation, 120)  # a refit (at 400 samples) on the way
    assert original.model.refits == loaded.model.refits >= 2
    for name, array in original.state_arrays().items():
        assert array.tobytes() == loaded.state_arrays()[name].tobytes(), name


def test_its_laser_map_is_saved_and_learned_on_after_loading(tmp_path: Path) -> None:
    """On feature observations: the readings' evidence and the episode's step count come back,
    and the loaded agent maps on as the saved one."""
    env = nav_env(observation="features")
    agent = agent_for(env, seed=5)
    observation, _ = env.reset(seed=5)
    for _ in range(40):
        action = agent.act(observation)
        next_observation, reward, terminated, truncated, info = env.step(action)
        agent.observe(observation, action, reward, next_observation, terminated, truncated, info)
        observation = next_observation
    assert agent.evidence.ray_ends.sum() > 0 and agent.episode_steps == 40
    agent.save(tmp_path / "mppi")
    loaded = load_mppi_agent(tmp_path / "mppi")
    assert loaded.episode_steps == 40
    assert loaded.evidence.cost_map.blocked.tobytes() == agent.evidence.cost_map.blocked.tobytes()
    for each in (agent, loaded):
        env = nav_env(observation="features")
        start, _ = env.reset(seed=6)
        run_episode(each, env, start, 30)
    for name, array in agent.state_arrays().items():
        assert array.tobytes() == loaded.state_arrays()[name].tobytes(), name


def test_its_saved_planner_loads_as_a_wheel_speed_policy(
    trained: tuple[MPPIKinematicAgent, Path],
) -> None:
    original, path = trained
    json_path = path.with_name("mppi.json")
    policy = policy_from_file(json_path, json.loads(json_path.read_text()))
    assert isinstance(policy, WheelSpeedPolicy)
    pose = np.array([0.2, 0.25, 0.0])
    assert policy.wheel_speeds(pose) == original.policy(seed=0).wheel_speeds(pose)


def damaged_copy(path: Path, folder: Path, edit_json: Any = None, edit_arrays: Any = None) -> Path:
    """A copy of the saved agent at ``path`` in ``folder``, its JSON and arrays edited."""
    meta = json.loads(path.with_name("mppi.json").read_text())
    with np.load(path.with_name("mppi.npz")) as archive:
        arrays = {name: archive[name] for name in archive.files}
    if edit_json:
        edit_json(meta)
    if edit_arrays:
        edit_arrays(arrays)
    copy = folder / "copy"
    copy.with_name("copy.json").write_text(json.dumps(meta))
    np.savez(copy.with_name("copy.npz"), **arrays)
    return copy


def test_a_version_2_file_had_its_temperature_in_control_steps(
    trained: tuple[MPPIKinematicAgent, Path], tmp_path: Path
) -> None:
    """Version 2 held λ in control steps (of 0.1 s here): read as λ × 0.1 s, so the loaded
    agent plans as it did; anything but a number there is one line."""
    original, path = trained

    def version_2(meta: dict[str, Any]) -> None:
        meta.update(version=2)
        meta["config"].update(temperature=original.config.temperature / 0.1)

    loaded = load_mppi_agent(damaged_copy(path, tmp_path, version_2))
    assert loaded.planner.temperature == original.planner.temperature == 1.0
    with pytest.raises(CorruptFileError, match="temperature"):
        load_mppi_agent(
            damaged_copy(
                path, tmp_path, lambda m: (version_2(m), m["config"].update(temperature="1"))
            )
        )


@pytest.mark.parametrize(
    ("edit_json", "edit_arrays", "expected"),
    [
        (lambda m: m.update(version=99), None, "not a skidnav mppi-kinematic agent file"),
        (lambda m: m["config"].update(samples=1), None, "samples"),
        (lambda m: m["config"].update(colour=1), None, "unknown key 'colour'"),
        (lambda m: m.pop("goal"), None, "missing 'goal'"),
        (lambda m: m.update(goal=[99, 0]), None, "goal cell"),
        (lambda m: m["counters"].update(steps=-1), None, "counter steps"),
        (lambda m: m["geometry"]["discretization"].update(n_x=2001, n_y=2001), None, "states"),
        (None, lambda a: a.update(hits=np.zeros((3, 3), np.int64)), "hits"),
        (None, lambda a: a.update(passes=-a["passes"] - 1), "passes are not counts"),
        (None, lambda a: a.update(ray_ends=-a["ray_ends"] - 1), "ray_ends are not counts"),
        (None, lambda a: a.pop("ray_crossings"), "ray_crossings"),
        (lambda m: m["counters"].update(episode_steps=1.5), None, "counter episode_steps"),
        (None, lambda a: a.update(plan=a["plan"] * 0 + 9.0), "plan"),
        (None, lambda a: a.update(dynamics_mean=a["dynamics_mean"] * np.nan), "not finite"),
        (None, lambda a: a.pop("kinematic_counts"), "kinematic_counts"),
    ],
)
def test_a_damaged_file_is_one_line_naming_it(
    trained: tuple[MPPIKinematicAgent, Path],
    tmp_path: Path,
    edit_json: Any,
    edit_arrays: Any,
    expected: str,
) -> None:
    _, path = trained
    copy = damaged_copy(path, tmp_path, edit_json, edit_arrays)
    with pytest.raises(CorruptFileError, match=expected) as caught:
        load_mppi_agent(copy)
    message = str(caught.value)
    assert "\n" not in message and message.startswith(str(tmp_path / "copy."))
