"""Whole runs at high time scale: an episode that reaches the goal, learning, logs, resume."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from skidnav.agents.tabular.registry import load_agent
from skidnav.cli import main
from skidnav.realtime.config import load_config
from skidnav.realtime.control.checkpoint import Checkpoints
from skidnav.world.discretization import Discretization
from tests.realtime.realtime_helpers import read_events, write_config

CONFIGS = Path(__file__).resolve().parents[2] / "configs" / "realtime.toml"


def small_room_map(path: Path) -> Path:
    """A 5 × 5-cell room (cells 10–14 in i and j) walled in; start (11, 12), goal (13, 12)."""
    rows = []
    for j in reversed(range(25)):
        row = ""
        for i in range(25):
            free = 10 <= i <= 14 and 10 <= j <= 14
            row += (
                "S" if (i, j) == (11, 12) else "G" if (i, j) == (13, 12) else "." if free else "#"
            )
        rows.append(row)
    path.write_text("skidnav-map 1\nwidth 25\nheight 25\nmap\n" + "\n".join(rows) + "\n")
    return path


def test_episode_reaches_the_goal_and_learns_online(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    room = small_room_map(tmp_path / "room.txt")
    config = write_config(
        tmp_path,
        f"""
[run]
episodes = 1
max_actions = 300
time_scale = 25.0
map = "{room}"

[sim]
slip = "rough"

[agents.dyna-q]
planning_steps = 10
""",
    )
    out = tmp_path / "out"
    common = ["robot", "run", "--quiet", "--out", str(out), "--driver", "sim", "--agent", "dyna-q"]
    assert main([*common, "--config", str(config)]) == 0  # in-process; the server is a child
    assert "1 reached the goal" in capsys.readouterr().out
    summary = json.loads((out / "summary.json").read_text())
    assert summary["goals"] == 1 and summary["aborted"] == 0
    events = read_events(out / "run.jsonl")
    transitions = [e for e in events if e["event"] == "transition"]
    assert transitions[-1]["terminated"] and transitions[-1]["reward"] == 10.0
    assert not any(t["terminated"] for t in transitions[:-1])
    grid = Discretization()
    i, j, _ = grid.unflatten(transitions[-1]["next_state"])
    assert (i, j) == (13, 12)
    forward = [t for t in transitions if t["action"] == 0 and not t["collision"]]
    assert forward and all(t["log_rows"] >= 5 for t in forward)  # kinematic rows from poses
    for t in transitions:  # rewards follow the env's rule
        assert t["reward"] in (10.0, -10.0) or -2.0 < t["reward"] <= -1.0
    assert sum(e["event"] == "pose" for e in events) > 10 * len(transitions) * 0.5
    server = read_events(out / "sim-server.jsonl")
    assert sum(e["event"] == "cmd" for e in server) >= len(transitions)
    latest = Checkpoints(out / "checkpoints").latest()
    assert latest is not None and latest[0] == 0
    agent = load_agent(latest[1] / "agent")
    assert agent.planning_updates > 0 and np.any(agent.q != 0)

    # --resume continues with the next episode from the saved agent and loop state
    assert main([*common, "--config", str(config), "--episodes", "2", "--resume"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["episodes"] == 2
    latest = Checkpoints(out / "checkpoints").latest()
    assert latest is not None and latest[0] == 1
    resumed = load_agent(latest[1] / "agent")
    assert resumed.episodes == 2


def test_resume_without_checkpoint_is_a_user_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["robot", "run", "--driver", "tcp", "--resume", "--out", str(tmp_path / "out")]
    for chosen in (["--agent", "q-learning"], ["--policy", "goal-tracker"]):
        assert main([*argv, *chosen]) == 2
        assert "no checkpoint to resume from" in capsys.readouterr().err
        assert not (tmp_path / "out").exists()  # refused before anything was written


def test_shipped_config_presets_load() -> None:
    for preset in (None, "rough-stationary", "slippery-drifting", "quick", "obstacles"):
        config = load_config(CONFIGS, preset)
        assert config.run.episodes >= 1
    assert load_config(CONFIGS, "slippery-drifting").sim.drift > 0
    assert load_config(CONFIGS, "quick").run.time_scale > 1


def test_bad_config_is_a_one_line_user_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config = write_config(tmp_path, "[run]\nepisodes = 0\n")
    assert main(["robot", "run", "--agent", "q-learning", "--config", str(config)]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"skidnav: error: expected episodes to be an integer >= 1, got 0 in {config}: [run]"
    ]


def test_map_files_are_relative_to_the_config(tmp_path: Path) -> None:
    (tmp_path / "maps").mkdir()
    small_room_map(tmp_path / "maps" / "room.txt")
    config_path = tmp_path / "rt.toml"
    config_path.write_text(
        '[run]\nmap = "maps/room.txt"\n[presets.p.run]\nmap = "maps/other.txt"\n'
        '[presets.q.run]\nmap = "maze"\n',
        encoding="utf-8",
    )
    assert load_config(config_path).run.map == str(tmp_path / "maps" / "room.txt")
    assert load_config(config_path, "p").run.map == str(tmp_path / "maps" / "other.txt")
    assert load_config(config_path, "q").run.map == "maze"
    shipped = load_config(CONFIGS)
    assert Path(shipped.run.map).is_file()
