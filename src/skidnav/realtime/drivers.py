"""Robot drivers by name, ``sim``, ``tcp``, ``serial`` and ``ros2`` (docs/realtime.md), configured
from a run's :class:`~skidnav.realtime.config.RealtimeConfig`; the links they speak over are in
:mod:`skidnav.realtime.link`.

``sim`` starts ``skidnav robot sim-server`` as a child process on a free loopback port (with the
run's map, seed, time scale and ``[sim]`` settings, and a lease as long as the run's command
``ttl``; without the current directory on its ``sys.path``, :mod:`skidnav.childprocess`) and
talks to it over TCP; reconnecting after a fault restarts the server if it died. The child's
standard input is a pipe from this process and the server exits at its end of stream
(``--exit-with-stdin``): when this process ends in any way, SIGKILL included, the kernel closes
the pipe and the server follows. ``ros2`` is built by ``skidnav.realtime.link.ros2`` when that
module is installed.

The line drivers authenticate the link (docs/protocol.md, "Authentication") with the secret in
the file ``secret_file`` of their table, else in the environment variable
``SKIDNAV_LINK_SECRET`` (which a ``sim`` server inherits); without either, they do not. A secret
named but unreadable, too short or empty is a UserError (:func:`link_secret`), never a plain
link.
"""

from __future__ import annotations

import importlib
import logging
import subprocess
from pathlib import Path
from typing import Any

from skidnav.childprocess import child_environment, python_module_command
from skidnav.errors import UserError
from skidnav.extras import require
from skidnav.realtime.config import RealtimeConfig
from skidnav.realtime.driver_settings import SerialSettings, TcpSettings
from skidnav.realtime.link.auth import load_secret
from skidnav.realtime.link.interface import RobotDriver
from skidnav.realtime.link.line_client import LineClient, SerialLink, TcpLink
from skidnav.realtime.reference_robot.rules import MAX_LEASE_LIMIT

log = logging.getLogger(__name__)

DRIVERS = ("sim", "tcp", "serial", "ros2")
DRIVER_EXTRAS = {"serial": "serial", "ros2": "ros2"}
"""The drivers that need an extra (:mod:`skidnav.extras`) → that extra."""


def require_driver_extras(name: str, config: RealtimeConfig) -> None:
    """Refuse, before anything runs, driver ``name`` on ``config`` when an extra it needs is
    missing: ``serial`` and ``ros2`` (:data:`DRIVER_EXTRAS`), and a ``sim`` server moved by the
    MuJoCo robot (``[sim] physics = "mujoco"``).

    Raises:
        MissingExtraError: one line naming the ``pip install`` that brings it.
    """
    if name in DRIVER_EXTRAS:
        require(DRIVER_EXTRAS[name], f"--driver {name}")
    if name == "sim" and config.sim.physics == "mujoco":
        require("physics", '[sim] physics = "mujoco"')


class SimServerProcess:
    """A ``skidnav robot sim-server`` child process on 127.0.0.1 with a free port."""

    def __init__(self, arguments: list[str], log_path: Path | None = None) -> None:
        self.arguments = arguments
        self.log_path = log_path
        self.process: subprocess.Popen[str] | None = None
        self.port = 0

    def start(self) -> int:
        """Start the server (if not running) and return its port; ConnectionError on failure."""
        if self.process is not None and self.process.poll() is None:
            return self.port
        command = python_module_command("skidnav.cli", "robot", "sim-server", "--port", "0")
        command += ["--exit-with-stdin", *self.arguments]
        if self.log_path is not None:
            command += ["--log", str(self.log_path)]
        self.process = subprocess.Popen(
            command,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            env=child_environment(),
        )
        assert self.process.stdout is not None
        line = self.process.stdout.readline()
        if not line.startswith("listening on "):
            self.stop()
            raise ConnectionError("the sim server did not start")
        self.port = int(line.rsplit(":", 1)[1])
        return self.port

    def stop(self) -> None:
        """Terminate the server and wait for it."""
        if self.process is None:
            return
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=5.0)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        for stream in (self.process.stdin, self.process.stdout):
            if stream is not None:
                stream.close()
        self.process = None


class SimDriver(LineClient):
    """The line client connected to a sim server child process it owns."""

    def __init__(self, server: SimServerProcess, **client_options: Any) -> None:
        super().__init__(TcpLink("127.0.0.1", 0), **client_options)
        self.server = server

    def connect(self) -> None:
        """(Re)start the server if needed, then connect and shake hands."""
        self.close()
        port = self.server.start()
        self.link = TcpLink("127.0.0.1", port)
        super().connect()

    def shutdown(self) -> None:
        """Close the link and end the server process."""
        self.close()
        self.server.stop()


def link_secret(name: str, config: RealtimeConfig) -> bytes | None:
    """The link secret of driver ``name``: the file of ``[tcp]`` or ``[serial]``
    ``secret_file``, else ``SKIDNAV_LINK_SECRET`` (``sim`` too: its server inherits it), else
    None; always None for ``ros2``. UserError in one line (the secret never shown) if the file
    cannot be read, or the file or the variable holds fewer than 16 bytes."""
    if name == "ros2":
        return None
    line = _line_settings(name, config)
    return load_secret(line.secret_file if line is not None else None)


def _line_settings(name: str, config: RealtimeConfig) -> TcpSettings | SerialSettings | None:
    """The table of line driver ``name`` (``[tcp]`` or ``[serial]``); None for another."""
    lines: dict[str, TcpSettings | SerialSettings] = {"tcp": config.tcp, "serial": config.serial}
    return lines.get(name)


def make_driver(name: str, config: RealtimeConfig, server_log: Path | None = None) -> RobotDriver:
    """The driver ``name`` configured from ``config`` (``[tcp]``, ``[serial]``, ``[ros2]``,
    ``[sim]`` and ``[run]``); ``server_log`` is the sim server's command log (sim only)."""
    if name == "ros2":
        return _make_ros2_driver(config)
    line = _line_settings(name, config)
    client: dict[str, Any] = {
        "stop_timeout": max(0.05, 2 * config.run.period_wall),
        "command_ttl": config.run.pose_timeout,  # a command lives as long as a pose may lag
        "lockstep": config.sim.lockstep if line is None else line.lockstep,
        "secret": link_secret(name, config),
        "time_scale": config.run.time_scale,
    }
    if name == "sim":
        run = config.run
        arguments = [
            "--max-lease",
            str(min(run.pose_timeout, MAX_LEASE_LIMIT)),
            "--time-scale",
            str(run.time_scale),
            "--map",
            run.map,
            "--seed",
            str(run.seed),
            *config.sim.server_arguments(),
        ]
        return SimDriver(SimServerProcess(arguments, server_log), **client)
    if name == "tcp":
        return LineClient(TcpLink(config.tcp.host, config.tcp.port), **client)
    if name == "serial":
        return LineClient(SerialLink(config.serial.url, config.serial.baudrate), **client)
    raise UserError(f"unknown driver {name!r}; expected one of {', '.join(DRIVERS)}")


def _make_ros2_driver(config: RealtimeConfig) -> RobotDriver:
    """The rosbridge driver of ``skidnav.realtime.link.ros2`` with the ``[ros2]`` settings."""
    module = importlib.import_module("skidnav.realtime.link.ros2")  # lazily: it imports roslibpy
    driver: RobotDriver = module.Ros2Driver(config.ros2)
    return driver
