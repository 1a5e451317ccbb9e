"""The reference robot's main loop: one thread, polling, never blocking on the host.

Each pass of :func:`run`:

1. let the transport accept whoever connected: the first host starts a new
   :class:`~.core.ProtocolCore` session, the others are told ``busy``;
2. read everything that arrived (at most :data:`READ_LIMIT` bytes) and feed it to the core as
   one batch; apply the wheel speeds it returns;
3. once per control period: the core's own safety (lease, link timeout, idle host) right before
   the pose is read, then the ``pose`` report;
4. write what the transport takes now; a host that lets :data:`SEND_LIMIT` bytes queue up is
   dropped rather than waited for;
5. wait for input until the next period is due.

A host that goes away, fails authentication or stays idle is dropped, and the wheels stop.
"""

import os

from .core import ProtocolCore

TYPE_CHECKING = False  # MicroPython has no typing module: its names are for the type checker
if TYPE_CHECKING:
    from collections.abc import Callable
    from typing import Any

    from .interfaces import Robot, Transport

READ_LIMIT = 32 * 1024
"""Most bytes read per pass [bytes]; the rest waits for the next pass."""
SEND_LIMIT = 64 * 1024
"""Bytes queued for a host that does not read before it is dropped [bytes]."""


class MainLoop:
    """The state of :func:`run` (same arguments); :meth:`cycle` is one pass."""

    def __init__(
        self,
        transport: "Transport",
        robot: "Robot",
        clock: "Callable[[], float]",
        period: float = 0.1,
        name: str = "skidnav-reference",
        secret: bytes | None = None,
        max_lease: float = 0.5,
        link_timeout: float = 0.5,
        idle_timeout: float = 2.0,
        random_bytes: "Callable[[int], bytes]" = os.urandom,
        on_event: "Callable[[str, dict[str, Any]], None] | None" = None,
    ) -> None:
        if not period > 0:
            raise ValueError("expected a period > 0 s, got " + repr(period))
        self.transport, self.robot, self.clock, self.period = transport, robot, clock, period
        self.options = (name, period, robot.wheel_limit)
        self.timeouts = {"max_lease": max_lease, "link_timeout": link_timeout}
        self.timeouts["idle_timeout"] = idle_timeout
        self.secret, self.random_bytes, self.on_event = secret, random_bytes, on_event
        self.core: ProtocolCore | None = None
        self.sent = 0  # the next seq on a serial line, which outlives its sessions
        self.outbox = b""
        self.next_tick = clock()

    def _event(self, event: str, fields: "dict[str, Any]") -> None:
        if self.on_event is not None:
            self.on_event(event, fields)

    def _attach(self, now: float) -> None:
        name, period, limit = self.options
        self.core = ProtocolCore(
            name, period, limit, now, self.secret,
            restart_on_hello=self.transport.connectionless,
            random_bytes=self.random_bytes, on_note=self.on_event, **self.timeouts,
        )  # fmt: skip
        if self.transport.connectionless:
            self.core.seq = self.sent
        self.outbox = b""
        self._event("connect", {})

    def _drop(self, reason: str) -> None:
        """Forget the host and stop the wheels."""
        self.robot.stop()
        if self.core is not None:
            self.sent = self.core.seq
        self.core, self.outbox = None, b""
        self.transport.hang_up()
        self._event("disconnect", {"reason": reason})

    def _wheels(self, wheels: "tuple[float, float] | None") -> None:
        if wheels is None:
            return
        if wheels == (0.0, 0.0):
            self.robot.stop()
        else:
            self.robot.set_wheels(wheels[0], wheels[1])

    def _answer(self, out: bytes, wheels: "tuple[float, float] | None") -> None:
        """Apply what the core returned; drop the host if it asked to."""
        self._wheels(wheels)
        self.outbox += out
        if self.core is not None and self.core.hang_up is not None:
            reason = self.core.hang_up
            self._flush()  # the last error goes out before the hang-up, if it fits
            if self.core is not None:
                self._drop(reason)

    def _receive(self, now: float) -> None:
        """Read what arrived and answer it as one batch."""
        data, gone = b"", False
        while len(data) < READ_LIMIT:
            chunk = self.transport.read()
            if chunk is None:
                gone = True
                break
            if not chunk:
                break
            data += chunk
        if data and self.core is not None:
            self._answer(*self.core.feed(data, now))
        if gone and self.core is not None:
            self._drop("the host went away")

    def _tick(self, now: float) -> None:
        """One control period: the core's safety, then the pose report."""
        if self.core is not None:
            self._answer(*self.core.watch(now))
        pose = self.robot.pose(now)
        if self.core is not None and pose is not None:
            self.outbox += self.core.pose(now, pose[0], pose[1], pose[2])

    def _flush(self) -> None:
        """Write what the transport takes; drop a host that does not read."""
        try:
            while self.outbox:
                written = self.transport.write(self.outbox)
                if not written:
                    break
                self.outbox = self.outbox[written:]
        except OSError as error:
            self._drop("write failed: " + str(error))
            return
        if len(self.outbox) > SEND_LIMIT:
            self._drop("host not reading (" + str(len(self.outbox)) + " bytes queued)")

    def cycle(self) -> None:
        """One pass of the loop (see module doc)."""
        now = self.clock()
        attached = self.transport.attach()  # every pass: others waiting are told busy
        if self.core is None and attached:
            self._attach(now)
        if self.core is not None:
            self._receive(now)
        if now >= self.next_tick:
            self._tick(now)
            self.next_tick += self.period
            if self.next_tick < now - self.period:
                self.next_tick = now  # fell behind: no burst of catch-up periods
        if self.core is not None:
            self._flush()
        self.transport.wait(max(0.0, min(self.next_tick - self.clock(), self.period)))


def run(
    transport: "Transport",
    robot: "Robot",
    clock: "Callable[[], float]",
    running: "Callable[[], bool] | None" = None,
    **options: "Any",
) -> None:
    """Serve hosts on ``transport`` with ``robot`` until ``running()`` turns False (forever
    without it); ``clock()`` is the robot's running clock [s] (:func:`~.clock.running_clock`).

    Options (keywords of :class:`MainLoop`): ``period`` [s] (the control period, 0.1),
    ``name``, ``secret`` (bytes, at least 16: authenticate every line; None: no
    authentication), ``max_lease``, ``link_timeout``, ``idle_timeout`` [s] (0.5, 0.5, 2.0),
    ``random_bytes`` (the nonce source, ``os.urandom``), ``on_event(event, fields)`` (called on
    connects, drops and every note of the rules). The wheels stop when it returns.
    """
    loop = MainLoop(transport, robot, clock, **options)
    try:
        while running is None or running():
            loop.cycle()
    finally:
        robot.stop()
        if loop.core is not None:
            transport.hang_up()
