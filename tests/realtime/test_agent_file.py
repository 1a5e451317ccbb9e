"""From simulation to the robot: ``skidnav run`` keeps each run's trained agent (``[experiment]
save_agents``) with the world it was trained for, and ``skidnav robot run --agent-file`` drives
it on the sim server: a tabular agent continues from its saved tables; a run of another robot,
arena/grid, goal or action duration is refused in one line before anything moves."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium
import numpy as np
import pytest

from skidnav.agents.catalog import entry
from skidnav.agents.linear.registry import make_linear_agent
from skidnav.agents.policies.agent import GoalTrackerAgent
from skidnav.agents.policies.goal_tracker import GoalTracker, GoalTrackerConfig
from skidnav.agents.saved import load_saved_agent
from skidnav.agents.tabular.agent import TabularAgent
from skidnav.agents.trained_world import read_trained_world
from skidnav.cli import main
from skidnav.experiments.store import ResultStore
from skidnav.realtime.control.checkpoint import Checkpoints
from skidnav.robot.params import RobotParams
from skidnav.world.mapfile import load_map
from tests.realtime.realtime_helpers import read_events, write_config

EXPERIMENT = """
[experiment]
name = "to-the-robot"
episodes = 4
max_steps = 40
seeds = 1
root_seed = 3
presets = ["rough"]
eval_rollouts = 1
oracle_samples = 2
bootstrap_samples = 100
convergence_window = 1
save_agents = true

[[maps]]
kind = "free"

[[agents]]
name = "q-learning"
params = { epsilon = 0.3 }
"""
"""One q-learning run of four short episodes on a free map, its agent kept."""

RUN = {
    "episodes": 1, "max_actions": 12, "time_scale": 20.0, "reconnect_timeout": 2.0,
    "homing_timeout": 20.0,
}  # fmt: skip


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The run folder of the one run of :data:`EXPERIMENT`, trained by ``skidnav run``."""
    folder = tmp_path_factory.mktemp("experiment")
    config = folder / "experiment.toml"
    config.write_text(EXPERIMENT, encoding="utf-8")
    out = folder / "results"
    argv = ["run", str(config), "--out", str(out), "--backend", "serial", "--no-progress"]
    assert main(argv) == 0
    (run_id,) = ResultStore(out).finished()
    return ResultStore(out).run_folder(run_id)


def robot_config(tmp_path: Path, map_path: Path, **run: object) -> Path:
    settings = {**RUN, "map": json.dumps(str(map_path)), **run}
    text = "[run]\n" + "".join(f"{key} = {value}\n" for key, value in settings.items())
    return write_config(tmp_path, text + "[sim]\nlatency = 0.0\ndrop = 0.0\n")


def test_skidnav_run_keeps_the_agent_and_its_world(trained: Path) -> None:
    assert {path.name for path in trained.iterdir()} == {
        "agent.npz", "agent.json", "world.json", "map.txt",
    }  # fmt: skip
    agent = load_saved_agent(trained / "agent.json")
    assert isinstance(agent, TabularAgent) and agent.episodes == 4
    assert np.count_nonzero(agent.q) > 0
    world = read_trained_world(trained / "world.json")
    assert world.agent == "q-learning" and world.action_duration == pytest.approx(1.0)
    grid_map = load_map(trained / "map.txt")
    assert grid_map.goal == world.grid_map.goal
    assert (grid_map.occupancy == world.grid_map.occupancy).all()


def test_a_resumed_experiment_keeps_the_agents_it_wrote(trained: Path) -> None:
    results = trained.parents[1]
    before = (trained / "agent.npz").read_bytes()
    config = results / "config.toml"
    assert main(["run", str(config), "--out", str(results), "--no-progress"]) == 0
    assert (trained / "agent.npz").read_bytes() == before  # the finished run was not run again


def test_the_tabular_agent_continues_learning_from_its_saved_tables(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    saved = load_saved_agent(trained / "agent.json")
    assert isinstance(saved, TabularAgent)
    out = tmp_path / "out"
    config = robot_config(tmp_path, trained / "map.txt")
    argv = ["robot", "run", "--quiet", "--config", str(config), "--out", str(out)]
    assert main([*argv, "--agent-file", str(trained / "agent.json")]) == 0
    assert "1 episode" in capsys.readouterr().out
    learned = load_saved_agent(out / "checkpoints" / "ep-00000" / "agent.json")
    assert isinstance(learned, TabularAgent)
    # the episode counter goes on from the saved agent's, and q-learning changed only the
    # entries of the pairs it tried on the robot: every other saved value is still there
    assert learned.episodes == saved.episodes + 1
    assert learned.steps > saved.steps
    tried = np.zeros_like(saved.q, dtype=bool)
    for event in read_events(out / "run.jsonl"):
        if event["event"] == "transition":
            tried[event["state"], event["action"]] = True
    assert tried.any()
    np.testing.assert_array_equal(learned.q[~tried], saved.q[~tried])
    untouched = ~tried & (saved.q != 0)
    assert untouched.any()  # the saved tables were there from the start


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"substeps": 5}, "it was trained with actions of 1 s, the run's last 0.5 s"),
        ({"map": '"free"', "seed": 99}, "it was trained for the goal cell"),
    ],
)
def test_a_run_of_another_world_is_refused_in_one_line(
    trained: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    change: dict[str, object],
    message: str,
) -> None:
    config = robot_config(tmp_path, trained / "map.txt", **change)
    argv = ["robot", "run", "--config", str(config), "--out", str(tmp_path / "o")]
    assert main([*argv, "--agent-file", str(trained / "agent.json")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and "agent.json" in lines[0], lines
    assert not (tmp_path / "o").exists()


def test_an_agent_of_another_robot_or_grid_is_refused(
    trained: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The world the file was trained for names another robot, then another grid."""
    copy = tmp_path / "agent"
    copy.mkdir()
    for name in ("agent.npz", "agent.json", "map.txt"):
        (copy / name).write_bytes((trained / name).read_bytes())
    world = json.loads((trained / "world.json").read_text())
    config = robot_config(tmp_path, trained / "map.txt")
    argv = ["robot", "run", "--config", str(config), "--out", str(tmp_path / "o")]
    for table, key, value, message in [
        ("robot", "wheel_radius", 0.03, "a robot of wheel_radius 0.03, the run's has 0.0225"),
        ("discretization", "n_headings", 16, "on the arena/grid 25 × 25 cells × 16 headings"),
    ]:
        changed = json.loads(json.dumps(world))
        changed["geometry"][table][key] = value
        (copy / "world.json").write_text(json.dumps(changed))
        assert main([*argv, "--agent-file", str(copy / "agent.json")]) == 2
        lines = capsys.readouterr().err.strip().splitlines()
        assert len(lines) == 1 and message in lines[0], lines
    (copy / "world.json").unlink()  # without it, the agent's own states are checked
    (copy / "agent.json").write_text(
        json.dumps({**json.loads((trained / "agent.json").read_text()), "n_states": 100})
    )
    assert main([*argv, "--agent-file", str(copy / "agent.json")]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_a_saved_frozen_policy_acts_and_an_agent_of_the_pose_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A family that does not learn on the robot drives frozen, as --policy-file runs it; a
    discrete-action agent that observes the pose, which the robot's loop does not compute, is
    refused in one line."""
    tracker = GoalTrackerAgent(GoalTracker(GoalTrackerConfig(), RobotParams()))
    (tmp_path / "tracker").mkdir()
    saved = tracker.save(tmp_path / "tracker" / "agent")[1]
    out = tmp_path / "out"
    config = write_config(
        tmp_path,
        "[run]\n"
        + "".join(f"{key} = {value}\n" for key, value in RUN.items())
        + 'map = "free"\n[sim]\nlatency = 0.0\ndrop = 0.0\n',
    )
    argv = ["robot", "run", "--quiet", "--config", str(config), "--out", str(out)]
    assert main([*argv, "--agent-file", str(saved)]) == 0
    latest = Checkpoints(out / "checkpoints").latest()
    assert latest is not None and latest[2]["policy"] == f"file:{saved.resolve()}"
    assert not (latest[1] / "agent.npz").exists()  # a frozen policy has nothing to save
    env = gymnasium.make("skidnav/SkidSteerNav-v0", map_kind="free", observation="pose")
    space = env.observation_space
    assert isinstance(space, gymnasium.spaces.Box)
    linear = make_linear_agent("linear-q", space, 4, {}, np.random.default_rng(0))
    linear_file = linear.save(tmp_path / "linear" / "agent")[1]
    argv[-1] = str(tmp_path / "linear-run")  # a new run: the first one's folder holds it
    assert main([*argv, "--agent-file", str(linear_file)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "it observes the pose (x, y, heading)" in lines[0], lines
    assert "linear" in lines[0] and not (tmp_path / "linear-run").exists()


def test_a_saved_classical_navigator_drives_frozen(tmp_path: Path) -> None:
    """The classical navigator, saved, drives ``robot run --agent-file`` as a frozen policy."""
    env = gymnasium.make(
        "skidnav/SkidSteerNav-v0", map_kind="free", observation="features", action="continuous"
    )
    navigator = entry("classical").build(env, {}, np.random.SeedSequence(0), 100).agent
    (tmp_path / "classical").mkdir()
    saved = navigator.save(tmp_path / "classical" / "agent")[1]
    config = write_config(
        tmp_path,
        "[run]\n"
        + "".join(f"{key} = {value}\n" for key, value in RUN.items())
        + 'map = "free"\n[sim]\nlatency = 0.0\ndrop = 0.0\n',
    )
    out = tmp_path / "out"
    argv = ["robot", "run", "--quiet", "--config", str(config), "--out", str(out)]
    assert main([*argv, "--agent-file", str(saved)]) == 0
    latest = Checkpoints(out / "checkpoints").latest()
    assert latest is not None and latest[2]["policy"] == f"file:{saved.resolve()}"
