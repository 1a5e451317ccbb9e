"""The reference robot against skidnav's real host: the line client over TCP and over a serial
line (two pseudo-terminals, pyserial on both ends), a whole ``skidnav robot run --driver tcp``
and ``--driver serial``, and the cases the sim server's tests put to it — busy, replay,
expired, range, oversized, the lease and link timeout, a stall, authentication."""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from skidnav.realtime.link import protocol as pr
from skidnav.realtime.link.line_client import LineClient, SerialLink, TcpLink
from tests.cli_support import exit_code
from tests.realtime.realtime_helpers import (
    RawClient,
    read_events,
    start_run,
    wait_for,
    write_config,
)
from tests.realtime.reference_robot_helpers import PtyBridge, RobotProcess, RobotThread
from tests.realtime.test_link_auth import refused
from tests.realtime.test_wire_server import busy_or_closed, check_replays_refused

SECRET = b"the lab's shared secret, 33 bytes"


def drive_and_stop(client: LineClient, robot: RobotThread | None = None) -> None:
    """Connect, see poses, drive forward, see the robot move, stop it with confirmation."""
    client.connect()
    try:
        wait_for(lambda: client.latest_measurement() is not None, 2.0, "a first pose")
        first = client.latest_measurement()
        assert first is not None
        client.command(1.7, 1.7)
        wait_for(lambda: client.latest_pose().x > first[0].x + 0.005, 3.0, "the robot to move")  # type: ignore[union-attr]
        assert client.stop() is True
        if robot is not None:
            assert robot.base.wheels == (0.0, 0.0)
        assert client.fault is None
    finally:
        client.close()


def connect_once_free(make_client: Callable[[], LineClient], within: float = 5.0) -> LineClient:
    """A client of ``make_client`` connected, trying again while the robot still answers
    ``busy`` (it frees the link when it reads the previous client's hang-up, later on a loaded
    machine); any other refusal is raised at once."""
    deadline = time.monotonic() + within
    while True:
        client = make_client()
        try:
            client.connect()
            return client
        except ConnectionError as refused:
            client.close()
            if "busy" not in str(refused) or time.monotonic() > deadline:
                raise
            time.sleep(0.05)


def test_the_line_client_drives_the_reference_robot_over_tcp() -> None:
    with RobotThread() as robot:
        client = LineClient(TcpLink("127.0.0.1", robot.port))
        drive_and_stop(client, robot)
        assert client.robot_period == pytest.approx(0.02)
        assert robot.kinds()[:3] == ["connect", "hello", "cmd"]


def test_a_second_host_is_busy_and_the_slot_frees_when_the_first_leaves() -> None:
    with RobotThread() as robot:
        first = RawClient(robot.port)
        assert first.hello().name == "skidnav-reference"
        second = socket.create_connection(("127.0.0.1", robot.port), timeout=2.0)
        assert busy_or_closed(second) == "busy"
        second.close()
        first.close()
        wait_for(lambda: "disconnect" in robot.kinds(), 2.0, "the first host to be dropped")
        again = RawClient(robot.port)
        assert again.hello().name == "skidnav-reference"
        again.close()


@pytest.mark.parametrize("secret", [None, SECRET], ids=["plain", "auth"])
def test_a_replayed_or_older_command_is_refused_not_acknowledged(secret: bytes | None) -> None:
    with RobotThread(secret=secret) as robot:
        check_replays_refused(
            RawClient(robot.port, secret=secret), lambda: robot.base.wheels == (0.0, 0.0)
        )


@pytest.mark.parametrize(
    ("junk", "code"),
    [
        (b"{" + b"x" * 5000 + b"}\n", "oversized"),
        (b"\x00\xffgarbage\n", "encoding"),
        (
            b'{"v":2,"type":"cmd","seq":90,"omega_left":1.7000001,"omega_right":0,"stamp":0,"ttl":1}\n',
            "range",
        ),
    ],
)
def test_junk_is_answered_with_an_error_stops_the_wheels_and_the_robot_serves_on(
    junk: bytes, code: str
) -> None:
    with RobotThread() as robot:
        client = RawClient(robot.port)
        client.hello()
        client.command(1.7, 1.7)
        client.receive_until(pr.Ack)
        client.sock.sendall(junk)
        error = client.receive_until(pr.Error)
        assert isinstance(error, pr.Error) and error.code == code
        assert robot.base.wheels == (0.0, 0.0)
        client.seq = 100
        seq = client.send(lambda s: pr.Stop(seq=s))
        stopped = client.receive_until(pr.Stopped)
        assert isinstance(stopped, pr.Stopped) and stopped.ack == seq
        client.close()


def test_a_command_read_after_its_deadline_is_refused() -> None:
    with RobotThread() as robot:
        client = RawClient(robot.port)
        client.hello()
        client.send(lambda seq: pr.Heartbeat(seq=seq, stamp=time.monotonic()))  # the clock
        client.command(1.7, 1.7, ttl=0.2, age=0.5)
        error = client.receive_until(pr.Error)
        assert isinstance(error, pr.Error) and error.code == "expired"
        assert robot.base.wheels == (0.0, 0.0)
        fresh = client.command(1.7, 1.7, ttl=0.2, age=0.05)
        ack = client.receive_until(pr.Ack)
        assert isinstance(ack, pr.Ack) and ack.ack == fresh
        client.close()


def test_the_lease_and_the_link_timeout_stop_the_wheels_by_themselves() -> None:
    with RobotThread(max_lease=0.15, link_timeout=0.3, idle_timeout=0.6) as robot:
        client = RawClient(robot.port)
        client.hello()
        client.command(1.7, 1.7, ttl=5.0)
        client.receive_until(pr.Ack)
        sent = time.monotonic()
        while robot.base.wheels != (0.0, 0.0) and time.monotonic() - sent < 2.0:
            client.send(lambda seq: pr.Heartbeat(seq=seq, stamp=time.monotonic()))
            time.sleep(0.02)
        assert 0.15 <= time.monotonic() - sent < 0.5  # the lease ran out on a live link
        assert "lease" in robot.kinds() and "watchdog" not in robot.kinds()
        client.command(1.7, 1.7, ttl=5.0)  # then the link goes quiet
        client.receive_until(pr.Ack)
        quiet = time.monotonic()
        wait_for(lambda: robot.base.wheels == (0.0, 0.0), 1.0, "the lease or watchdog")
        wait_for(lambda: "disconnect" in robot.kinds(), 2.0, "the idle host to be dropped")
        assert time.monotonic() - quiet >= 0.6
        client.close()


@pytest.mark.parametrize("host_stops", [True, False], ids=["host-stops", "host-silent"])
def test_a_robot_frozen_mid_action_never_resumes_the_old_command(host_stops: bool) -> None:
    """Commands (and the tripped host's stop) queue up while the robot's loop is frozen; when
    it resumes it runs none of them: the wheels stay at zero and the pose stays put."""
    with RobotThread() as robot:
        client = LineClient(TcpLink("127.0.0.1", robot.port), command_ttl=0.1, stop_timeout=0.1)
        client.connect()
        try:
            client.command(1.7, 1.7)
            wait_for(lambda: robot.base.wheels == (1.7, 1.7), 1.0, "the wheels to turn")
            freezing = robot.freeze  # commands go on for 0.1 s of the 0.4 s freeze
            thread = threading.Thread(target=lambda: stamps.extend(freezing(0.4)))
            stamps: list[float] = []
            thread.start()
            for _ in range(5):
                client.command(1.7, 1.7)
                time.sleep(0.02)
            if host_stops:
                stopping = threading.Thread(target=lambda: confirmed.append(client.stop()))
                confirmed: list[bool] = []
                stopping.start()
            thread.join()
            thawed = stamps[1]
            time.sleep(0.1)
            assert robot.base.wheels == (0.0, 0.0)
            assert "cmd" not in robot.kinds(after=thawed)
            pose = robot.base.pose(time.monotonic())
            time.sleep(0.1)
            assert robot.base.pose(time.monotonic()) == pose
            if host_stops:
                stopping.join()
                assert confirmed == [True]  # confirmed once the robot lived again
            else:
                codes = [f.get("code") for t, e, f in robot.events if t >= thawed and e == "error"]
                assert "expired" in codes  # the newest command was read too late
        finally:
            client.close()


def test_only_a_host_with_the_secret_drives_an_authenticated_robot() -> None:
    with RobotThread(secret=SECRET) as robot:
        plain = RawClient(robot.port)  # a hello without a nonce, then a command
        plain.send(lambda seq: pr.Hello(seq=seq, name="intruder"))
        plain.command(1.7, 1.7)
        assert refused(plain) == "auth"
        with pytest.raises(ConnectionError, match="robot not authenticated"):
            connect_once_free(
                lambda: LineClient(
                    TcpLink("127.0.0.1", robot.port), secret=b"not the lab's secret at all"
                )
            )
        assert robot.base.pose(time.monotonic()) == (0.3, 0.25, 0.0)
        assert "cmd" not in robot.kinds()
        drive_and_stop(LineClient(TcpLink("127.0.0.1", robot.port), secret=SECRET), robot)


def test_an_authenticated_host_refuses_a_robot_without_the_secret() -> None:
    with RobotThread(secret=b"another secret of the lab, 30 b") as robot:
        client = LineClient(TcpLink("127.0.0.1", robot.port), secret=SECRET)
        with pytest.raises(ConnectionError, match="robot not authenticated"):
            client.connect()
        assert "cmd" not in robot.kinds()


def test_the_line_client_drives_it_over_a_serial_line_and_reconnects() -> None:
    with PtyBridge() as bridge:
        robot = RobotProcess("--serial", bridge.robot_end, "--period", "0.02")
        try:
            for _ in range(2):  # the second time the port is opened anew: a new session
                drive_and_stop(LineClient(SerialLink(bridge.host_end)))
        finally:
            code, err = robot.stop()
    assert code == 0
    assert err.count('"event": "hello"') == 2 and '"event": "cmd"' in err


def run_config(tmp_path: Path, table: str) -> Path:
    return write_config(
        tmp_path,
        f"""
[run]
episodes = 1
max_actions = 3
period = 0.05
substeps = 4

{table}
""",
    )


@pytest.mark.parametrize("driver", ["tcp", "serial"])
def test_skidnav_robot_run_drives_the_reference_robot(tmp_path: Path, driver: str) -> None:
    with PtyBridge() as bridge:
        if driver == "tcp":
            robot = RobotProcess("--tcp", "127.0.0.1:0", "--period", "0.05")
            table = f"[tcp]\nport = {robot.port}"
        else:
            robot = RobotProcess("--serial", bridge.robot_end, "--period", "0.05")
            table = f'[serial]\nurl = "{bridge.host_end}"'
        config = run_config(tmp_path, table)
        run = start_run(
            tmp_path, "--driver", driver, "--agent", "q-learning", "--config", str(config)
        )
        try:
            _, err = run.communicate(timeout=60)
        finally:
            code, robot_err = robot.stop()
    assert run.returncode == 0, err
    assert code == 0
    events = read_events(tmp_path / "out" / "run.jsonl")
    assert [e["event"] for e in events].count("transition") == 3
    assert not [e for e in events if e["event"] == "trip"]
    # every command the host sent reached the robot, at least one per action: periods are
    # counted on the robot's clock, so a host that reads a pose late sends fewer than one per
    # period (substeps = 4) while the robot's time still advances four periods per action
    commands = robot_err.count('"event": "cmd"')
    assert 3 <= commands <= [e["event"] for e in events].count("cmd")
    poses = [(e["x"], e["y"], e["heading"]) for e in events if e["event"] == "pose"]
    # the robot's start (its own pose source, not the simulator's), and it moved; on a busy
    # machine the first pose logged may come a few periods late, already turned a little
    assert all(abs(a - b) <= 0.05 for a, b in zip(poses[0], (0.3, 0.25, 0.0), strict=True))
    assert poses[-1] != poses[0]


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        ([], "one of the arguments --tcp --serial is required"),
        (["--tcp", "127.0.0.1:99999"], "expected HOST:PORT with a port in [0, 65535]"),
        (["--tcp", "0.0.0.0:0"], "refusing to serve the robot link on 0.0.0.0 without a secret"),
        (["--tcp", "127.0.0.1:0", "--period", "nan"], "expected a finite number > 0"),
        (["--tcp", "127.0.0.1:0", "--max-lease", "9"], "expected --max-lease in (0, 5.0]"),
        (["--tcp", "127.0.0.1:0", "--secret-file", "{short}"], "at least 16 bytes, got 5"),
        (["--serial", "{missing}"], "cannot open"),
    ],
)
def test_bad_arguments_end_in_one_line_and_exit_code_2(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    argv: list[str],
    needle: str,
) -> None:
    from skidnav.realtime.reference_robot.cli import main

    monkeypatch.delenv("SKIDNAV_LINK_SECRET", raising=False)
    short = tmp_path / "short.key"
    short.write_text("short\n", encoding="utf-8")
    arguments = [a.format(short=short, missing=tmp_path / "no-such-port") for a in argv]
    code = exit_code(arguments, main)
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert code == 2 and captured.out == ""
    assert len(lines) == 1 and lines[0].startswith("reference-robot: error: "), captured.err
    assert needle in lines[0]


def test_the_command_line_robot_authenticates_with_its_secret_file(tmp_path: Path) -> None:
    key = tmp_path / "robot.key"
    key.write_bytes(SECRET + b"\n")
    robot = RobotProcess("--tcp", "127.0.0.1:0", "--secret-file", str(key))
    try:
        drive_and_stop(LineClient(TcpLink("127.0.0.1", robot.port), secret=SECRET))
        with pytest.raises(ConnectionError, match="robot not authenticated"):
            connect_once_free(
                lambda: LineClient(
                    TcpLink("127.0.0.1", robot.port), secret=b"not the lab's secret at all"
                )
            )
    finally:
        code, err = robot.stop()
    assert code == 0 and err.count('"event": "cmd"') >= 1
    assert "Traceback" not in err
