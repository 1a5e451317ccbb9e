"""The safety monitor against a scripted driver: every trip condition, the command gate."""

from __future__ import annotations

import threading
import time

import pytest

from skidnav.realtime.control.safety import SafetyLimits, SafetyMonitor
from skidnav.realtime.link.interface import Pose
from tests.realtime.realtime_helpers import wait_for


class ScriptedDriver:
    """A driver whose pose the test sets; records every command and stop with its time."""

    def __init__(self) -> None:
        self.pose: Pose | None = None
        self.commands: list[tuple[float, float, float]] = []
        self.stops: list[float] = []
        self.on_fault = None
        self.lock = threading.Lock()

    def connect(self) -> None: ...

    def command(self, omega_left: float, omega_right: float) -> None:
        with self.lock:
            self.commands.append((time.monotonic(), omega_left, omega_right))

    def latest_pose(self) -> Pose | None:
        return self.pose

    def stop(self) -> bool:
        self.stops.append(time.monotonic())
        return True

    def close(self) -> None: ...

    def feed(self, x: float = 0.3, y: float = 0.2) -> None:
        self.pose = Pose(time.monotonic(), x, y, 0.0)


LIMITS = SafetyLimits(pose_timeout=0.1, check_interval=0.005)


@pytest.fixture
def monitored() -> tuple[ScriptedDriver, SafetyMonitor, list[str]]:
    driver = ScriptedDriver()
    events: list[str] = []
    monitor = SafetyMonitor(driver, LIMITS, record=lambda event, fields: events.append(event))
    monitor.start()
    yield driver, monitor, events
    monitor.close()


def test_fresh_poses_inside_the_arena_never_trip(monitored) -> None:
    driver, monitor, _ = monitored
    monitor.arm()
    for _ in range(30):
        driver.feed()
        assert monitor.command(1.7, 1.7)
        time.sleep(0.01)
    assert not monitor.tripped.is_set() and driver.stops == []


def test_stale_pose_trips_and_stops_within_a_check_interval(monitored) -> None:
    driver, monitor, events = monitored
    monitor.arm()
    driver.feed()
    last = driver.pose.stamp
    wait_for(lambda: bool(driver.stops), 1.0, "the stop")
    assert "stale" in monitor.reason
    assert LIMITS.pose_timeout <= driver.stops[0] - last < LIMITS.pose_timeout + 0.05
    wait_for(monitor.stop_done.is_set, 1.0, "the stop record")
    assert events == ["trip", "stopped"] and monitor.stop_confirmed


def test_leaving_the_arena_trips(monitored) -> None:
    driver, monitor, _ = monitored
    monitor.arm()
    driver.feed(x=0.62 + 0.05)
    wait_for(lambda: bool(driver.stops), 1.0, "the stop")
    assert "outside the arena" in monitor.reason


def test_non_finite_pose_trips(monitored) -> None:
    driver, monitor, _ = monitored
    monitor.arm()
    driver.feed(x=float("nan"))
    wait_for(lambda: bool(driver.stops), 1.0, "the stop")


def test_driver_fault_callback_trips_and_gates_commands(monitored) -> None:
    driver, monitor, _ = monitored
    assert driver.on_fault == monitor.trip
    driver.on_fault("link lost: test")
    wait_for(lambda: bool(driver.stops), 1.0, "the stop")
    assert monitor.reason == "link lost: test"
    assert monitor.command(1.7, 1.7) is False
    assert all(stamp < driver.stops[0] for stamp, _, _ in driver.commands)
    monitor.reset()
    assert monitor.command(1.0, 1.0) is True and not monitor.tripped.is_set()


def test_disarmed_monitor_ignores_missing_poses(monitored) -> None:
    driver, monitor, _ = monitored
    time.sleep(0.2)
    assert driver.stops == []
    monitor.arm()
    wait_for(lambda: bool(driver.stops), 1.0, "the stop after arming without poses")


def test_first_trip_reason_is_kept(monitored) -> None:
    _, monitor, _ = monitored
    monitor.trip("signal SIGINT")
    monitor.trip("link lost")
    assert monitor.reason == "signal SIGINT"


def test_limits_validate() -> None:
    with pytest.raises(ValueError, match="pose_timeout"):
        SafetyLimits(pose_timeout=0)


@pytest.mark.timeout(30)
def test_a_signal_handlers_request_takes_no_lock(monitored) -> None:
    """A signal handler runs on the thread it interrupted, which may hold the lock of the
    monitor's Event at that instant (entering or leaving ``Event.wait``, as the control loop
    does every period): a request that took it would wait for itself forever. This one returns
    at once, and the watchdog trips as soon as the lock is free."""
    driver, monitor, _ = monitored
    with monitor.tripped._cond:  # the lock Event.wait holds
        monitor.request_trip("signal SIGINT")
        assert not monitor.tripped.is_set()
    wait_for(lambda: bool(driver.stops), 1.0, "the stop")
    assert monitor.reason == "signal SIGINT"


def test_a_request_made_while_tripped_trips_again_after_the_reset(monitored) -> None:
    driver, monitor, _ = monitored
    monitor.trip("link lost: test")
    wait_for(monitor.stop_done.is_set, 1.0, "the first stop")
    monitor.request_trip("signal SIGINT")
    monitor.reset()
    wait_for(lambda: len(driver.stops) == 2, 1.0, "the stop the request asked for")
    assert monitor.reason == "signal SIGINT"
