"""The sim server in lockstep: the host's commands, not the wall clock, advance robot time.

Every ``cmd`` the robot runs (one it acknowledges) advances the robot by exactly one control
period, after which the server sends that period's ``pose`` (unless dropped) and only then the
``ack``: a host that has the ``ack`` of its newest ``cmd`` has everything that period produced.
Robot time stands still between commands, so a study runs as fast as the host and the physics
go, and the same commands give the same poses, however the lines were batched by the transport
(docs/protocol.md, "Lockstep").

What changes from :class:`~skidnav.realtime.robot_server.server.SimServer`:

- Batches: every ``cmd`` of a batch runs, one period each, in order — except those followed in
  the batch by a ``stop`` or a malformed line, which are dropped unapplied as in the stall rule
  (:func:`lockstep_segments`).
- Poses: right after the handshake the current pose is sent (never dropped, so the host has a
  first pose without commanding anything), and every ``heartbeat`` is answered with the newest
  pose sent again (same stamp and values, no random draw): while robot time stands still the
  robot is exactly there, and the host's pose watchdog measures whether the server answers.
- Unchanged, on the server's wall clock: command expiry, the lease and link timeouts (they stop
  the wheels of the next period), dropping idle or non-reading clients, faults (applied at the
  next wake-up, at most :data:`IDLE_WAKE` later).
"""

from __future__ import annotations

import selectors
import socket
import time
from collections.abc import Callable, Iterator

from skidnav.realtime.config import ServerOptions
from skidnav.realtime.control.records import EventLog
from skidnav.realtime.link import protocol as pr
from skidnav.realtime.robot_server.server import SimServer
from skidnav.realtime.robot_server.simulated_robot import SimRobot
from skidnav.realtime.robot_server.transport import Channel

IDLE_WAKE = 0.01
"""Longest the server sleeps without input [s wall]: its timeouts and faults are this punctual."""

Item = pr.Message | pr.ProtocolError
"""One decoded line, or the error of a bad one."""


def lockstep_segments(items: list[Item]) -> Iterator[list[Item]]:
    """Split one batch into the sub-batches a lockstep robot answers one after the other:
    each ends with a ``cmd`` that runs (one period follows it), the last one may end without.
    The ``cmd`` lines before the batch's last ``stop`` or malformed line all stay in the first
    sub-batch, where the firmware's own rule drops them.

    >>> cmd = pr.Command(seq=0, omega_left=1.0, omega_right=1.0, stamp=0.0, ttl=1.0)
    >>> beat = pr.Heartbeat(seq=1, stamp=0.0)
    >>> [len(s) for s in lockstep_segments([cmd, beat, cmd, pr.Stop(seq=2), cmd, cmd, beat])]
    [5, 1, 1]
    """
    halts = [i for i, item in enumerate(items) if isinstance(item, pr.Stop | pr.ProtocolError)]
    last_halt = halts[-1] if halts else -1
    segment: list[Item] = []
    for index, item in enumerate(items):
        segment.append(item)
        if isinstance(item, pr.Command) and index > last_halt:
            yield segment
            segment = []
    if segment:
        yield segment


class LockstepServer(SimServer):
    """A :class:`SimServer` whose robot moves one period per command (see module doc)."""

    def __init__(
        self, robot: SimRobot, options: ServerOptions, events: EventLog, watch_fd: int | None = None
    ) -> None:
        super().__init__(robot, options, events, watch_fd)
        self._deferred: list[Callable[[int], pr.Message]] | None = None
        self._last_pose: pr.PoseReport | None = None

    def _send(self, build: Callable[[int], pr.Message]) -> None:
        """Send, remembering the newest pose; while a command's period is pending its ``ack``
        waits until after the pose."""
        message = build(0)
        if isinstance(message, pr.PoseReport):
            self._last_pose = message
        if self._deferred is not None and isinstance(message, pr.Ack):
            self._deferred.append(build)
            return
        super()._send(build)

    def attach(self, channel: Channel) -> None:
        self._last_pose = None
        super().attach(channel)

    def receive(self) -> None:
        """Read what arrived and answer it sub-batch by sub-batch (see module doc)."""
        now = time.monotonic()
        ended = self._read_available()
        for segment in lockstep_segments(self._complete_lines()):
            if self.firmware is None or self.firmware.closed:
                break
            self._answer(segment, now)
        self._hang_up_if_asked()
        if ended is not None and self._channel is not None:
            self._drop(ended)

    def _answer(self, segment: list[Item], now: float) -> None:
        """One sub-batch: the firmware's replies, the period of a command it ran (pose, then
        its ``ack``), the first pose after a handshake, a repeated pose per heartbeat."""
        firmware = self.firmware
        assert firmware is not None
        greeted, applied = firmware.greeted, firmware.applied
        self._deferred = []
        ticked = False
        try:
            firmware.receive(segment, now)
            ticked = firmware.applied > applied and not firmware.closed
            if ticked:
                self.tick()
        finally:
            deferred, self._deferred = self._deferred, None
        for build in deferred:
            self._send(build)
        if self.firmware is not firmware or not firmware.greeted:
            return
        if not greeted and not ticked:
            self._report_pose()
        if any(isinstance(item, pr.Heartbeat) for item in segment):
            self._repeat_pose()

    def _silenced(self) -> bool:
        return "silence" in self._active_faults

    def _report_pose(self) -> None:
        """The current measured pose, never dropped (the first one of a connection)."""
        if self._silenced():
            return
        measured = self.robot.measured_pose(droppable=False)
        assert measured is not None
        x, y, heading = measured
        if "escape" in self._active_faults:
            x = -0.3
        stamp = self.robot.time
        self._send(lambda seq: pr.PoseReport(seq=seq, stamp=stamp, x=x, y=y, heading=heading))

    def _repeat_pose(self) -> None:
        """The newest pose sent, sent again (robot time has not moved since)."""
        last = self._last_pose
        if last is None or self._silenced():
            return
        x = -0.3 if "escape" in self._active_faults else last.x
        self._send(
            lambda seq: pr.PoseReport(
                seq=seq, stamp=last.stamp, x=x, y=last.y, heading=last.heading
            )
        )

    def _cycle(
        self, selector: selectors.BaseSelector, listener: socket.socket | None, next_tick: float
    ) -> float:
        """Serve what is ready (commands run their periods as they are read), then the faults
        and the firmware's wall-clock safety; no period runs on its own."""
        self._handle_ready(selector.select(IDLE_WAKE), listener)
        self._apply_requested_fault()
        if self.firmware is not None:
            idle = self.firmware.watch(time.monotonic())
            if idle is not None:
                self._drop(idle)
        return next_tick
