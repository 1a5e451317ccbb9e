"""The simulated robot server: a :class:`~skidnav.realtime.robot_server.simulated_robot.SimRobot`
behind the line protocol (docs/protocol.md), for hardware-in-the-loop runs of the real-time
platform.

Every control period (``robot.dt`` of robot time, ``robot.dt / time_scale`` of wall time) the
server advances the physics and sends one ``pose`` (unless dropped). It serves one client at a
time over TCP (bound to 127.0.0.1 by default) or over any byte channel (a pty, a serial line);
other TCP clients get ``error busy``. All I/O is non-blocking on one selector, so no peer can
stall the physics: what a client does not read queues up to ``send_limit`` bytes, then the
client is dropped; a read takes what has arrived, at most ``READ_LIMIT`` bytes per wake-up.

What the robot answers, and when it stops on its own, is the
:class:`~skidnav.realtime.robot_server.simulated_robot.Firmware` of the connection
(docs/protocol.md, "What a robot must do"); the server adds the transport: it reads everything that
arrived before handing it over as one batch (so a stalled robot applies only the newest command),
stops the wheels when the client disconnects, and drops a client the firmware declares idle, so a
dead controller never locks the robot. With a secret (``options.secret``) it authenticates every
line after the client's ``hello`` and every line it sends (:mod:`~skidnav.realtime.link.auth`), and
hangs up on a client that fails; without one,
:func:`~skidnav.realtime.robot_server.transport.bind_listener` serves loopback only.

Every received command, stop, fault, wheel change, late period and connection is appended to a
JSON-lines log with the system-wide monotonic clock (``mono`` [s]), so tests can measure when a
stop arrived and which command the wheels ran.

Fault injection for tests: with ``faults`` set, each SIGUSR1 (or :meth:`SimServer.inject`)
triggers the next one of them (cycling) at the next period: ``silence`` (no more poses),
``garbage`` (one line of junk bytes), ``oversized`` (one line over the length cap), ``escape``
(poses reported outside the arena from then on), ``hangup`` (the client is disconnected),
``future`` (poses stamped :data:`FUTURE_STAMP` from then on); ``silence``, ``escape`` and
``future`` last until the next client connects.
"""

from __future__ import annotations

import contextlib
import logging
import os
import selectors
import socket
import threading
import time
from collections.abc import Callable

from skidnav.realtime.config import ServerOptions
from skidnav.realtime.control.records import EventLog
from skidnav.realtime.link import protocol as pr
from skidnav.realtime.link.auth import Session
from skidnav.realtime.robot_server.simulated_robot import Firmware, SimRobot
from skidnav.realtime.robot_server.transport import Channel, FdChannel, refuse_busy

log = logging.getLogger(__name__)

READ_LIMIT = 32 * 1024
"""Most bytes read from the client per wake-up [bytes]; the rest waits for the next one."""
LATE_LOG = 0.05
"""A period that starts this much late [s wall] is logged as ``late`` (the server stalled)."""
FUTURE_STAMP = 1e308
"""The stamp of the poses of the ``future`` fault [s robot clock]."""
LASTING_FAULTS = ("silence", "escape", "future")
"""The faults that last until the next client connects."""


class SimServer:
    """Serves one :class:`SimRobot` (see module doc).

    Args:
        robot: the simulated robot (its period is ``robot.robot.dt``).
        options: timing and behaviour.
        events: the command log.
        watch_fd: a descriptor whose end of stream ends the server (the read end of a pipe
            held by the parent process, so the server never outlives it), or None.
    """

    def __init__(
        self, robot: SimRobot, options: ServerOptions, events: EventLog, watch_fd: int | None = None
    ) -> None:
        self.robot = robot
        self.options = options
        self.events = events
        self.watch_fd = watch_fd
        self.period_wall = robot.robot.dt / options.time_scale
        self.shutdown = threading.Event()
        self.firmware: Firmware | None = None
        self._seq = 0
        self._channel: Channel | None = None
        self._session: Session | None = None
        self._selector: selectors.BaseSelector | None = None
        self._buffer = pr.LineBuffer()
        self._outbox = bytearray()
        self._logged_wheels = (0.0, 0.0)
        self._fault_requests = 0  # inject() counts up, the period catches up: no lock taken
        self._fault_requests_seen = 0
        self._shutdown_requested = False  # request_shutdown(), from a signal handler
        self._active_faults: set[str] = set()
        self._faults_injected = 0
        self._single = False  # serve_channel: the server ends with its one client

    def inject(self) -> None:
        """Trigger the configured fault at the next period. Safe from a signal handler: it only
        counts (setting a :class:`threading.Event` takes its condition's lock, which the
        interrupted thread may hold at that instant, and the handler would wait for it
        forever)."""
        self._fault_requests += 1

    def request_shutdown(self) -> None:
        """End the serving loop at its next cycle; safe from a signal handler (an assignment,
        as :meth:`inject`). Other threads may set :attr:`shutdown` instead."""
        self._shutdown_requested = True

    @property
    def connected(self) -> bool:
        """True while a client is attached."""
        return self._channel is not None

    # --- sending -------------------------------------------------------------------------
    def _send(self, build: Callable[[int], pr.Message]) -> None:
        if self._channel is None:
            return
        message = build(self._seq)
        self._seq += 1
        line = pr.encode(message)
        if self._session is not None and self._session.keyed:
            line = self._session.seal(line)
        self._send_raw(line)

    def _send_raw(self, data: bytes) -> None:
        """Queue ``data`` for the client; a client that lets the queue overflow is dropped."""
        if self._channel is None:
            return
        self._outbox += data
        if len(self._outbox) > self.options.send_limit:
            self._drop(f"client not reading ({len(self._outbox)} bytes queued)")
            return
        self._flush()

    def _flush(self) -> None:
        """Write what the client's socket takes now; wait for writability for the rest."""
        channel = self._channel
        while channel is not None and self._outbox:
            try:
                written = channel.write(bytes(self._outbox))
            except OSError as error:
                self._drop(f"write failed: {error}")
                return
            if written == 0:
                break
            del self._outbox[:written]
        if channel is not None and self._selector is not None:
            events = selectors.EVENT_READ | (selectors.EVENT_WRITE if self._outbox else 0)
            if self._selector.get_key(channel.fileno()).events != events:
                self._selector.modify(channel.fileno(), events, "client")

    # --- connection ----------------------------------------------------------------------
    def attach(self, channel: Channel) -> None:
        """Make ``channel`` the current client."""
        self._channel = channel
        self._buffer = pr.LineBuffer()
        self._outbox = bytearray()
        secret = self.options.secret
        self._session = Session(secret, "robot") if secret is not None else None
        nonce = self._session.hello_nonce if self._session is not None else ""
        self.firmware = Firmware(
            self.robot, self.options, self.events, self._send, time.monotonic(), nonce
        )
        self._active_faults.difference_update(LASTING_FAULTS)
        if self._selector is not None:
            self._selector.register(channel.fileno(), selectors.EVENT_READ, "client")
        self.events.write("connect")

    def _drop(self, reason: str) -> None:
        """Forget the client and stop the wheels."""
        channel, self._channel = self._channel, None
        if self.firmware is not None:
            self.firmware.closed = True  # a batch being answered stops here
        self.robot.stop()
        self.firmware = None
        self._outbox = bytearray()
        self.events.write("disconnect", reason=reason)
        log.info("client dropped: %s", reason)
        if self._single:
            self.shutdown.set()
        if channel is not None:
            if self._selector is not None:
                with contextlib.suppress(KeyError, ValueError):
                    self._selector.unregister(channel.fileno())
            with contextlib.suppress(OSError):
                channel.close()

    # --- receiving -----------------------------------------------------------------------
    def receive(self) -> None:
        """Read everything that arrived (at most :data:`READ_LIMIT` bytes) and hand its
        complete lines to the firmware as one batch."""
        now = time.monotonic()
        ended = self._read_available()
        items = self._complete_lines()
        if self.firmware is not None and items:
            self.firmware.receive(items, now)
        self._hang_up_if_asked()
        if ended is not None and self._channel is not None:
            self._drop(ended)

    def _hang_up_if_asked(self) -> None:
        """Drop the client the firmware refused to hear more from (failed authentication)."""
        if self.firmware is not None and self.firmware.hang_up is not None:
            self._drop(self.firmware.hang_up)

    def _read_available(self) -> str | None:
        """Feed what arrived to the line buffer; the reason if the stream ended."""
        received = 0
        while self._channel is not None and received < READ_LIMIT:
            try:
                data = self._channel.read()
            except BlockingIOError:
                return None
            except OSError as error:  # a reset connection, a closed pty
                return f"read failed: {error}"
            if not data:
                return "end of stream"
            received += len(data)
            self._buffer.feed(data)
        return None

    def _complete_lines(self) -> list[pr.Message | pr.ProtocolError]:
        """The complete lines received, each decoded: a message, or the error of a bad line."""
        items: list[pr.Message | pr.ProtocolError] = []
        while True:
            try:
                for line in self._buffer.lines():
                    try:
                        items.append(self._decode_line(line))
                    except pr.ProtocolError as error:
                        items.append(error)
                return items
            except pr.ProtocolError as error:  # an oversized line; the buffer resynchronizes
                items.append(error)

    def _decode_line(self, line: bytes) -> pr.Message:
        """One line decoded; with a secret, its MAC checked once the client's ``hello`` gave
        its nonce (a ``hello`` without one fails: ProtocolError ``auth``)."""
        session = self._session
        if session is not None and session.keyed:
            session.verify(line)
        message = pr.decode(line)
        if session is not None and not session.keyed and isinstance(message, pr.Hello):
            session.greet(message.nonce)
        return message

    # --- the period ----------------------------------------------------------------------
    def _apply_requested_fault(self) -> None:
        """Inject the configured fault if :meth:`inject` was called since the last one."""
        if self._fault_requests != self._fault_requests_seen:
            self._apply_fault()

    def _apply_fault(self) -> None:
        self._fault_requests_seen = self._fault_requests
        if not self.options.faults:
            return
        fault = self.options.faults[self._faults_injected % len(self.options.faults)]
        self._faults_injected += 1
        self.events.write("fault", fault=fault, robot_time=self.robot.time)
        log.info("injecting fault %s", fault)
        if fault in LASTING_FAULTS:
            self._active_faults.add(fault)
        elif fault == "garbage":
            self._send_raw(b"\x00\xff\xfe not json {{{\n")
        elif fault == "oversized":
            self._send_raw(b"{" + b"x" * (2 * pr.MAX_LINE_BYTES) + b"}\n")
        elif fault == "hangup" and self._channel is not None:
            self._drop("fault hangup")

    def tick(self, late: float = 0.0) -> None:
        """One control period, starting ``late`` wall seconds after it was due: faults, the
        firmware's own safety, physics, pose report. A change of the wheel speeds the physics
        ran, and a period more than :data:`LATE_LOG` late (the server stalled), are logged
        with the pose before and after."""
        self._apply_requested_fault()
        if self.firmware is not None:
            idle = self.firmware.watch(time.monotonic())
            if idle is not None:
                self._drop(idle)
        before, start = self.robot.pose, self.robot.time
        self.robot.step()
        ran = self.robot.wheels
        if ran != self._logged_wheels or late > max(LATE_LOG, 2 * self.period_wall):
            event = "wheels" if ran != self._logged_wheels else "late"
            self._logged_wheels = ran
            self.events.write(
                event, wheels=ran, late=late, robot_time=start, pose=before, after=self.robot.pose
            )
        greeted = self.firmware is not None and self.firmware.greeted
        if not greeted or "silence" in self._active_faults:
            return
        measured = self.robot.measured_pose()
        if measured is None:
            return
        x, y, heading = measured
        if "escape" in self._active_faults:
            x = -0.3
        stamp = FUTURE_STAMP if "future" in self._active_faults else self.robot.time
        self._send(lambda seq: pr.PoseReport(seq=seq, stamp=stamp, x=x, y=y, heading=heading))

    # --- main loops ----------------------------------------------------------------------
    def _loop(self, selector: selectors.BaseSelector, listener: socket.socket | None) -> None:
        """Tick at the wall-clock period, handling ready descriptors in between."""
        self._selector = selector
        if self.watch_fd is not None:
            selector.register(self.watch_fd, selectors.EVENT_READ, "watch")
        next_tick = time.monotonic()
        try:
            while not (self.shutdown.is_set() or self._shutdown_requested):
                next_tick = self._cycle(selector, listener, next_tick)
        finally:
            if self.connected:
                self._drop("server shutdown")
            self._selector = None

    def _cycle(
        self, selector: selectors.BaseSelector, listener: socket.socket | None, next_tick: float
    ) -> float:
        """Handle what is ready until the period due at ``next_tick`` (monotonic [s]), run it
        if due; returns when the next one is due."""
        ready = selector.select(max(0.0, next_tick - time.monotonic()))
        self._handle_ready(ready, listener)
        now = time.monotonic()
        if now >= next_tick:
            self.tick(late=now - next_tick)
            next_tick += self.period_wall
            if next_tick < now - self.period_wall:
                next_tick = now  # fell behind (machine busy): no burst of catch-up ticks
        return next_tick

    def _handle_ready(
        self, ready: list[tuple[selectors.SelectorKey, int]], listener: socket.socket | None
    ) -> None:
        """Serve the ready descriptors, the client first: a hangup frees the slot."""
        for key, mask in sorted(ready, key=lambda pair: pair[0].data != "client"):
            self._dispatch(key.data, mask, listener)

    def _dispatch(self, kind: str, mask: int, listener: socket.socket | None) -> None:
        if kind == "listener" and listener is not None:
            self._accept(listener)
        elif kind == "watch":
            self._check_watch()
        elif kind == "client" and self.connected:
            if mask & selectors.EVENT_READ:
                self.receive()
            if self.connected and mask & selectors.EVENT_WRITE:
                self._flush()

    def _check_watch(self) -> None:
        """The watched descriptor is readable: at its end of stream, shut down."""
        assert self.watch_fd is not None
        try:
            data = os.read(self.watch_fd, 4096)
        except BlockingIOError:
            return
        except OSError:
            data = b""
        if not data:
            self.events.write("parent_gone")
            log.info("the parent process is gone; shutting down")
            self.shutdown.set()

    def serve_channel(self, channel: Channel) -> None:
        """Serve one already-connected channel until it closes or :attr:`shutdown` is set."""
        with selectors.DefaultSelector() as selector:
            self._selector = selector
            self._single = True
            self.attach(channel)
            self._loop(selector, None)

    def serve_tcp(self, listener: socket.socket) -> None:
        """Accept clients on ``listener`` (one at a time; others get ``error busy``) until
        :attr:`shutdown` is set."""
        listener.setblocking(False)
        with selectors.DefaultSelector() as selector:
            selector.register(listener.fileno(), selectors.EVENT_READ, "listener")
            self._loop(selector, listener)

    def _accept(self, listener: socket.socket) -> None:
        """Accept every pending connection: the first becomes the client if none is attached,
        the others are told ``busy`` and closed — without ever blocking."""
        while True:
            try:
                sock, _ = listener.accept()
            except BlockingIOError:
                return
            except OSError as error:  # aborted before accept, out of descriptors
                log.warning("accept failed: %s", error)
                return
            if self.connected:
                refuse_busy(sock)
                continue
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)  # a line leaves at once
            # the kernel's queue is bounded too: a client that does not read is found out soon
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, self.options.send_limit)
            self.attach(FdChannel(sock.detach()))
