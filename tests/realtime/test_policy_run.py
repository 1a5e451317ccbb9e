"""A frozen continuous policy through ``skidnav robot run`` against real sim servers: the same
watchdog, reconnects, episodes and logs as a tabular agent, and every command the robot ran is
the policy's output clipped to the wheels' limit."""

from __future__ import annotations

import dataclasses
import json
import logging
import math
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from skidnav.agents import catalog, saved
from skidnav.agents.policies.goal_tracker import GoalTracker
from skidnav.cli import main
from skidnav.realtime.arena import arena_map
from skidnav.realtime.control.checkpoint import Checkpoints
from skidnav.sim.features import PoseFeatures
from skidnav.world.discretization import Discretization
from tests.realtime.realtime_helpers import ServerThread, read_events, wait_for, write_config
from tests.realtime.test_faults import POSE_TIMEOUT, STOP_WITHIN, assert_quiet_until_reconnect

TIME_SCALE = 20.0
SEED = 0  # the world of ServerThread: the run's map is the server's
LIMIT = 1.7
POLICY_TRANSITION_KEYS = {
    "episode", "state", "action", "observation", "output", "command", "reward", "next_state",
    "terminated", "truncated", "collision", "pose", "log_rows",
}  # fmt: skip


class Overdriven:
    """The goal tracker with its wheel speeds doubled: outputs beyond ±1.7 rad/s that the loop
    must clip. After ``fail_after`` calls (if set) it answers NaN."""

    def __init__(self, gain: float = 2.0, fail_after: int | None = None) -> None:
        self.tracker = GoalTracker()
        self.lidar_rays, self.lidar_range = self.tracker.lidar_rays, self.tracker.lidar_range
        self.gain, self.fail_after, self.calls = gain, fail_after, 0

    def wheel_speeds(self, observation: np.ndarray) -> tuple[float, float]:
        self.calls += 1
        if self.fail_after is not None and self.calls > self.fail_after:
            return math.nan, 0.0
        left, right = self.tracker.wheel_speeds(observation)
        return self.gain * left, self.gain * right


def register_format(monkeypatch: pytest.MonkeyPatch, name: str, loader: Any) -> None:
    """Saved files of the format ``name`` load as policies by ``loader``: a test family, the
    policy family's descriptor with that format and loader."""
    test_family = dataclasses.replace(
        catalog.family("policies"), name=f"test-{name}", save_formats=(name,), policy=loader
    )
    original = saved.family_of_format
    monkeypatch.setattr(
        saved, "family_of_format", lambda kind: test_family if kind == name else original(kind)
    )


def load_overdriven(path: Path, data: dict[str, Any]) -> Overdriven:
    """The loader of the test format ``test-overdriven``: ``{"gain": g, "fail_after": n}``."""
    return Overdriven(data.get("gain", 2.0), data.get("fail_after"))


@pytest.fixture
def overdriven_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Any:
    """Factory of saved ``test-overdriven`` policies, the format registered for the test."""
    register_format(monkeypatch, "test-overdriven", load_overdriven)

    def write(**fields: Any) -> Path:
        path = tmp_path / "overdriven.json"
        path.write_text(json.dumps({"format": "test-overdriven", **fields}), encoding="utf-8")
        return path

    return write


def run_config(tmp_path: Path, port: int | None = None, **run: Any) -> Path:
    settings = {"episodes": 2, "max_actions": 40, "time_scale": TIME_SCALE, "map": '"free"'}
    settings |= {"seed": SEED, "reconnect_timeout": 8.0, "homing_timeout": 10.0, **run}
    text = "[run]\n" + "".join(f"{key} = {value}\n" for key, value in settings.items())
    if port is not None:
        text += f"[tcp]\nport = {port}\n"
    return write_config(tmp_path, text)


def clipped(output: list[float]) -> list[float]:
    return [min(max(value, -LIMIT), LIMIT) for value in output]


def assert_commands_follow_the_policy(
    events: list[dict[str, Any]], policy: Any, features: PoseFeatures
) -> list[dict[str, Any]]:
    """Every transition: the env's features of its pose, the policy's output for them and that
    output clipped as the command; every wheel command sent during an action is its command
    (or the closing stop). Returns the transitions."""
    transitions = [e for e in events if e["event"] == "transition"]
    assert transitions
    for transition in transitions:
        assert set(transition) == POLICY_TRANSITION_KEYS | {"mono", "event"}
        assert transition["action"] is None
        observation = np.array(transition["observation"])
        x, y, cos_heading, sin_heading = observation[:4]
        pose = np.array([x, y, math.atan2(sin_heading, cos_heading)])
        np.testing.assert_allclose(features(pose), observation, atol=1e-9)
        assert transition["output"] == list(policy.wheel_speeds(observation))
        assert transition["command"] == clipped(transition["output"])
    sent: list[tuple[float, float]] = []
    for event in events:
        if event["event"] == "cmd":
            sent.append((event["omega_left"], event["omega_right"]))
        elif event["event"] == "transition":
            assert set(sent) <= {(0.0, 0.0), tuple(event["command"])}, sent
            sent = []
        elif event["event"] in ("episode_start", "episode_end", "homing_start", "homing_end"):
            sent = []  # the stop of an aborted action, homing
    return transitions


def inject_after_transitions(server: ServerThread, out: Path, count: int) -> threading.Thread:
    """Inject the server's next fault once the run has logged ``count`` transitions."""

    def watch() -> None:
        events = out / "run.jsonl"
        wait_for(
            lambda: sum(e["event"] == "transition" for e in read_events(events)) >= count,
            60.0,
            "transitions",
        )
        server.server.inject()

    thread = threading.Thread(target=watch, daemon=True)
    thread.start()
    return thread


def test_lost_poses_stop_a_continuous_policy_and_the_run_goes_on(
    tmp_path: Path, overdriven_file: Any, capsys: pytest.CaptureFixture[str]
) -> None:
    """The ``silence`` fault mid-episode: the watchdog trips on the stale pose, the stop reaches
    the server within 100 ms of the pose timeout, nothing but zero is sent until the reconnect,
    the episode is aborted and the run completes its episodes; the commands the server ran are
    the policy's outputs clipped."""
    out = tmp_path / "out"
    policy_path = overdriven_file(gain=2.0)
    with ServerThread(TIME_SCALE, log=tmp_path / "server.jsonl", faults=("silence",)) as server:
        config = run_config(tmp_path, server.port, episodes=3)
        watcher = inject_after_transitions(server, out, 3)
        argv = ["robot", "run", "--quiet", "--driver", "tcp", "--config", str(config)]
        code = main([*argv, "--policy-file", str(policy_path), "--out", str(out)])
        watcher.join(timeout=5)
        served = server.events()
    assert code == 0, capsys.readouterr()
    fault = next(e for e in served if e["event"] == "fault")
    stop = next(e for e in served if e["event"] == "stop" and e["mono"] > fault["mono"])
    assert stop["mono"] - fault["mono"] < POSE_TIMEOUT + STOP_WITHIN
    assert_quiet_until_reconnect(served, stop)
    events = read_events(out / "run.jsonl")
    trip = next(e for e in events if e["event"] == "trip")
    assert "pose stale" in trip["reason"]
    assert [e["confirmed"] for e in events if e["event"] == "stopped"] == [True]
    assert any(e["event"] == "reconnected" for e in events)
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["episodes"], summary["aborted"], summary["exit_code"]) == (3, 1, 0)

    grid = Discretization()
    features = PoseFeatures(arena_map("free", SEED, grid), grid, 8, 0.3)
    transitions = assert_commands_follow_the_policy(events, Overdriven(2.0), features)
    assert any(max(map(abs, t["output"])) > LIMIT for t in transitions)  # clipping happened
    commands = {tuple(t["command"]) for t in transitions}
    driven = {(e["omega_left"], e["omega_right"]) for e in served if e["event"] == "cmd"}
    homing = {
        (e["omega_left"], e["omega_right"])
        for e in events
        if e["event"] == "cmd" and _in_homing(events, e)
    }
    aborted = _aborted_action_commands(events)
    assert len(aborted) == 1  # one action's command, within the box
    assert all(abs(speed) <= LIMIT for command in aborted for speed in command)
    assert driven <= commands | homing | aborted | {(0.0, 0.0)}
    moved = {tuple(t["command"]) for t in transitions if not t["collision"]}
    assert moved <= driven  # every decision that could move reached the robot

    latest = Checkpoints(out / "checkpoints").latest()
    assert latest is not None and latest[0] == 2
    _, directory, state = latest
    assert state["policy"] == f"file:{policy_path.resolve()}"
    assert not (directory / "agent.npz").exists()
    assert [r["aborted"] for r in state["results"]].count(True) == 1


def _aborted_action_commands(events: list[dict[str, Any]]) -> set[tuple[float, float]]:
    """The wheel commands the run log sent between the last transition before the trip and the
    trip: those of the action the trip aborted, which no transition records."""
    trip = next(i for i, e in enumerate(events) if e["event"] == "trip")
    last = max(i for i, e in enumerate(events[:trip]) if e["event"] == "transition")
    return {(e["omega_left"], e["omega_right"]) for e in events[last:trip] if e["event"] == "cmd"}


def _in_homing(events: list[dict[str, Any]], command: dict[str, Any]) -> bool:
    """Whether the run log's ``command`` record lies between a homing start and its end."""
    inside = False
    for event in events:
        if event is command:
            return inside
        if event["event"] in ("homing_start", "homing_end"):
            inside = event["event"] == "homing_start"
    return False


def test_goal_tracker_reaches_the_goal_through_the_sim_driver_and_resumes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    config = run_config(tmp_path, episodes=1)
    argv = [
        "robot",
        "run",
        "--quiet",
        "--driver",
        "sim",
        "--config",
        str(config),
        "--out",
        str(out),
    ]
    assert main([*argv, "--policy", "goal-tracker"]) == 0
    assert "1 reached the goal" in capsys.readouterr().out
    events = read_events(out / "run.jsonl")
    grid = Discretization()
    features = PoseFeatures(arena_map("free", SEED, grid), grid, 8, 0.3)
    transitions = assert_commands_follow_the_policy(events, GoalTracker(), features)
    assert transitions[-1]["terminated"] and transitions[-1]["reward"] == 10.0
    assert all(t["log_rows"] >= 1 for t in transitions[1:])
    served = read_events(out / "sim-server.jsonl")
    assert {tuple(t["command"]) for t in transitions} <= {
        (e["omega_left"], e["omega_right"]) for e in served if e["event"] == "cmd"
    }

    assert main([*argv, "--policy", "goal-tracker", "--resume", "--episodes", "2"]) == 0
    assert json.loads((out / "summary.json").read_text())["episodes"] == 2
    capsys.readouterr()
    assert main([*argv, "--agent", "q-learning", "--resume", "--episodes", "3"]) == 2
    assert "checkpoint holds policy 'goal-tracker', not agent 'q-learning'" in (
        capsys.readouterr().err
    )


def test_a_failing_policy_stops_the_robot_and_ends_the_run(
    tmp_path: Path, overdriven_file: Any, caplog: pytest.LogCaptureFixture
) -> None:
    """NaN wheel speeds from the 4th call on (the 1st is the check before connecting): the
    monitor trips, the stop is confirmed, exit code 3; the failure is logged in one line (no
    traceback)."""
    out = tmp_path / "out"
    policy_path = overdriven_file(fail_after=3)
    with ServerThread(TIME_SCALE, log=tmp_path / "server.jsonl") as server:
        config = run_config(tmp_path, server.port)
        argv = ["robot", "run", "--quiet", "--driver", "tcp", "--config", str(config)]
        assert main([*argv, "--policy-file", str(policy_path), "--out", str(out)]) == 3
    events = read_events(out / "run.jsonl")
    trip = next(e for e in events if e["event"] == "trip")
    assert trip["reason"].startswith("policy failed: expected an action of two finite wheel")
    errors = [record for record in caplog.records if record.levelno >= logging.ERROR]
    assert [record.getMessage() for record in errors] == [trip["reason"]]
    assert not any(record.exc_info for record in errors)
    assert [e["confirmed"] for e in events if e["event"] == "stopped"] == [True]
    assert sum(e["event"] == "transition" for e in events) == 2
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["episodes"], summary["aborted"]) == (1, 1)


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ([], "one of the arguments --agent --policy --policy-file --agent-file is required"),
        (["--policy", "goal-tracker", "--agent", "dyna-q"], "not allowed with argument"),
        (["--policy", "wall-follower"], "unknown policy 'wall-follower'; expected one of"),
        (["--policy-file", "missing.json"], "missing.json: no such policy file"),
        (["--policy-file", ""], "argument --policy-file: expected a path, got an empty one"),
        (["--policy-file", "/"], "not the path of a policy file"),
    ],
)
def test_bad_policy_choices_are_one_line_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], arguments: list[str], message: str
) -> None:
    argv = ["robot", "run", "--driver", "tcp", "--out", str(tmp_path / "out"), *arguments]
    try:
        code = main(argv)
    except SystemExit as exit_:  # argparse's own errors
        code = int(exit_.code or 0)
    assert code == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], lines


def test_bad_policy_settings_and_files_are_one_line_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config = write_config(tmp_path, "[policies.goal-tracker]\nturn_gain = -1.0\n")
    argv = ["robot", "run", "--driver", "tcp", "--out", str(tmp_path / "out")]
    assert main([*argv, "--config", str(config), "--policy", "goal-tracker"]) == 2
    assert capsys.readouterr().err.strip() == (
        "skidnav: error: expected turn_gain to be a finite number > 0, got -1.0 "
        "in [policies.goal-tracker]"
    )
    saved = tmp_path / "policy.json"
    for content, message in [
        ("[1, 2]", "policy.json: "),
        ('{"format": "ppo-wheel"}', "not a saved skidnav agent or policy (format 'ppo-wheel')"),
    ]:
        saved.write_text(content, encoding="utf-8")
        assert main([*argv, "--policy-file", str(saved)]) == 2
        lines = capsys.readouterr().err.strip().splitlines()
        assert len(lines) == 1 and message in lines[0], lines
    assert not (tmp_path / "out").exists()  # refused before anything was written


@pytest.mark.parametrize("weight", [1e308, 1e32, math.nan])
def test_a_policy_with_weights_no_search_writes_is_one_line(
    weight: float, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Weights of 10³² and more (the search keeps them below: cmaes asserts it) would overflow
    the policy's sums to NaN on the robot: refused when the file is loaded."""
    from skidnav.agents.policies.search.policy_file import save_policy
    from skidnav.agents.policies.search.tanh_policy import PolicyLayout, TanhPolicy

    layout = PolicyLayout(np.zeros(9), np.ones(9), hidden=2, wheel_speed=1.7, lidar_rays=2)
    npz_path, json_path = save_policy(
        TanhPolicy(layout, np.ones(layout.n_parameters)), tmp_path / "p"
    )
    with np.load(npz_path) as archive:
        arrays = {name: archive[name] for name in archive.files}
    np.savez(npz_path, **{**arrays, "parameters": np.full(layout.n_parameters, weight)})
    argv = ["robot", "run", "--driver", "tcp", "--policy-file", str(json_path)]
    assert main([*argv, "--out", str(tmp_path / "out")]) == 2
    assert capsys.readouterr().err.strip() == (
        f"skidnav: error: {npz_path}: array 'parameters' holds a value that is NaN or not below "
        "1e+32 in magnitude"
    )
    assert not (tmp_path / "out").exists()


def test_lockstep_runs_of_a_policy_are_identical(tmp_path: Path) -> None:
    """On a lockstep server an action is exactly ``substeps`` commands whatever the load, so
    the same world gives the same transitions, command for command."""
    runs = []
    for name in ("first", "second"):
        with ServerThread(1.0, lockstep=True) as server:
            config = run_config(tmp_path, server.port, episodes=1, time_scale=1.0)
            with config.open("a", encoding="utf-8") as stream:
                stream.write("lockstep = true\n")  # [tcp] is the config's last table
            out = tmp_path / name
            argv = ["robot", "run", "--quiet", "--driver", "tcp", "--config", str(config)]
            assert main([*argv, "--policy", "goal-tracker", "--out", str(out)]) == 0
        events = read_events(out / "run.jsonl")
        transitions = [e for e in events if e["event"] == "transition"]
        assert transitions[-1]["terminated"]
        commands = [e for e in events if e["event"] == "cmd"]
        assert len(commands) == 10 * len(transitions) + 1  # and the closing stop
        runs.append([{k: v for k, v in t.items() if k != "mono"} for t in transitions])
    assert runs[0] == runs[1]


WALL_AHEAD = """\
skidnav-map 1
width 25
height 25
map
#########################
#.......................#
#.......................#
#.......................#
#.......................#
#.......................#
#.......................#
#.......................#
#.......................#
#.......................#
#..............G........#
#.......................#
#........#..............#
#........#..............#
#........#..............#
#........#..............#
#....S...#..............#
#........#..............#
#........#..............#
#........#..............#
#........#..............#
#.......................#
#.......................#
#.......................#
#########################
"""
"""A wall four cells ahead of the start (heading 0)."""


class SlowForward:
    """Full speed ahead, answering after ``delay`` seconds of wall time."""

    lidar_rays, lidar_range = 8, 0.3

    def __init__(self, delay: float) -> None:
        self.delay = delay

    def wheel_speeds(self, observation: np.ndarray) -> tuple[float, float]:
        time.sleep(self.delay)
        return LIMIT, LIMIT


def load_slow_forward(path: Path, data: dict[str, Any]) -> SlowForward:
    """The loader of the test format ``test-slow-forward``: ``{"delay": seconds}``."""
    return SlowForward(data["delay"])


def test_a_slow_policy_is_not_driven_into_a_wall(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The command held while the policy answers is checked by the virtual bumper too: a policy
    taking 20 ms (a third of a period at this time scale) never pushes the robot against the
    wall; the bumper stops it before, as a collision."""
    register_format(monkeypatch, "test-slow-forward", load_slow_forward)
    (tmp_path / "wall.txt").write_text(WALL_AHEAD, encoding="utf-8")
    policy = tmp_path / "slow.json"
    policy.write_text(json.dumps({"format": "test-slow-forward", "delay": 0.02}))
    pushed = 0
    with ServerThread(TIME_SCALE, map_spec=str(tmp_path / "wall.txt")) as server:
        advance = server.robot.dynamics.advance

        def counting(pose: Any, wheels: Any, time_: Any, noise: Any) -> Any:
            nonlocal pushed
            new = advance(pose, wheels, time_, noise)
            if wheels[0] > 0 and wheels[1] > 0 and tuple(new[:2]) == tuple(pose[:2]):
                pushed += 1  # driving forward without moving: against the wall
            return new

        monkeypatch.setattr(server.robot.dynamics, "advance", counting)
        config = run_config(tmp_path, server.port, episodes=1, max_actions=6,
                            map=f'"{tmp_path / "wall.txt"}"')  # fmt: skip
        argv = ["robot", "run", "--quiet", "--driver", "tcp", "--config", str(config)]
        assert main([*argv, "--policy-file", str(policy), "--out", str(tmp_path / "out")]) == 0
    transitions = [e for e in read_events(tmp_path / "out" / "run.jsonl")
                   if e["event"] == "transition"]  # fmt: skip
    assert any(t["collision"] for t in transitions)
    assert pushed == 0


def test_a_trip_while_stopping_at_the_goal_leaves_results_and_log_agreeing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The action that reached the goal is logged before the wheels stop: a trip during that
    stop aborts the episode with as many actions counted as transitions logged."""
    from skidnav.realtime.control.periods import Aborted
    from skidnav.realtime.control.policy_loop import PolicyLoop

    def tripping(self: PolicyLoop, stamp: float) -> Any:
        self.monitor.trip("test: trip while settling")
        raise Aborted("test: trip while settling")

    monkeypatch.setattr(PolicyLoop, "_stop_and_settle", tripping)
    out = tmp_path / "out"
    config = run_config(tmp_path, episodes=1)
    argv = ["robot", "run", "--quiet", "--driver", "sim", "--config", str(config)]
    main([*argv, "--policy", "goal-tracker", "--out", str(out)])
    events = read_events(out / "run.jsonl")
    (end,) = [e for e in events if e["event"] == "episode_end"]
    assert end["aborted"]
    assert end["actions"] == sum(e["event"] == "transition" for e in events)
