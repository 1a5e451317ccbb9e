"""The sim server on MuJoCo physics, and lockstep: the fault-injection and protocol tests the
kinematic server passes, the wall rule, lockstep's determinism and speed, and a run of
``skidnav robot run`` in lockstep."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest

from skidnav.realtime.link import protocol as pr
from skidnav.realtime.robot_server.simulated_robot import SimRobotConfig, build_robot
from tests.realtime import test_faults, test_sim_server
from tests.realtime.realtime_helpers import (
    RawClient,
    ServerThread,
    cli_env,
    read_events,
    start_run,
    write_config,
)

pytest.importorskip("mujoco")


def physics_server(**options: object) -> ServerThread:
    return ServerThread(physics="mujoco", **options)  # type: ignore[arg-type]


def test_physics_server_answers_the_injected_faults_with_a_confirmed_stop(tmp_path: Path) -> None:
    kinds = tuple(fault for fault, _, _ in test_faults.FAULTS)
    with physics_server(
        time_scale=test_faults.TIME_SCALE, log=tmp_path / "server.jsonl", faults=kinds
    ) as server:
        test_faults.check_faults(tmp_path, server)


@pytest.mark.parametrize(
    "check",
    [
        test_sim_server.test_server_handshake_command_ack_pose_and_stop,
        test_sim_server.test_server_requires_hello_and_refuses_a_second_client,
    ],
)
def test_physics_server_speaks_the_protocol(check: object) -> None:
    with physics_server() as server:
        check(server)  # type: ignore[operator]


def test_physics_robot_drives_turns_slower_than_icr_and_walls_block_it() -> None:
    robots = {
        physics: build_robot(
            slip="rough",
            drift=0.0,
            drift_period=600.0,
            map_spec="free",
            seed=0,
            config=SimRobotConfig(),
            physics=physics,
        )
        for physics in ("kinematic", "mujoco")
    }
    turned = {}
    for physics, robot in robots.items():
        start = robot.pose
        robot.command(1.7, 1.7)
        for _ in range(10):
            robot.step()
        assert robot.pose[0] - start[0] == pytest.approx(0.0225 * 1.7, rel=0.25), physics
        heading = robot.pose[2]
        robot.command(-1.7, 1.7)
        for _ in range(10):
            robot.step()
        turned[physics] = robot.pose[2] - heading
    assert 0.05 < turned["mujoco"] < 0.8 * turned["kinematic"]
    walled = build_robot(
        slip="rough",
        drift=0.0,
        drift_period=600.0,
        map_spec="free",
        seed=0,
        config=SimRobotConfig(),
        physics="mujoco",
    )
    walled.task.occupancy[:] = 1  # every cell a wall: the position stays, the heading turns
    start = walled.pose
    walled.command(-1.7, 1.7)
    for _ in range(5):
        walled.step()
    assert walled.pose[:2] == pytest.approx(start[:2], abs=1e-9)
    assert walled.pose[2] > start[2] + 0.02


def lockstep_poses(physics: str, n: int) -> tuple[list[tuple[float, ...]], float]:
    """Poses of ``n`` commands (forward, then turning) on a lockstep server with noise, drops
    and latency; and the wall time they took [s]."""
    options = {"latency": 0.02, "pose_noise": 0.001, "drop": 0.05}
    with ServerThread(physics=physics, lockstep=True, **options) as server:  # type: ignore[arg-type]
        client = RawClient(server.port)
        client.hello()
        first = client.receive_until(pr.PoseReport)
        assert isinstance(first, pr.PoseReport) and first.stamp == 0.0
        poses: list[tuple[float, ...]] = []
        started = time.monotonic()
        for k in range(n):
            seq = client.command(1.7, 1.7 if k % 20 < 10 else -1.7)
            while not isinstance(reply := client.receive_until(pr.Message), pr.Ack):
                assert isinstance(reply, pr.PoseReport)
                poses.append((reply.stamp, reply.x, reply.y, reply.heading))
            assert reply.ack == seq
        elapsed = time.monotonic() - started
        client.send(lambda s: pr.Heartbeat(seq=s, stamp=0.0))  # answered with the pose again
        again = client.receive_until(pr.PoseReport)
        assert isinstance(again, pr.PoseReport) and again.stamp == pytest.approx(poses[-1][0])
        client.close()
    return poses, elapsed


@pytest.mark.parametrize("physics", ["kinematic", "mujoco"])
def test_lockstep_same_commands_give_the_same_poses_faster_than_real_time(physics: str) -> None:
    n = 200
    first, elapsed = lockstep_poses(physics, n)
    second, _ = lockstep_poses(physics, n)
    assert first == second
    stamps = [pose[0] for pose in first]
    assert n * 0.8 < len(stamps) < n  # some dropped, each pose one period later than a command
    assert all(s == pytest.approx(round(s / 0.1) * 0.1) for s in stamps)
    assert stamps[-1] == pytest.approx(n * 0.1)
    assert elapsed < 0.5 * n * 0.1  # at least twice as fast as real time


def test_lockstep_runs_the_commands_of_one_batch_one_period_each() -> None:
    with ServerThread(physics="kinematic", lockstep=True) as server:
        client = RawClient(server.port)
        client.hello()
        stamp = time.monotonic()
        lines = [
            pr.encode(pr.Command(seq=s, omega_left=1.7, omega_right=1.7, stamp=stamp, ttl=1.0))
            for s in (1, 2, 3)
        ]
        client.sock.sendall(b"".join(lines))
        acks = [client.receive_until(pr.Ack) for _ in range(3)]
        assert [a.ack for a in acks if isinstance(a, pr.Ack)] == [1, 2, 3]
        assert server.robot.time == pytest.approx(0.3)
        dropped = pr.encode(pr.Command(seq=4, omega_left=1.7, omega_right=1.7, stamp=stamp, ttl=1))
        client.sock.sendall(dropped + pr.encode(pr.Stop(seq=5)))
        assert isinstance(client.receive_until(pr.Stopped), pr.Stopped)
        assert server.robot.time == pytest.approx(0.3)  # a cmd before a stop never runs
        client.close()


def test_physics_without_mujoco_is_one_line_and_exit_2(tmp_path: Path) -> None:
    (tmp_path / "mujoco.py").write_text("raise ImportError('no mujoco here')\n")
    env = cli_env()
    env["PYTHONPATH"] = f"{tmp_path}:{env['PYTHONPATH']}"
    command = [sys.executable, "-m", "skidnav.cli", "robot", "sim-server", "--port", "0"]
    done = subprocess.run(
        [*command, "--physics", "mujoco"], capture_output=True, text=True, env=env, timeout=60
    )
    assert done.returncode == 2
    assert len(done.stderr.strip().splitlines()) == 1 and "MuJoCo" in done.stderr
    assert "Traceback" not in done.stderr and "listening" not in done.stdout


def lockstep_run(tmp_path: Path) -> tuple[list[tuple[object, ...]], float]:
    tmp_path.mkdir()
    config = write_config(
        tmp_path,
        """
[run]
episodes = 2
max_actions = 30
map = "obstacles"

[sim]
physics = "mujoco"
lockstep = true
latency = 0.02
pose_noise = 0.001
drop = 0.02
""",
    )
    run = start_run(tmp_path, "--agent", "q-learning", "--config", str(config))
    _, stderr = run.communicate(timeout=120)
    assert run.returncode == 0, stderr
    events = read_events(tmp_path / "out" / "run.jsonl")
    assert not any(e["event"] == "trip" for e in events)
    moves = [
        (e["action"], e["next_state"], *e["pose"]) for e in events if e["event"] == "transition"
    ]
    wall = sum(e["wall_time"] for e in events if e["event"] == "episode_end")
    return moves, wall


def test_robot_run_in_lockstep_on_physics_is_repeatable_and_fast(tmp_path: Path) -> None:
    first, wall = lockstep_run(tmp_path / "a")
    second, _ = lockstep_run(tmp_path / "b")
    assert len(first) == 60 and first == second
    assert wall < 0.25 * len(first) * 1.0  # an action is 1 s of robot time
    summary = json.loads((tmp_path / "a" / "out" / "summary.json").read_text())
    assert summary["aborted"] == 0
