"""The TCP and serial drivers against the sim server (thread, pty) and a misbehaving peer."""

from __future__ import annotations

import os
import socket
import threading
import time

import pytest

from skidnav.realtime.control.safety import SafetyLimits, SafetyMonitor
from skidnav.realtime.link import protocol as pr
from skidnav.realtime.link.line_client import LineClient, SerialLink, TcpLink
from skidnav.realtime.robot_server.transport import FdChannel
from tests.realtime.realtime_helpers import ServerThread, wait_for


def test_tcp_client_drives_the_sim_robot_and_stops_it(server_thread: ServerThread) -> None:
    client = LineClient(TcpLink("127.0.0.1", server_thread.port))
    client.connect()
    try:
        assert client.robot_period == pytest.approx(0.1)
        wait_for(lambda: client.latest_pose() is not None, 1.0, "a first pose")
        first = client.latest_pose()
        assert first is not None
        client.command(-1.7, -1.7)
        time.sleep(0.15)
        moved = client.latest_pose()
        assert moved is not None and moved.x < first.x - 0.02
        assert moved.stamp > first.stamp  # stamped on our monotonic clock at receipt
        assert client.stop() is True
        assert server_thread.robot.wheels == (0.0, 0.0)
        assert client.fault is None
    finally:
        client.close()


def test_connect_to_nothing_raises_connection_error() -> None:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    with pytest.raises(ConnectionError):
        LineClient(TcpLink("127.0.0.1", port, connect_timeout=0.5)).connect()


def fake_robot(listener: socket.socket, script: list[bytes]) -> None:
    """Accept one client, answer its hello, then send the scripted lines 50 ms apart."""
    conn, _ = listener.accept()
    with conn:
        conn.recv(4096)
        conn.sendall(pr.encode(pr.Hello(seq=0, name="fake", period=0.1)))
        for line in script:
            time.sleep(0.05)
            conn.sendall(line)
        time.sleep(0.3)


@pytest.mark.parametrize(
    ("script", "fault"),
    [
        ([b"\xff\xfe\x00junk\n"], "malformed"),
        ([b"x" * 3000 + b"\n"], "malformed"),
        ([pr.encode(pr.Error(seq=1, code="state", message="no"))], "robot error"),
        ([], "link lost"),
    ],
)
def test_faults_reach_the_callback_at_once(script: list[bytes], fault: str) -> None:
    listener = socket.create_server(("127.0.0.1", 0))
    thread = threading.Thread(target=fake_robot, args=(listener, script))
    thread.start()
    client = LineClient(TcpLink("127.0.0.1", listener.getsockname()[1]))
    seen: list[tuple[str, float]] = []
    client.on_fault = lambda reason: seen.append((reason, time.monotonic()))
    try:
        client.connect()
        wait_for(lambda: bool(seen), 2.0, "a fault")
        assert seen[0][0].startswith(fault)
        assert client.fault == seen[0][0]
    finally:
        client.close()
        thread.join()
        listener.close()


def test_serial_client_over_a_pty_pair() -> None:
    master, slave = os.openpty()
    with ServerThread(time_scale=10.0) as holder:  # borrow its robot; serve it over the pty
        holder.server.shutdown.set()
        holder.thread.join()
        server = holder.server
        server.shutdown.clear()
        thread = threading.Thread(target=server.serve_channel, args=(FdChannel(master),))
        thread.start()
        client = LineClient(SerialLink(os.ttyname(slave)))
        try:
            client.connect()
            wait_for(lambda: client.latest_pose() is not None, 1.0, "a pose over serial")
            client.command(-1.7, -1.7)
            wait_for(lambda: server.robot.wheels == (-1.7, -1.7), 1.0, "the command")
            assert client.stop() is True
            assert server.robot.wheels == (0.0, 0.0)
        finally:
            client.close()
            server.shutdown.set()
            thread.join(timeout=5)
            os.close(slave)


class ScriptedRobot:
    """A robot on a loopback socket that answers ``hello``, sends ``lines`` once, and answers
    each ``stop`` with ``stopped`` once ``answer_after`` seconds have passed since the first
    (never, if None). Counts the stops it read."""

    def __init__(self, lines: list[bytes], answer_after: float | None = 0.0) -> None:
        self.lines, self.answer_after = lines, answer_after
        self.stops = 0
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port = self.listener.getsockname()[1]
        self.done = threading.Event()
        self.thread = threading.Thread(target=self._serve)
        self.thread.start()

    def _serve(self) -> None:
        conn, _ = self.listener.accept()
        conn.settimeout(0.01)
        buffer, first_stop, seq = pr.LineBuffer(), None, 0
        with conn:
            while not self.done.is_set():
                try:
                    data = conn.recv(4096)
                except TimeoutError:
                    continue
                if not data:
                    return
                buffer.feed(data)
                for line in buffer.lines():
                    message = pr.decode(line)
                    replies: list[bytes] = []
                    if isinstance(message, pr.Hello):
                        replies = [pr.encode(pr.Hello(seq=0, name="scripted", period=0.1))]
                        replies += self.lines
                    elif isinstance(message, pr.Stop):
                        self.stops += 1
                        first_stop = first_stop or time.monotonic()
                        late = time.monotonic() - first_stop
                        if self.answer_after is not None and late >= self.answer_after:
                            seq += 1
                            replies = [pr.encode(pr.Stopped(seq=seq, ack=message.seq))]
                    for reply in replies:
                        conn.sendall(reply)

    def close(self) -> None:
        self.done.set()
        self.thread.join(timeout=5)
        self.listener.close()


HUGE_POSE = (
    b'{"v":2,"type":"pose","seq":1,"stamp":0.1,"x":' + b"9" * 400 + b',"y":0.2,"heading":0}\n'
)


def test_a_malformed_line_trips_and_the_reader_still_confirms_the_stop() -> None:
    robot = ScriptedRobot([HUGE_POSE])
    client = LineClient(TcpLink("127.0.0.1", robot.port))
    monitor = SafetyMonitor(client, SafetyLimits(pose_timeout=5.0, check_interval=0.005))
    monitor.start()
    try:
        client.connect()
        wait_for(monitor.stop_done.is_set, 5.0, "the emergency stop")
        assert monitor.reason is not None and monitor.reason.startswith("malformed message")
        assert monitor.stop_confirmed  # the reader lived on to read the robot's stopped
        assert client._thread is not None and client._thread.is_alive()
    finally:
        monitor.close()
        client.close()
        robot.close()


def test_the_stop_is_resent_until_a_stalled_robot_confirms() -> None:
    robot = ScriptedRobot([], answer_after=0.3)
    client = LineClient(TcpLink("127.0.0.1", robot.port), stop_timeout=0.05, dead_timeout=5.0)
    try:
        client.connect()
        started = time.monotonic()
        assert client.stop() is True
        assert time.monotonic() - started >= 0.3
        assert robot.stops >= 3  # re-sent every stop_timeout / 2 meanwhile
    finally:
        client.close()
        robot.close()


def test_the_stop_gives_up_once_the_robot_is_silent_for_the_dead_timeout() -> None:
    robot = ScriptedRobot([], answer_after=None)
    client = LineClient(TcpLink("127.0.0.1", robot.port), stop_timeout=0.05, dead_timeout=0.3)
    try:
        client.connect()
        started = time.monotonic()
        assert client.stop() is False
        assert 0.3 <= time.monotonic() - started < 3.0
    finally:
        client.close()
        robot.close()
