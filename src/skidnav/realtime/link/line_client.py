"""Robot drivers speaking the line protocol (docs/protocol.md) over TCP or a serial line.

:class:`LineClient` implements :class:`~skidnav.realtime.link.interface.RobotDriver` over any
:class:`Link` (a byte stream). A reader thread parses incoming lines, keeps the newest pose
(stamped on this process's monotonic clock at receipt), collects ``ack``/``stopped`` replies and
sends a ``heartbeat`` whenever nothing was sent for ``heartbeat_interval`` seconds once the
robot's ``hello`` arrived. A lost link, a malformed line, a robot message whose ``seq`` does not
increase, an ``error`` from the robot, a pose stamped from the future
(:class:`~skidnav.realtime.link.robot_clock.RobotClock`) and, with a secret, a line that fails
authentication (docs/protocol.md, "Authentication") are *faults*: each is kept in :attr:`fault`
and passed at once to the fault callback (the safety monitor's trip). A fault during
:meth:`LineClient.connect` is what its ConnectionError says, so only a fault of a connected
link is logged as a warning.
"""

from __future__ import annotations

import logging
import math
import socket
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

from skidnav.extras import require
from skidnav.realtime.link import protocol as pr
from skidnav.realtime.link.auth import Session, require_secret
from skidnav.realtime.link.interface import Pose
from skidnav.realtime.link.robot_clock import RobotClock

if TYPE_CHECKING:
    import serial

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
        require("serial", "the serial link")
        import serial  # pyserial: the serial extra, imported only by a serial link

        self._serial: Any = serial
        self.url, self.baudrate = url, baudrate
        self._port: serial.SerialBase | None = None

    def open(self) -> None:
        try:
            self._port = self._serial.serial_for_url(
                self.url, baudrate=self.baudrate, timeout=READ_POLL
            )
        except (self._serial.SerialException, ValueError) as error:
            raise ConnectionError(f"cannot open {self.url}: {error}") from None

    def read(self) -> bytes:
        assert self._port is not None
        try:
            waiting = max(1, self._port.in_waiting)
            return bytes(self._port.read(waiting))
        except (self._serial.SerialException, OSError) as error:
            raise ConnectionError(str(error)) from None

    def write(self, data: bytes) -> None:
        if self._port is None:
            raise ConnectionError("not connected")
        try:
            self._port.write(data)
        except (self._serial.SerialException, OSError) as error:
            raise ConnectionError(str(error)) from None

    def close(self) -> None:
        if self._port is not None:
            self._port.close()
            self._port = None


class LineClient:
    """A :class:`~skidnav.realtime.link.interface.RobotDriver` over a :class:`Link`.

    Args:
        link: the byte stream.
        handshake_timeout: wait for the robot's ``hello`` [s].
        stop_timeout: the stop is re-sent every ``stop_timeout / 2`` until confirmed [s].
        heartbeat_interval: idle time before a ``heartbeat`` is sent [s].
        command_ttl: validity of each ``cmd`` after it was sent [s] (the robot's lease).
        dead_timeout: a robot from which nothing at all arrived for this long is declared
            lost, and :meth:`stop` gives up [s].
        lockstep: the robot runs one control period per ``cmd`` and acknowledges it after
            that period's pose (docs/protocol.md, "Lockstep"); the loop then paces itself by
            :meth:`wait_answered` instead of the wall clock.
        secret: the link secret (at least 16 bytes): the robot must prove it knows it and
            every line is authenticated; None: no authentication (loopback robots only).
        time_scale: robot seconds per wall second (the run's; a real robot's is 1), for
            :attr:`robot_clock`, which refuses poses stamped from the future.
    """

    def __init__(
        self,
        link: Link,
        *,
        handshake_timeout: float = 2.0,
        stop_timeout: float = 0.1,
        heartbeat_interval: float = 0.05,
        command_ttl: float = 0.5,
        dead_timeout: float = 2.0,
        lockstep: bool = False,
        secret: bytes | None = None,
        time_scale: float = 1.0,
    ) -> None:
        if not (stop_timeout > 0 and command_ttl > 0 and dead_timeout > 0):
            raise ValueError("expected stop_timeout, command_ttl and dead_timeout > 0 s")
        self.secret = require_secret(secret) if secret is not None else None
        self.link = link
        self.handshake_timeout = handshake_timeout
        self.stop_timeout = stop_timeout
        self.heartbeat_interval = heartbeat_interval
        self.command_ttl = command_ttl
        self.dead_timeout = dead_timeout
        self.lockstep = lockstep
        # kept across reconnections: the robot's clock goes on
        self.robot_clock = RobotClock(time_scale, command_ttl, lockstep)
        self.robot_period: float | None = None
        self.fault: str | None = None
        self.on_fault: Callable[[str], None] | None = None
        self.on_pose: Callable[[Pose, float], None] | None = None
        self._pose: Pose | None = None
        self._measurement: tuple[Pose, float] | None = None
        self._seq = 0
        self._session: Session | None = None
        self._robot_seq: int | None = None  # the newest seq taken from the robot
        self._last_tx = 0.0
        self._last_rx = 0.0
        self._write_lock = threading.Lock()
        self._reply = threading.Condition()
        self._hello = threading.Event()
        self._stopped_up_to = -1  # the largest seq a ``stopped`` acknowledged
        self._acked_up_to = -1  # the largest seq an ``ack`` acknowledged
        self._last_command = -1  # seq of the newest ``cmd`` sent
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
        self._stopped_up_to = -1
        self._acked_up_to = self._last_command = -1
        self._session = Session(self.secret, "host") if self.secret is not None else None
        self._robot_seq = None
        nonce = self._session.hello_nonce if self._session is not None else ""
        self.link.open()
        self._last_rx = time.monotonic()
        self._running.set()
        self._thread = threading.Thread(target=self._read_loop, name="line-client", daemon=True)
        self._thread.start()
        self._send(lambda seq: pr.Hello(seq=seq, name="skidnav", nonce=nonce))
        deadline = time.monotonic() + self.handshake_timeout
        while not self._hello.wait(READ_POLL):  # an error reply (busy, version) ends the wait
            if self.fault is not None or time.monotonic() >= deadline:
                reason = self.fault or "no hello from the robot"
                self.close()
                raise ConnectionError(reason)

    def command(self, omega_left: float, omega_right: float) -> None:
        """Send wheel speeds [rad/s], valid for ``command_ttl`` from now; a link error becomes
        a fault, not an exception."""
        seq = self._send(
            lambda seq: pr.Command(
                seq=seq,
                omega_left=omega_left,
                omega_right=omega_right,
                stamp=time.monotonic(),
                ttl=self.command_ttl,
            )
        )
        if seq is not None:
            self._last_command = seq

    def wait_answered(self, timeout: float) -> bool:
        """Wait up to ``timeout`` [s] for the ``ack`` of the newest ``cmd`` (True), or False at
        the timeout or when the link ends. A lockstep robot sends it after the period's pose."""
        deadline = time.monotonic() + timeout
        with self._reply:
            while self._acked_up_to < self._last_command and self._running.is_set():
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    return False
                self._reply.wait(remaining)
            return self._acked_up_to >= self._last_command

    def latest_pose(self) -> Pose | None:
        """The newest pose, stamped on this process's monotonic clock at receipt."""
        return self._pose

    def latest_measurement(self) -> tuple[Pose, float] | None:
        """The newest pose with the robot's own stamp [s robot clock], or None."""
        return self._measurement

    def stop(self) -> bool:
        """Send ``stop`` and re-send it every ``stop_timeout / 2`` until a ``stopped`` answers
        one of them (True), or until the link is dead (False): the connection failed, or
        nothing at all arrived from the robot for ``dead_timeout``. A stalled robot that
        resumes reads them all and confirms."""
        return self._stop_until(math.inf)

    def close(self) -> None:
        """Stop the wheels (best effort, one ``stop_timeout``), end the reader, close the link."""
        if self._thread is None:
            return
        if self._running.is_set():
            self._stop_until(time.monotonic() + self.stop_timeout)
        self._running.clear()
        self._thread.join(timeout=1.0)
        self._thread = None
        self.link.close()

    def _stop_until(self, give_up: float) -> bool:
        """:meth:`stop`, giving up at ``give_up`` (monotonic [s]) at the latest."""
        first: int | None = None
        while True:
            seq = self._send(lambda seq: pr.Stop(seq=seq))
            if seq is None:
                return False
            first = seq if first is None else first
            wait_until = min(give_up, time.monotonic() + self.stop_timeout / 2)
            with self._reply:
                while self._stopped_up_to < first and self._running.is_set():
                    remaining = wait_until - time.monotonic()
                    if remaining <= 0:
                        break
                    self._reply.wait(remaining)
                if self._stopped_up_to >= first:  # a stopped for a later stop counts too
                    return True
            silent = time.monotonic() - self._last_rx > self.dead_timeout
            if silent or not self._running.is_set() or time.monotonic() >= give_up:
                return False

    # --- internals -----------------------------------------------------------------------
    def _send(self, build: Callable[[int], pr.Message]) -> int | None:
        """Encode and write one message; returns its seq, or None if the link failed."""
        with self._write_lock:
            seq = self._seq
            self._seq += 1
            line = pr.encode(build(seq))
            if self._session is not None and self._session.keyed:
                line = self._session.seal(line)
            try:
                self.link.write(line)
            except ConnectionError as error:
                self._report(f"link lost: {error}")
                return None
            self._last_tx = time.monotonic()
            return seq

    def _report(self, fault: str) -> None:
        if self.fault is None:
            self.fault = fault
            # before the robot's hello, connect() raises it: the caller's one line says it
            level = logging.WARNING if self._hello.is_set() else logging.DEBUG
            log.log(level, "robot link fault: %s", fault)
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
                self._last_rx = time.monotonic()
                buffer.feed(data)
                self._drain(buffer)
            quiet = time.monotonic() - self._last_tx > self.heartbeat_interval
            if quiet and self._hello.is_set():  # before: nothing to authenticate it with
                self._send(lambda seq: pr.Heartbeat(seq=seq, stamp=time.monotonic()))
        self._running.clear()
        with self._reply:
            self._reply.notify_all()

    def _drain(self, buffer: pr.LineBuffer) -> None:
        while True:
            try:
                for line in buffer.lines():
                    self._handle_line(line)
                return
            except pr.ProtocolError as error:  # an oversized line; the buffer resynchronizes
                self._report(f"malformed message ({error.code}): {error}")

    def _handle_line(self, line: bytes) -> None:
        """Decode and dispatch one line; nothing in it can end the reader."""
        try:
            message = self._accept(line)
        except pr.ProtocolError as error:
            kind = "robot not authenticated" if error.code == "auth" else "malformed message"
            self._report(f"{kind} ({error.code}): {error}")
            return
        try:
            self._handle(message)
        except Exception as error:  # a failing callback must not stop stops being confirmed
            log.exception("handling a %s message failed", message.TYPE)
            self._report(f"handling a {message.TYPE} message failed: {error}")

    def _accept(self, line: bytes) -> pr.Message:
        """One robot line decoded and checked: with a secret, its MAC (the ``hello``'s once its
        nonce is read; before it, only an unauthenticated ``error`` passes), then the seq rule.
        ProtocolError ``auth`` or ``replay`` otherwise."""
        session = self._session
        if session is not None and session.keyed:
            session.verify(line)
        message = pr.decode(line)
        if session is not None and not session.keyed:
            if isinstance(message, pr.Hello):
                session.greet(message.nonce)
                session.verify(line)
            elif not isinstance(message, pr.Error):
                raise pr.ProtocolError("auth", f"unauthenticated {message.TYPE} before hello")
        last = self._robot_seq
        if last is not None and message.seq <= last:
            raise pr.ProtocolError("replay", f"robot {message.TYPE} {message.seq} after {last}")
        self._robot_seq = message.seq
        return message

    def _handle(self, message: pr.Message) -> None:
        if isinstance(message, pr.PoseReport):
            received = time.monotonic()
            refused = self.robot_clock.refuse(message.stamp, received)
            if refused is not None:
                self._report(refused)
                return
            pose = Pose(received, message.x, message.y, message.heading)
            self._measurement = (pose, message.stamp)
            self._pose = pose
            if self.on_pose is not None:
                self.on_pose(pose, message.stamp)
        elif isinstance(message, pr.Stopped):
            with self._reply:
                self._stopped_up_to = max(self._stopped_up_to, message.ack)
                self._reply.notify_all()
        elif isinstance(message, pr.Ack):
            with self._reply:
                self._acked_up_to = max(self._acked_up_to, message.ack)
                self._reply.notify_all()
        elif isinstance(message, pr.Hello):
            self.robot_period = message.period
            self._hello.set()
        elif isinstance(message, pr.Error):
            self._report(f"robot error ({message.code}): {message.message}")
