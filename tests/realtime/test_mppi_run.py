"""mppi-kinematic's frozen planner through ``skidnav robot run --policy-file``: trained in the
simulator on the run's world, saved, and driven on the sim server every 0.1 s with the same
watchdog, episodes, checkpoints and logs as any continuous policy; a run of another goal or
action duration is refused in one line."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium
import numpy as np
import pytest

from skidnav.agents.mpc.agent import make_mppi_agent
from skidnav.agents.mpc.training import train_mppi
from skidnav.agents.saved import load_policy
from skidnav.cli import main
from skidnav.realtime.arena import arena_map
from skidnav.realtime.policies import check_policy
from skidnav.world.discretization import Discretization
from tests.realtime.realtime_helpers import read_events, write_config

SEED = 0  # the run's world: the env's world_seed and the run's seed build the same map
TIME_SCALE = 10.0
SETTINGS = {
    "episodes": 1, "max_actions": 300, "time_scale": TIME_SCALE, "map": '"free"', "seed": SEED,
    "substeps": 1, "settle_periods": 0, "reconnect_timeout": 8.0, "homing_timeout": 20.0,
}  # fmt: skip
"""One action every 0.1 s (the period the planner plans with), the free map of seed 0."""


@pytest.fixture(scope="module")
def saved_planner(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """An agent trained one episode of 0.1-s actions on the run's world, saved."""
    env = gymnasium.make(
        "skidnav/SkidSteerNav-v0", map_kind="free", world_seed=SEED, slip="rough",
        action="continuous", observation="features", control_period=0.1, max_episode_steps=400,
    )  # fmt: skip
    agent = make_mppi_agent(env, {"samples": 128, "horizon": 30}, np.random.default_rng(0))
    assert train_mppi(agent, env, 1, seed=0).successes[0]
    return agent.save(tmp_path_factory.mktemp("planner") / "agent")[1]


def config(tmp_path: Path, **run: object) -> Path:
    text = "[run]\n" + "".join(f"{k} = {v}\n" for k, v in {**SETTINGS, **run}.items())
    return write_config(tmp_path, text + "[sim]\nlatency = 0.0\ndrop = 0.0\n")


def test_the_frozen_planner_drives_the_sim_robot_to_the_goal_and_resumes(
    saved_planner: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    argv = ["robot", "run", "--quiet", "--driver", "sim", "--config", str(config(tmp_path))]
    argv += ["--policy-file", str(saved_planner), "--out", str(out)]
    assert main(argv) == 0
    assert "1 reached the goal" in capsys.readouterr().out
    transitions = [e for e in read_events(out / "run.jsonl") if e["event"] == "transition"]
    assert transitions[-1]["terminated"] and len(transitions) < SETTINGS["max_actions"]
    # the run's policy asked as the loop asks: once at the start pose before connecting, then
    # from a forgotten plan, observation after observation: the same outputs, draw for draw
    replay, grid = load_policy(saved_planner), Discretization()
    check_policy(replay, "replay", arena_map("free", SEED, grid), grid, 0.1)
    replay.start_greedy_rollout()  # type: ignore[attr-defined]
    for transition in transitions:
        output = replay.wheel_speeds(np.array(transition["observation"]))
        assert list(output) == transition["output"] == transition["command"]  # within ±1.7
    # the control period held: an action every 0.1 s of robot time (the median; wall clock ×
    # time scale), about one robot period of the server's poses per action (at 10 ms of wall
    # clock a period, a busy machine's late actions let a few more poses in: a quarter more at
    # most, where a pose per sub-step would be ten times as many)
    held = np.diff([transition["mono"] for transition in transitions]) * TIME_SCALE
    assert np.median(held) == pytest.approx(0.1, abs=0.02)
    poses = [e for e in read_events(out / "run.jsonl") if e["event"] == "pose"]
    assert len(transitions) - 5 <= len(poses) <= 1.25 * len(transitions) + 5
    assert main([*argv, "--resume", "--episodes", "2"]) == 0
    assert json.loads((out / "summary.json").read_text())["episodes"] == 2


@pytest.mark.parametrize(
    ("run", "message"),
    [
        ({"substeps": 10, "settle_periods": 1}, "it plans actions of 0.1 s, the run's last 1 s"),
        ({"map": '"obstacles"'}, "it drives to the goal cell (6, 16), the run's map has its goal"),
    ],
)
def test_a_run_the_planner_was_not_trained_for_is_one_line(
    saved_planner: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    run: dict[str, object],
    message: str,
) -> None:
    argv = ["robot", "run", "--driver", "sim", "--config", str(config(tmp_path, **run))]
    assert main([*argv, "--policy-file", str(saved_planner), "--out", str(tmp_path / "o")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], lines
    assert not (tmp_path / "o").exists()
