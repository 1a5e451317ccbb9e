"""The safety monitor: a watchdog thread that stops the wheels when anything goes wrong.

Trip conditions (docs/realtime.md, "Safety"): the pose goes stale (no new pose for ``pose_timeout``
wall seconds while armed), the link drops or a malformed message arrives (the driver's fault
callback), the robot leaves the arena (by more than ``arena_margin``), or SIGINT/SIGTERM (the loop's
signal handler asks, :meth:`SafetyMonitor.request_trip`). On a trip the watchdog, within one check
interval (at most a quarter control period), lets any command in flight finish, then calls the
driver's ``stop``, which re-sends it until the robot confirms or the link is declared dead (at
most :data:`STOP_WAIT`); from the trip on no further command passes
:meth:`SafetyMonitor.command` until :meth:`SafetyMonitor.reset`.

A signal handler asks with :meth:`SafetyMonitor.request_trip`, which only assigns an attribute;
the watchdog trips within one check interval. It must not call :meth:`trip`: setting a
:class:`threading.Event` takes its condition's lock, which the interrupted main thread may be
holding at that instant (entering or leaving ``Event.wait``, as the control loop does every
period), and the handler, run by that same thread, would wait for it forever. Other threads
(the driver's reader) call :meth:`trip`.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

from skidnav.realtime.link.interface import Pose, RobotDriver

log = logging.getLogger(__name__)

STOP_WAIT = 10.0
"""Longest wait for an emergency stop to end [s wall]; drivers bound their own retries below
it (the line client gives up when the robot has been silent for its ``dead_timeout``)."""


@dataclass(frozen=True)
class SafetyLimits:
    """What the watchdog checks, validated on construction.

    Attributes:
        pose_timeout: longest time without a new pose while armed [s wall].
        check_interval: watchdog polling period [s wall].
        arena_width, arena_height: arena extent [m].
        arena_margin: how far outside the arena a pose may lie (tracking noise) [m].
    """

    pose_timeout: float = 0.5
    check_interval: float = 0.025
    arena_width: float = 0.62
    arena_height: float = 0.505
    arena_margin: float = 0.03

    def __post_init__(self) -> None:
        for name in ("pose_timeout", "check_interval", "arena_width", "arena_height"):
            if not getattr(self, name) > 0:
                raise ValueError(f"expected {name} > 0, got {getattr(self, name)}")
        if not self.arena_margin >= 0:
            raise ValueError(f"expected arena_margin >= 0 m, got {self.arena_margin}")

    def outside(self, pose: Pose) -> bool:
        """True if ``pose`` lies outside the arena grown by the margin (or is not finite)."""
        m = self.arena_margin
        values = (pose.x, pose.y, pose.heading)
        if not all(math.isfinite(v) for v in values):
            return True
        return not (-m <= pose.x <= self.arena_width + m and -m <= pose.y <= self.arena_height + m)


class SafetyMonitor:
    """Watches a driver and stops it on a trip (see module doc).

    Args:
        driver: the robot. If it has an ``on_fault`` attribute, the monitor sets it to
            :meth:`trip` so link faults trip at once.
        limits: thresholds.
        record: ``record(event, fields)`` for the run log ("trip", "stopped").
    """

    def __init__(
        self,
        driver: RobotDriver,
        limits: SafetyLimits,
        record: Callable[[str, dict[str, object]], None] | None = None,
    ) -> None:
        self.driver = driver
        self.limits = limits
        self.record = record or (lambda event, fields: None)
        self.reason: str | None = None
        self.requested: str | None = None
        """A trip asked for by :meth:`request_trip`, not yet made by the watchdog."""
        self.tripped = threading.Event()
        self.stop_done = threading.Event()
        self.stop_confirmed = False
        self._armed_since: float | None = None
        self._command_lock = threading.Lock()
        self._running = threading.Event()
        self._thread: threading.Thread | None = None
        if hasattr(driver, "on_fault"):
            driver.on_fault = self.trip

    # --- control -------------------------------------------------------------------------
    def start(self) -> None:
        """Start the watchdog thread."""
        self._running.set()
        self._thread = threading.Thread(target=self._watch, name="safety-watchdog", daemon=True)
        self._thread.start()

    def close(self) -> None:
        """End the watchdog thread (without stopping the robot)."""
        self._running.clear()
        self.tripped.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        self._thread = None

    def arm(self) -> None:
        """Start checking pose freshness and arena bounds (the robot is meant to move)."""
        self._armed_since = time.monotonic()

    def disarm(self) -> None:
        """Stop checking pose freshness (the robot is parked and the wheels are at zero)."""
        self._armed_since = None

    def request_trip(self, reason: str) -> None:
        """Ask for an emergency stop from a signal handler: no lock is taken (see module doc);
        the watchdog trips with ``reason`` within one check interval, or, if the monitor is
        tripped already, at its first check after :meth:`reset`."""
        if self.requested is None:
            self.requested = reason

    def trip(self, reason: str) -> None:
        """Request an emergency stop now; the first reason is kept. Not from a signal handler
        (:meth:`request_trip`)."""
        if self.reason is None:
            self.reason = reason
        self.tripped.set()

    def reset(self) -> None:
        """Clear a trip once it has been handled (waits for the stop to finish)."""
        self.stop_done.wait(timeout=STOP_WAIT)
        if self._armed_since is not None:  # a fresh link: pose age counts from now
            self._armed_since = time.monotonic()
        self.reason = None
        self.stop_confirmed = False
        self.stop_done.clear()
        self.tripped.clear()

    def command(self, omega_left: float, omega_right: float) -> bool:
        """Forward a wheel command unless tripped; False if refused."""
        with self._command_lock:
            if self.tripped.is_set():
                return False
            self.driver.command(omega_left, omega_right)
            return True

    # --- the watchdog --------------------------------------------------------------------
    def check(self) -> str | None:
        """The reason to trip now from the pose, or None."""
        armed = self._armed_since
        pose = self.driver.latest_pose()
        if armed is None:
            return None
        if pose is not None and self.limits.outside(pose):
            return f"robot outside the arena at ({pose.x:.3f}, {pose.y:.3f}) m"
        newest = armed if pose is None else max(armed, pose.stamp)
        age = time.monotonic() - newest
        if age > self.limits.pose_timeout:
            return f"pose stale for {age:.3f} s"
        return None

    def _watch(self) -> None:
        while self._running.is_set():
            if not self.tripped.wait(self.limits.check_interval):
                reason = self.requested
                if reason is not None:  # None is never written over a request not yet read
                    self.requested = None
                else:
                    reason = self.check()
                if reason is not None:
                    self.trip(reason)
                continue
            if not self._running.is_set():
                return
            if not self.stop_done.is_set():
                self._emergency_stop()
            time.sleep(self.limits.check_interval)

    def _emergency_stop(self) -> None:
        tripped_at = time.monotonic()
        self.record("trip", {"reason": self.reason, "mono": tripped_at})
        log.warning("safety trip: %s", self.reason)
        with self._command_lock:  # any command in flight leaves before the stop
            try:
                confirmed = self.driver.stop()
            except Exception as error:  # a failing driver must not kill the watchdog
                log.error("stop failed: %s", error)
                confirmed = False
        self.stop_confirmed = confirmed
        self.record(
            "stopped",
            {
                "confirmed": confirmed,
                "mono": time.monotonic(),
                "delay": time.monotonic() - tripped_at,
            },
        )
        self.stop_done.set()
