"""A saved agent of discrete actions over the feature observation (linear-q, dqn), trained by
``skidnav run``, drives ``skidnav robot run --agent-file`` on the sim server frozen: every
command it sends is the wheel speeds of its greedy action at the observation logged with it; one
trained for another action duration or goal is refused in one line, by either door."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
import pytest

from skidnav.agents.catalog import families
from skidnav.agents.saved import load_saved_agent
from skidnav.cli import main
from skidnav.experiments.store import ResultStore
from skidnav.realtime.agent_file import LEARNING_FAMILIES
from skidnav.realtime.control.checkpoint import Checkpoints
from skidnav.robot.kinematics import N_ACTIONS, commanded_wheel_speeds
from skidnav.robot.params import RobotParams
from tests.realtime.realtime_helpers import read_events
from tests.realtime.test_agent_file import robot_config

EXPERIMENT = """
[experiment]
name = "discrete-to-the-robot"
episodes = 3
max_steps = 40
seeds = 1
root_seed = 3
presets = ["rough"]
eval_rollouts = 1
oracle_samples = 2
bootstrap_samples = 100
convergence_window = 1
save_agents = true

[env]
observation = "features"

[[maps]]
kind = "free"

[[agents]]
name = "{name}"
params = {params}
"""
"""One run of three short episodes of one agent on a free map, its agent kept."""


def train(folder: Path, name: str, params: str) -> Path:
    """The run folder of agent ``name`` (``params``: its TOML inline table) trained by
    ``skidnav run`` on :data:`EXPERIMENT`."""
    config = folder / "experiment.toml"
    config.write_text(EXPERIMENT.format(name=name, params=params), encoding="utf-8")
    out = folder / "results"
    argv = ["run", str(config), "--out", str(out), "--backend", "serial", "--no-progress"]
    assert main(argv) == 0
    (run_id,) = ResultStore(out).finished()
    return ResultStore(out).run_folder(run_id)


@pytest.fixture(scope="module")
def linear_q(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return train(tmp_path_factory.mktemp("linear-q"), "linear-q", "{ epsilon = 0.3 }")


@pytest.fixture(scope="module")
def dqn(tmp_path_factory: pytest.TempPathFactory) -> Path:
    pytest.importorskip("stable_baselines3")
    params = "{ learning_starts = 20, buffer_size = 1000, hidden = [16] }"
    return train(tmp_path_factory.mktemp("dqn"), "dqn", params)


def drive(saved: Path, tmp_path: Path, door: str = "--agent-file", **run: Any) -> int:
    """The exit code of ``skidnav robot run`` of the agent saved in run folder ``saved`` on the
    sim server, on the map it was trained on, into ``tmp_path / "out"``."""
    config = robot_config(tmp_path, saved / "map.txt", **run)
    argv = ["robot", "run", "--quiet", "--config", str(config), "--out", str(tmp_path / "out")]
    return main([*argv, door, str(saved / "agent.json")])


def check_greedy_commands(out: Path, agent: Any) -> None:
    """Every action of the run in ``out`` sent the wheel speeds of ``agent``'s greedy action at
    the observation logged with it, and nothing was learned."""
    speed = RobotParams().wheel_speed
    transitions = [e for e in read_events(out / "run.jsonl") if e["event"] == "transition"]
    assert len(transitions) >= 2
    actions = []
    for event in transitions:
        action = agent.greedy_action(np.array(event["observation"]))
        assert 0 <= action < N_ACTIONS
        assert tuple(event["command"]) == commanded_wheel_speeds(action, speed)
        assert event["output"] == event["command"]  # a discrete action is within the wheels' box
        actions.append(action)
    assert len(set(actions)) >= 2  # the commands follow the observations, not one constant
    latest = Checkpoints(out / "checkpoints").latest()
    assert latest is not None and latest[2]["policy"].endswith("agent.json")
    assert not (latest[1] / "agent.npz").exists()  # a frozen policy has nothing to save


def test_every_registered_family_runs_on_the_robot() -> None:
    """The rule that refuses a family which neither learns on the robot nor acts frozen there
    refuses none of those registered."""
    for family in families():
        assert family.name in LEARNING_FAMILIES or family.policy is not None, family.name


def test_a_saved_linear_q_agent_acts_frozen_by_its_greedy_actions(
    linear_q: Path, tmp_path: Path
) -> None:
    agent = load_saved_agent(linear_q / "agent.json")
    assert drive(linear_q, tmp_path) == 0
    check_greedy_commands(tmp_path / "out", agent)


def test_a_saved_dqn_acts_frozen_by_its_greedy_actions(dqn: Path, tmp_path: Path) -> None:
    env = gymnasium.make("skidnav/SkidSteerNav-v0", map_kind="free", observation="features")
    agent = load_saved_agent(dqn / "agent.json", env)  # the saved bounds are the env's
    assert drive(dqn, tmp_path) == 0
    check_greedy_commands(tmp_path / "out", agent)


@pytest.mark.parametrize(
    ("door", "change", "message"),
    [
        ("--agent-file", {"substeps": 5}, "it was trained with actions of 1 s, the run's last 0.5"),
        ("--agent-file", {"map": '"free"', "seed": 99}, "it was trained for the goal cell"),
        ("--policy-file", {"substeps": 5}, "it plans actions of 1 s, the run's last 0.5 s"),
        ("--policy-file", {"map": '"free"', "seed": 99}, "it drives to the goal cell"),
    ],
)
def test_a_discrete_agent_of_another_world_is_refused_in_one_line(
    linear_q: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    door: str,
    change: dict[str, Any],
    message: str,
) -> None:
    """By ``--agent-file``, its ``world.json`` against the run's; by ``--policy-file``, the
    goal and action duration the policy carries from it."""
    assert drive(linear_q, tmp_path, door, **change) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and "agent.json" in lines[0], lines
    assert not (tmp_path / "out").exists()
