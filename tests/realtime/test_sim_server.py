"""The simulated robot: physics (in-process) and the server's protocol behaviour (thread)."""

from __future__ import annotations

import math
import socket
import time

import numpy as np
import pytest

from skidnav.realtime.link import protocol as pr
from skidnav.realtime.robot_server.simulated_robot import SimRobot, SimRobotConfig, build_robot
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import make_slip_field
from skidnav.world.discretization import Discretization
from tests.realtime.realtime_helpers import RawClient, ServerThread


def make_robot(
    config: SimRobotConfig, occupancy: np.ndarray | None = None, integrator: str = "euler"
) -> SimRobot:
    slip = make_slip_field("thesis", np.random.default_rng(0))
    slip = type(slip)(eta=np.zeros((7, 7)), x_icr=slip.x_icr)  # no slip: exact kinematics
    grid = Discretization()
    robot = RobotParams(integrator=integrator)
    return SimRobot(
        robot, slip, occupancy, grid, config, np.random.default_rng(1), (0.2, 0.25, 0.0)
    )


def test_forward_second_moves_wheel_radius_times_speed() -> None:
    robot = make_robot(SimRobotConfig())
    robot.command(1.7, 1.7)
    for _ in range(10):
        robot.step()
    x, y, heading = robot.pose
    assert x - 0.2 == pytest.approx(0.0225 * 1.7, rel=1e-9)
    assert (y, heading) == (0.25, 0.0)
    assert robot.time == pytest.approx(1.0)


def test_turn_rotates_and_skids_sideways() -> None:
    robot = make_robot(SimRobotConfig())
    robot.command(-1.7, 1.7)
    for _ in range(10):
        robot.step()
    x, y, heading = robot.pose
    assert heading == pytest.approx(0.6375)
    assert math.hypot(x - 0.2, y - 0.25) > 0.02  # x_ICR ≠ 0 slides the body


def test_the_robots_integrator_is_used() -> None:
    """Ten exact 0.1 s steps of a constant twist are one exact 1 s step; Euler's differ."""
    from skidnav.robot.kinematics import body_velocities, exact_step

    poses = {}
    for integrator in ("euler", "exact"):
        robot = make_robot(SimRobotConfig(), integrator=integrator)
        robot.command(-1.7, 1.7)
        for _ in range(10):
            robot.step()
        poses[integrator] = robot.pose
    twist = body_velocities(-1.7, 1.7, 0.05, 0.0225, 0.06)
    closed_form = exact_step(0.2, 0.25, 0.0, *twist, 1.0)
    assert poses["exact"] == pytest.approx(closed_form, abs=1e-12)
    assert math.dist(poses["euler"][:2], closed_form[:2]) > 1e-4


def test_latency_delays_the_command() -> None:
    robot = make_robot(SimRobotConfig(latency=0.3))
    robot.command(1.7, 1.7)
    for _ in range(3):
        robot.step()
    assert robot.pose[0] == 0.2
    robot.step()
    assert robot.pose[0] > 0.2


def test_walls_block_motion() -> None:
    occupancy = np.zeros((25, 25), dtype=bool)
    occupancy[9:, :] = True  # wall from x = 9 · W/24 ≈ 0.2325 m on
    robot = make_robot(SimRobotConfig(), occupancy)
    robot.command(1.7, 1.7)
    for _ in range(30):
        robot.step()
    assert robot.grid.cell(*robot.pose[:2])[0] == 8
    assert robot.pose[0] > 0.22


def test_noise_and_drops_follow_the_config() -> None:
    robot = make_robot(SimRobotConfig(pose_noise=0.01, drop=0.3))
    reports = [robot.measured_pose() for _ in range(2000)]
    kept = [r for r in reports if r is not None]
    assert 0.25 < 1 - len(kept) / len(reports) < 0.35
    assert np.std([r[0] for r in kept]) == pytest.approx(0.01, rel=0.1)


def test_build_robot_starts_on_the_map_start() -> None:
    robot = build_robot(
        slip="slippery",
        drift=0.5,
        drift_period=60.0,
        map_spec="obstacles",
        seed=3,
        config=SimRobotConfig(),
    )
    assert robot.slip.drifting
    assert not robot.blocked(*robot.pose[:2])


def handshake(client: RawClient) -> pr.Hello:
    return client.hello()


def test_server_handshake_command_ack_pose_and_stop(server_thread: ServerThread) -> None:
    client = RawClient(server_thread.port)
    assert handshake(client).period == pytest.approx(0.1)
    first = client.receive_until(pr.PoseReport)
    assert isinstance(first, pr.PoseReport)
    seq = client.command(-1.7, -1.7)
    ack = client.receive_until(pr.Ack)
    assert isinstance(ack, pr.Ack) and ack.ack == seq
    time.sleep(0.15)  # 1.5 s of robot time at time scale 10
    moved = client.latest_pose()
    assert moved.x < first.x - 0.02 and moved.stamp > first.stamp
    stop_seq = client.send(lambda s: pr.Stop(seq=s))
    stopped = client.receive_until(pr.Stopped)
    assert isinstance(stopped, pr.Stopped) and stopped.ack == stop_seq
    assert server_thread.robot.wheels == (0.0, 0.0)
    client.close()


@pytest.mark.parametrize(
    "junk", [b"\x00\xffgarbage\n", b"{" + b"x" * 5000 + b"}\n", b'{"v":2,"type":"cmd","seq":1}\n']
)
def test_server_answers_junk_with_error_stops_and_keeps_serving(
    server_thread: ServerThread, junk: bytes
) -> None:
    client = RawClient(server_thread.port)
    handshake(client)
    client.command(1.7, 1.7)
    client.receive_until(pr.Ack)
    client.sock.sendall(junk)
    assert isinstance(client.receive_until(pr.Error), pr.Error)
    assert server_thread.robot.wheels == (0.0, 0.0)
    seq = client.send(lambda s: pr.Stop(seq=s))
    reply = client.receive_until(pr.Stopped)
    assert isinstance(reply, pr.Stopped) and reply.ack == seq
    client.close()


def test_server_requires_hello_and_refuses_a_second_client(server_thread: ServerThread) -> None:
    client = RawClient(server_thread.port)
    client.command(1.0, 1.0)
    error = client.receive_until(pr.Error)
    assert isinstance(error, pr.Error) and error.code == "state"
    other = RawClient(server_thread.port)
    busy = other.receive_until(pr.Error)
    assert isinstance(busy, pr.Error) and busy.code == "busy"
    other.close()
    client.close()
    time.sleep(0.05)
    again = RawClient(server_thread.port)  # the slot is free again
    handshake(again)
    again.close()


def test_server_stops_the_wheels_when_the_client_goes_quiet() -> None:
    with ServerThread(time_scale=10.0, options={"link_timeout": 0.1}) as server:
        client = RawClient(server.port)
        handshake(client)
        client.command(1.7, 1.7)
        client.receive_until(pr.Ack)
        assert server.robot.moving
        time.sleep(0.3)
        assert server.robot.wheels == (0.0, 0.0)
        client.close()


def test_server_survives_a_client_that_vanishes(server_thread: ServerThread) -> None:
    raw = socket.create_connection(("127.0.0.1", server_thread.port))
    raw.sendall(pr.encode(pr.Hello(seq=0, name="x")) + b'{"v":1,"type":"cmd"')
    raw.close()
    time.sleep(0.05)
    client = RawClient(server_thread.port)
    handshake(client)
    client.close()
