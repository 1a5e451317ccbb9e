"""The simulated robot server: a :class:`~skidnav.realtime.sim_robot.SimRobot` behind the line
protocol (docs/protocol.md), for hardware-in-the-loop runs of the real-time platform.

Every control period (``robot.dt`` of robot time, ``robot.dt / time_scale`` of wall time) the
server advances the physics and sends one ``pose`` (unless dropped). It serves one client at a
time over TCP (bound to 127.0.0.1 by default) or over any byte channel (a pty, a serial line).
Like firmware should, it stops the wheels when a line is malformed (and replies ``error``), when
the client goes quiet for ``link_timeout`` wall seconds, and when the client disconnects.

Every received command, stop, fault and disconnect is appended to a JSON-lines log with the
system-wide monotonic clock (``mono`` [s]), so tests can measure when a zero command arrived.

Fault injection for tests: with ``faults`` set, each SIGUSR1 (or :meth:`SimServer.inject`)
triggers the next one of them (cycling) at the next period: ``silence`` (no more poses),
``garbage`` (one line of junk bytes), ``oversized`` (one line over the length cap), ``escape``
(poses reported outside the arena from then on), ``hangup`` (the client is disconnected).
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import selectors
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import IO, Protocol

from skidnav.realtime import protocol as pr
from skidnav.realtime.sim_robot import SimRobot

log = logging.getLogger(__name__)

FAULTS = ("silence", "garbage", "oversized", "escape", "hangup")


@dataclass(frozen=True)
class ServerOptions:
    """Timing and behaviour of the server, validated on construction.

    Attributes:
        time_scale: robot seconds per wall second (> 0); 10 runs ten times faster than real time.
        link_timeout: wall seconds without any line from the client before the wheels stop.
        faults: the faults successive SIGUSR1s inject, in order (each one of :data:`FAULTS`).
        name: robot name sent in ``hello``.
    """

    time_scale: float = 1.0
    link_timeout: float = 0.5
    faults: tuple[str, ...] = ()
    name: str = "skidnav-sim"

    def __post_init__(self) -> None:
        if not self.time_scale > 0:
            raise ValueError(f"expected time_scale > 0, got {self.time_scale}")
        if not self.link_timeout > 0:
            raise ValueError(f"expected link_timeout > 0 s, got {self.link_timeout}")
        for fault in self.faults:
            if fault not in FAULTS:
                raise ValueError(f"expected faults among {', '.join(FAULTS)}, got {fault!r}")


class Channel(Protocol):
    """A connected byte stream the server can select on."""

    def fileno(self) -> int: ...
    def read(self) -> bytes: ...
    def write(self, data: bytes) -> None: ...
    def close(self) -> None: ...


class SocketChannel:
    """A connected TCP socket as a :class:`Channel` (``read`` returns b"" at EOF)."""

    def __init__(self, sock: socket.socket) -> None:
        self.sock = sock
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def fileno(self) -> int:
        return self.sock.fileno()

    def read(self) -> bytes:
        return self.sock.recv(4096)

    def write(self, data: bytes) -> None:
        self.sock.sendall(data)

    def close(self) -> None:
        self.sock.close()


class FdChannel:
    """A file descriptor (a pty master, a serial device) as a :class:`Channel`."""

    def __init__(self, fd: int) -> None:
        self.fd = fd

    def fileno(self) -> int:
        return self.fd

    def read(self) -> bytes:
        return os.read(self.fd, 4096)

    def write(self, data: bytes) -> None:
        os.write(self.fd, data)

    def close(self) -> None:
        os.close(self.fd)


class EventLog:
    """Append-only JSON-lines log (flushed per line); a no-op without a file."""

    def __init__(self, stream: IO[str] | None) -> None:
        self.stream = stream

    def write(self, event: str, **fields: object) -> None:
        if self.stream is None:
            return
        record = {"mono": time.monotonic(), "wall": time.time(), "event": event, **fields}
        self.stream.write(json.dumps(record) + "\n")
        self.stream.flush()


class SimServer:
    """Serves one :class:`SimRobot` (see module doc).

    Args:
        robot: the simulated robot (its period is ``robot.robot.dt``).
        options: timing and behaviour.
        events: the command log.
    """

    def __init__(self, robot: SimRobot, options: ServerOptions, events: EventLog) -> None:
        self.robot = robot
        self.options = options
        self.events = events
        self.period_wall = robot.robot.dt / options.time_scale
        self._seq = 0
        self._channel: Channel | None = None
        self._buffer = pr.LineBuffer()
        self._greeted = False
        self._last_rx = 0.0
        self._detach_hook: Callable[[Channel], None] | None = None
        self._fault_requested = threading.Event()
        self._active_faults: set[str] = set()
        self._faults_injected = 0
        self.shutdown = threading.Event()

    def inject(self) -> None:
        """Trigger the configured fault at the next period (safe from a signal handler)."""
        self._fault_requested.set()

    # --- sending -------------------------------------------------------------------------
    def _send(self, build: Callable[[int], pr.Message]) -> None:
        if self._channel is None:
            return
        message = build(self._seq)
        self._seq += 1
        try:
            self._channel.write(pr.encode(message))
        except OSError:
            self._drop("write failed")

    def _send_raw(self, data: bytes) -> None:
        if self._channel is not None:
            try:
                self._channel.write(data)
            except OSError:
                self._drop("write failed")

    # --- connection ----------------------------------------------------------------------
    def attach(self, channel: Channel) -> None:
        """Make ``channel`` the current client."""
        self._channel = channel
        self._buffer = pr.LineBuffer()
        self._greeted = False
        self._last_rx = time.monotonic()
        self._active_faults.discard("silence")
        self._active_faults.discard("escape")
        self.events.write("connect")

    def _drop(self, reason: str) -> None:
        """Forget the client and stop the wheels."""
        channel, self._channel = self._channel, None
        self.robot.stop()
        self.events.write("disconnect", reason=reason)
        log.info("client dropped: %s", reason)
        if channel is not None:
            if self._detach_hook is not None:
                self._detach_hook(channel)
            with contextlib.suppress(OSError):
                channel.close()

    @property
    def connected(self) -> bool:
        """True while a client is attached."""
        return self._channel is not None

    # --- receiving -----------------------------------------------------------------------
    def receive(self) -> None:
        """Read what the client sent and answer every complete line."""
        assert self._channel is not None
        try:
            data = self._channel.read()
        except OSError:
            data = b""
        if not data:
            self._drop("end of stream")
            return
        self._last_rx = time.monotonic()
        self._buffer.feed(data)
        while self._channel is not None:
            try:
                for line in self._buffer.lines():
                    self._handle_line(line)
                    if self._channel is None:
                        return
                return
            except pr.ProtocolError as error:
                self._reject(error.code, str(error))

    def _reject(self, code: str, text: str) -> None:
        """Malformed input: stop the wheels and report it."""
        self.robot.stop()
        self.events.write("error", code=code, message=text)
        self._send(lambda seq: pr.Error(seq=seq, code=code, message=text[:200]))

    def _handle_line(self, line: bytes) -> None:
        try:
            message = pr.decode(line)
        except pr.ProtocolError as error:
            self._reject(error.code, str(error))
            return
        if isinstance(message, pr.Hello):
            self._greeted = True
            self.events.write("hello", name=message.name)
            period = self.robot.robot.dt
            self._send(lambda seq: pr.Hello(seq=seq, name=self.options.name, period=period))
        elif not self._greeted:
            self._reject("state", f"{message.TYPE} before hello")
        elif isinstance(message, pr.Command):
            self.robot.command(message.omega_left, message.omega_right)
            self.events.write(
                "cmd",
                seq=message.seq,
                omega_left=message.omega_left,
                omega_right=message.omega_right,
                robot_time=self.robot.time,
            )
            self._send(lambda seq: pr.Ack(seq=seq, ack=message.seq))
        elif isinstance(message, pr.Stop):
            self.robot.stop()
            self.events.write("stop", seq=message.seq, robot_time=self.robot.time)
            self._send(lambda seq: pr.Stopped(seq=seq, ack=message.seq))
        elif isinstance(message, pr.Heartbeat):
            self._send(lambda seq: pr.Heartbeat(seq=seq, stamp=self.robot.time))
        elif isinstance(message, pr.Error):
            self.events.write("peer_error", code=message.code, message=message.message)
        else:
            self._reject("state", f"unexpected {message.TYPE} from host")

    # --- the period ----------------------------------------------------------------------
    def _apply_fault(self) -> None:
        self._fault_requested.clear()
        if not self.options.faults:
            return
        fault = self.options.faults[self._faults_injected % len(self.options.faults)]
        self._faults_injected += 1
        self.events.write("fault", fault=fault, robot_time=self.robot.time)
        log.info("injecting fault %s", fault)
        if fault in ("silence", "escape"):
            self._active_faults.add(fault)
        elif fault == "garbage":
            self._send_raw(b"\x00\xff\xfe not json {{{\n")
        elif fault == "oversized":
            self._send_raw(b"{" + b"x" * (2 * pr.MAX_LINE_BYTES) + b"}\n")
        elif fault == "hangup" and self._channel is not None:
            self._drop("fault hangup")

    def tick(self) -> None:
        """One control period: faults, link watchdog, physics, pose report."""
        if self._fault_requested.is_set():
            self._apply_fault()
        if self.connected and time.monotonic() - self._last_rx > self.options.link_timeout:
            if self.robot.wheels != (0.0, 0.0):
                self.events.write("watchdog", robot_time=self.robot.time)
            self.robot.stop()
        self.robot.step()
        if not (self.connected and self._greeted) or "silence" in self._active_faults:
            return
        measured = self.robot.measured_pose()
        if measured is None:
            return
        x, y, heading = measured
        if "escape" in self._active_faults:
            x = -0.3
        stamp = self.robot.time
        self._send(lambda seq: pr.PoseReport(seq=seq, stamp=stamp, x=x, y=y, heading=heading))

    # --- main loops ----------------------------------------------------------------------
    def _loop(self, selector: selectors.BaseSelector, on_ready: Callable[[int], None]) -> None:
        """Tick at the wall-clock period; ``on_ready(fd)`` handles a readable descriptor."""
        next_tick = time.monotonic()
        while not self.shutdown.is_set():
            timeout = max(0.0, next_tick - time.monotonic())
            for key, _ in selector.select(timeout):
                on_ready(key.fd)
            now = time.monotonic()
            if now >= next_tick:
                self.tick()
                next_tick += self.period_wall
                if next_tick < now - self.period_wall:
                    next_tick = now  # fell behind (machine busy): no burst of catch-up ticks

    def serve_channel(self, channel: Channel) -> None:
        """Serve one already-connected channel until it closes or :attr:`shutdown` is set."""
        self.attach(channel)
        with selectors.DefaultSelector() as selector:
            selector.register(channel.fileno(), selectors.EVENT_READ)

            def ready(fd: int) -> None:
                if self.connected:
                    self.receive()
                if not self.connected:
                    self.shutdown.set()

            try:
                self._loop(selector, ready)
            finally:
                if self.connected:
                    self._drop("server shutdown")

    def serve_tcp(self, listener: socket.socket) -> None:
        """Accept clients on ``listener`` (one at a time; others get ``error busy``) until
        :attr:`shutdown` is set."""
        listener.setblocking(False)
        with selectors.DefaultSelector() as selector:
            selector.register(listener.fileno(), selectors.EVENT_READ)

            def detach(channel: Channel) -> None:
                selector.unregister(channel.fileno())

            self._detach_hook = detach

            def ready(fd: int) -> None:
                if fd == listener.fileno():
                    self._accept(listener, selector)
                elif self.connected:
                    self.receive()

            try:
                self._loop(selector, ready)
            finally:
                if self.connected:
                    self._drop("server shutdown")
                self._detach_hook = None

    def _accept(self, listener: socket.socket, selector: selectors.BaseSelector) -> None:
        sock, _ = listener.accept()
        sock.setblocking(True)
        if self.connected:
            busy = pr.Error(seq=0, code="busy", message="another client is connected")
            try:
                sock.sendall(pr.encode(busy))
            finally:
                sock.close()
            return
        channel = SocketChannel(sock)
        self.attach(channel)
        selector.register(channel.fileno(), selectors.EVENT_READ)


def bind_listener(host: str, port: int) -> socket.socket:
    """A listening TCP socket on (host, port); port 0 picks a free one."""
    listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    listener.bind((host, port))
    listener.listen(2)
    return listener
