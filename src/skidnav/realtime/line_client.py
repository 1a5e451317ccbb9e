"""Robot drivers speaking the line protocol (docs/protocol.md) over TCP or a serial line.

:class:`LineClient` implements :class:`~skidnav.realtime.driver.RobotDriver` over any
:class:`Link` (a byte stream). A reader thread parses incoming lines, keeps the newest pose
(stamped on this process's monotonic clock at receipt), collects ``ack``/``stopped`` replies and
sends a ``heartbeat`` whenever nothing was sent for ``heartbeat_interval`` seconds. A lost link,
a malformed line or an ``error`` from the robot is a *fault*: it is kept in :attr:`fault` and
passed at once to the fault callback (the safety monitor's trip).
"""

from __future__ import annotations

import logging
import socket
import threading
import time
from collections.abc import Callable
from typing import Protocol

import serial

from skidnav.realtime import protocol as pr
from skidnav.realtime.driver import Pose

log = logging.getLogger(__name__)

READ_POLL = 0.005
"""Longest a link read blocks [s]: bounds how late a heartbeat or a shutdown can be."""


class Link(Protocol):
    """A byte stream to the robot."""

    def open(self) -> None: ...
    def read(self) -> bytes:
        """Bytes received (b"" if none within READ_POLL); raises ConnectionError at EOF."""
        ...

    def write(self, data: bytes) -> None: ...
    def close(self) -> None: ...


class TcpLink:
    """TCP to ``host:port`` (Nagle off: every line leaves at once)."""

    def __init__(self, host: str, port: int, connect_timeout: float = 2.0) -> None:
        self.host, self.port, self.connect_timeout = host, port, connect_timeout
        self._sock: socket.socket | None = None

    def open(self) -> None:
        try:
            sock = socket.create_connection((self.host, self.port), self.connect_timeout)
        except OSError as error:
            raise ConnectionError(f"cannot reach {self.host}:{self.port}: {error}") from None
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        sock.settimeout(READ_POLL)
        self._sock = sock

    def read(self) -> bytes:
        assert self._sock is not None
        try:
            data = self._sock.recv(4096)
        except TimeoutError:
            return b""
        except OSError as error:
            raise ConnectionError(str(error)) from None
        if not data:
            raise ConnectionError("connection closed by the robot")
        return data

    def write(self, data: bytes) -> None:
        if self._sock is None:
            raise ConnectionError("not connected")
        try:
            self._sock.sendall(data)
        except OSError as error:
            raise ConnectionError(str(error)) from None

    def close(self) -> None:
        if self._sock is not None:
            self._sock.close()
            self._sock = None


class SerialLink:
    """A serial port or any pyserial URL (``/dev/ttyUSB0``, ``loop://``, ``socket://…``)."""

    def __init__(self, url: str, baudrate: int = 115200) -> None:
        self.url, self.baudrate = url, baudrate
        self._port: serial.SerialBase | None = None

    def open(self) -> None:
        try:
            self._port = serial.serial_for_url(self.url, baudrate=self.baudrate, timeout=READ_POLL)
        except (serial.SerialException, ValueError) as error:
            raise ConnectionError(f"cannot open {self.url}: {error}") from None

    def read(self) -> bytes:
        assert self._port is not None
        try:
            waiting = max(1, self._port.in_waiting)
            return bytes(self._port.read(waiting))
        except (serial.SerialException, OSError) as error:
            raise ConnectionError(str(error)) from None

    def write(self, data: bytes) -> None:
        if self._port is None:
            raise ConnectionError("not connected")
        try:
            self._port.write(data)
        except (serial.SerialException, OSError) as error:
            raise ConnectionError(str(error)) from None

    def close(self) -> None:
        if self._port is not None:
            self._port.close()
            self._port = None


class LineClient:
    """A :class:`~skidnav.realtime.driver.RobotDriver` over a :class:`Link`.

    Args:
        link: the byte stream.
        handshake_timeout: wait for the robot's ``hello`` [s].
        stop_timeout: wait for ``stopped`` [s]; the stop is sent again once halfway.
        heartbeat_interval: idle time before a ``heartbeat`` is sent [s].
    """

    def __init__(
        self,
        link: Link,
        *,
        handshake_timeout: float = 2.0,
        stop_timeout: float = 0.1,
        heartbeat_interval: float = 0.05,
    ) -> None:
        self.link = link
        self.handshake_timeout = handshake_timeout
        self.stop_timeout = stop_timeout
        self.heartbeat_interval = heartbeat_interval
        self.robot_period: float | None = None
        self.fault: str | None = None
        self.on_fault: Callable[[str], None] | None = None
        self.on_pose: Callable[[Pose, float], None] | None = None
        self._pose: Pose | None = None
        self._measurement: tuple[Pose, float] | None = None
        self._seq = 0
        self._last_tx = 0.0
        self._write_lock = threading.Lock()
        self._reply = threading.Condition()
        self._hello = threading.Event()
        self._stopped_acks: set[int] = set()
        self._running = threading.Event()
        self._thread: threading.Thread | None = None

    # --- RobotDriver ---------------------------------------------------------------------
    def connect(self) -> None:
        """Open the link, start the reader and shake hands; raises ConnectionError."""
        self.close()
        self.fault = None
        self._pose = None
        self._measurement = None
        self._hello.clear()
        self.link.open()
        self._running.set()
        self._thread = threading.Thread(target=self._read_loop, name="line-client", daemon=True)
        self._thread.start()
        self._send(lambda seq: pr.Hello(seq=seq, name="skidnav"))
        if not self._hello.wait(self.handshake_timeout):
            reason = self.fault or "no hello from the robot"
            self.close()
            raise ConnectionError(reason)

    def command(self, omega_left: float, omega_right: float) -> None:
        """Send wheel speeds [rad/s]; a link error becomes a fault, not an exception."""
        self._send(lambda seq: pr.Command(seq=seq, omega_left=omega_left, omega_right=omega_right))

    def latest_pose(self) -> Pose | None:
        """The newest pose, stamped on this process's monotonic clock at receipt."""
        return self._pose

    def latest_measurement(self) -> tuple[Pose, float] | None:
        """The newest pose with the robot's own stamp [s robot clock], or None."""
        return self._measurement

    def stop(self) -> bool:
        """Send ``stop`` (again once halfway through the wait); True once ``stopped`` came."""
        deadline = time.monotonic() + self.stop_timeout
        for attempt in range(2):
            seq = self._send(lambda seq: pr.Stop(seq=seq))
            if seq is None:
                return False
            wait_until = deadline if attempt else time.monotonic() + self.stop_timeout / 2
            with self._reply:
                while seq not in self._stopped_acks:
                    remaining = wait_until - time.monotonic()
                    if remaining <= 0 or not self._running.is_set():
                        break
                    self._reply.wait(remaining)
                if seq in self._stopped_acks:
                    return True
        return False

    def close(self) -> None:
        """Stop the wheels (best effort), end the reader and close the link."""
        if self._thread is None:
            return
        if self._running.is_set():
            self.stop()
        self._running.clear()
        self._thread.join(timeout=1.0)
        self._thread = None
        self.link.close()

    # --- internals -----------------------------------------------------------------------
    def _send(self, build: Callable[[int], pr.Message]) -> int | None:
        """Encode and write one message; returns its seq, or None if the link failed."""
        with self._write_lock:
            seq = self._seq
            self._seq += 1
            try:
                self.link.write(pr.encode(build(seq)))
            except ConnectionError as error:
                self._report(f"link lost: {error}")
                return None
            self._last_tx = time.monotonic()
            return seq

    def _report(self, fault: str) -> None:
        if self.fault is None:
            self.fault = fault
            log.warning("robot link fault: %s", fault)
            if self.on_fault is not None:
                self.on_fault(fault)

    def _read_loop(self) -> None:
        buffer = pr.LineBuffer()
        while self._running.is_set():
            try:
                data = self.link.read()
            except ConnectionError as error:
                self._report(f"link lost: {error}")
                break
            if data:
                buffer.feed(data)
                self._drain(buffer)
            if time.monotonic() - self._last_tx > self.heartbeat_interval:
                self._send(lambda seq: pr.Heartbeat(seq=seq, stamp=time.monotonic()))
        self._running.clear()
        with self._reply:
            self._reply.notify_all()

    def _drain(self, buffer: pr.LineBuffer) -> None:
        while True:
            try:
                for line in buffer.lines():
                    self._handle(pr.decode(line))
                return
            except pr.ProtocolError as error:
                self._report(f"malformed message ({error.code}): {error}")

    def _handle(self, message: pr.Message) -> None:
        if isinstance(message, pr.PoseReport):
            pose = Pose(time.monotonic(), message.x, message.y, message.heading)
            self._measurement = (pose, message.stamp)
            self._pose = pose
            if self.on_pose is not None:
                self.on_pose(pose, message.stamp)
        elif isinstance(message, pr.Stopped):
            with self._reply:
                self._stopped_acks.add(message.ack)
                self._reply.notify_all()
        elif isinstance(message, pr.Hello):
            self.robot_period = message.period
            self._hello.set()
        elif isinstance(message, pr.Error):
            self._report(f"robot error ({message.code}): {message.message}")
