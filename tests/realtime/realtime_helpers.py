"""Helpers for the real-time tests: sim servers (in-process and as a subprocess), run
subprocesses, and readers for their JSON-lines logs (fixtures in conftest.py)."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from skidnav.realtime.config import ServerOptions
from skidnav.realtime.control.records import EventLog
from skidnav.realtime.link import protocol as pr
from skidnav.realtime.link.auth import Session
from skidnav.realtime.robot_server.lockstep import LockstepServer
from skidnav.realtime.robot_server.server import SimServer
from skidnav.realtime.robot_server.simulated_robot import (
    SimRobot,
    SimRobotConfig,
    build_robot,
    warm_up,
)
from skidnav.realtime.robot_server.transport import bind_listener
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import make_slip_field
from skidnav.world.discretization import Discretization

SRC = str(Path(__file__).resolve().parents[2] / "src")


def cli_env() -> dict[str, str]:
    """The environment for ``python -m skidnav.cli`` subprocesses."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [SRC, env.get("PYTHONPATH")]))
    return env


def read_events(path: Path) -> list[dict[str, Any]]:
    """The records of a JSON-lines log (a torn last line is ignored)."""
    if not path.exists():
        return []
    records = []
    for line in path.read_text(encoding="utf-8").splitlines():
        try:
            records.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return records


def wait_for(predicate: Callable[[], bool], timeout: float, what: str) -> None:
    """Poll ``predicate`` every 10 ms; fail the test after ``timeout`` seconds."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.01)
    pytest.fail(f"timed out waiting for {what}")


class ServerThread:
    """A :class:`SimServer` serving TCP on a loopback port (a free one by default) in a
    background thread, optionally logging to ``log``, injecting ``faults``, with other
    :class:`ServerOptions` from ``options``, the robot moved by ``physics`` (kinematic or
    mujoco), in ``lockstep`` if asked."""

    def __init__(
        self,
        time_scale: float = 10.0,
        *,
        log: Path | None = None,
        faults: tuple[str, ...] = (),
        map_spec: str = "free",
        port: int = 0,
        options: dict[str, Any] | None = None,
        physics: str = "kinematic",
        lockstep: bool = False,
        **robot_options: Any,
    ) -> None:
        config = SimRobotConfig(**robot_options)
        self.robot = build_robot(
            slip="rough", drift=0.0, drift_period=600.0, map_spec=map_spec, seed=0, config=config,
            physics=physics,
        )  # fmt: skip
        warm_up(self.robot)
        self.log = log
        self._stream = log.open("a", encoding="utf-8") if log else None
        settings = ServerOptions(time_scale=time_scale, faults=faults, **(options or {}))
        server_class = LockstepServer if lockstep else SimServer
        self.server = server_class(self.robot, settings, EventLog(self._stream))
        self.listener = bind_listener("127.0.0.1", port)
        self.port = int(self.listener.getsockname()[1])
        self.thread = threading.Thread(target=self.server.serve_tcp, args=(self.listener,))

    def __enter__(self) -> ServerThread:
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.server.shutdown.set()
        self.thread.join(timeout=5)
        self.listener.close()
        if self._stream is not None:
            self._stream.close()

    def events(self) -> list[dict[str, Any]]:
        assert self.log is not None
        return read_events(self.log)


class RawClient:
    """A bare socket speaking the protocol, for poking at the server; with ``secret`` it
    authenticates as a host does (every line after the robot's ``hello`` sealed and checked)."""

    def __init__(self, port: int, secret: bytes | None = None) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=2.0)
        self.buffer = pr.LineBuffer()
        self.seq = 0
        self.session = Session(secret, "host") if secret is not None else None
        self.sent: list[bytes] = []  # every line sent, as sent

    def send(self, build: Callable[[int], pr.Message]) -> int:
        seq = self.seq
        line = pr.encode(build(seq))
        if self.session is not None and self.session.keyed:
            line = self.session.seal(line)
        self.sock.sendall(line)
        self.sent.append(line)
        self.seq += 1
        return seq

    def command(self, left: float, right: float, *, ttl: float = 1.0, age: float = 0.0) -> int:
        """Send a ``cmd`` stamped ``age`` seconds ago on this machine's monotonic clock."""
        stamp = time.monotonic() - age
        return self.send(
            lambda s: pr.Command(seq=s, omega_left=left, omega_right=right, stamp=stamp, ttl=ttl)
        )

    def hello(self) -> pr.Hello:
        """Shake hands; the robot's ``hello``."""
        nonce = self.session.hello_nonce if self.session is not None else ""
        self.send(lambda seq: pr.Hello(seq=seq, name="test", nonce=nonce))
        reply = self.receive_until(pr.Hello)
        assert isinstance(reply, pr.Hello)
        return reply

    def _decode(self, line: bytes) -> pr.Message:
        """One received line; with a secret, its MAC checked (the ``hello`` keys the session)."""
        message = pr.decode(line)
        if self.session is None or (isinstance(message, pr.Error) and not self.session.keyed):
            return message
        if not self.session.keyed and isinstance(message, pr.Hello):
            self.session.greet(message.nonce)
        self.session.verify(line)
        return message

    def receive_until(self, kind: type[pr.Message], timeout: float = 2.0) -> pr.Message:
        """The next message of type ``kind`` (others are skipped)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for line in self.buffer.lines():
                message = self._decode(line)
                if isinstance(message, kind):
                    return message
            self.sock.settimeout(max(0.01, deadline - time.monotonic()))
            data = self.sock.recv(4096)
            if not data:
                raise ConnectionError("closed")
            self.buffer.feed(data)
        raise TimeoutError(f"no {kind.__name__}")

    def latest_pose(self, window: float = 0.03) -> pr.PoseReport:
        """The newest pose received within ``window`` seconds (what is buffered included)."""
        newest = None
        deadline = time.monotonic() + window
        while (remaining := deadline - time.monotonic()) > 0:
            try:
                newest = self.receive_until(pr.PoseReport, timeout=remaining)
            except (TimeoutError, OSError):
                break
        assert isinstance(newest, pr.PoseReport)
        return newest

    def close(self) -> None:
        self.sock.close()


class ServerProcess:
    """``skidnav robot sim-server`` as a subprocess with its command log."""

    def __init__(self, log: Path, *arguments: str, port: int = 0) -> None:
        command = [sys.executable, "-m", "skidnav.cli", "robot", "sim-server", "--port", str(port)]
        command += ["--log", str(log), *arguments]
        self.log = log
        self.process = subprocess.Popen(command, stdout=subprocess.PIPE, text=True, env=cli_env())
        assert self.process.stdout is not None
        line = self.process.stdout.readline()
        assert line.startswith("listening on "), line
        self.port = int(line.rsplit(":", 1)[1])

    def signal(self, signum: int) -> None:
        self.process.send_signal(signum)

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        if self.process.stdout is not None:
            self.process.stdout.close()

    def events(self) -> list[dict[str, Any]]:
        return read_events(self.log)


def start_run(tmp_path: Path, *arguments: str) -> subprocess.Popen[str]:
    """``skidnav robot run`` as a subprocess writing to ``tmp_path / "out"``."""
    command = [sys.executable, "-m", "skidnav.cli", "robot", "run", "--quiet"]
    command += ["--out", str(tmp_path / "out"), *arguments]
    return subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=cli_env()
    )


def write_config(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "realtime.toml"
    path.write_text(text, encoding="utf-8")
    return path


def bench_robot(slip: str = "rough", slip_free: bool = False) -> SimRobot:
    """A simulated robot at (0.3 m, 0.25 m, heading 0) on ``slip`` (no slip at all when
    ``slip_free``), without a server: for tests of the firmware on its own."""
    field = make_slip_field(slip, np.random.default_rng(0))
    if slip_free:
        field = type(field)(eta=np.zeros((7, 7)), x_icr=field.x_icr)
    return SimRobot(
        RobotParams(),
        field,
        None,
        Discretization(),
        SimRobotConfig(),
        np.random.default_rng(1),
        (0.3, 0.25, 0.0),
    )
