"""The stall rule of docs/protocol.md on the firmware alone, with a clock the test sets: what
was read at once counts only by its newest motion message, a command read after its deadline is
refused, the lease stops the wheels and no stamp or ttl stretches it, the host clock estimate
ignores late messages and forgets a step of the host's clock by the next command, and a
replayed or older seq is refused."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import pytest

from skidnav.realtime.config import ServerOptions
from skidnav.realtime.control.records import EventLog
from skidnav.realtime.link import protocol as pr
from skidnav.realtime.robot_server.simulated_robot import Firmware
from tests.realtime.realtime_helpers import bench_robot

HOST = 1000.0  # the host's clock reads 1000 s when the robot's reads 0


class Unit:
    """A firmware over a slip-free robot, its replies collected."""

    def __init__(self) -> None:
        self.robot = bench_robot("thesis", slip_free=True)
        self.replies: list[pr.Message] = []
        self.firmware = Firmware(self.robot, ServerOptions(), EventLog(None), self._reply, 0.0)
        self.seq = 0
        self.firmware.receive([pr.Hello(seq=self.next(), name="test")], 0.0)
        self.beat(0.0)

    def _reply(self, build: Callable[[int], pr.Message]) -> None:
        self.replies.append(build(len(self.replies)))

    def next(self) -> int:
        self.seq += 1
        return self.seq

    def beat(self, now: float) -> None:
        """A heartbeat sent and read at robot time ``now``."""
        self.firmware.receive([pr.Heartbeat(seq=self.next(), stamp=HOST + now)], now)

    def cmd(self, sent: float, left: float = 1.7, ttl: float = 0.5) -> pr.Command:
        stamp = HOST + sent
        return pr.Command(seq=self.next(), omega_left=left, omega_right=left, stamp=stamp, ttl=ttl)

    def stop(self) -> pr.Stop:
        return pr.Stop(seq=self.next())

    def kinds(self) -> list[str]:
        return [r.code if isinstance(r, pr.Error) else r.TYPE for r in self.replies]


def test_commands_read_together_with_a_later_stop_are_never_applied() -> None:
    unit = Unit()
    unit.replies.clear()
    old = [unit.cmd(0.01), unit.cmd(0.02), unit.stop(), unit.stop()]
    unit.firmware.receive(old, now=0.05)
    assert unit.kinds() == ["stopped", "stopped"]  # every stop answered, no ack
    assert not unit.robot.moving


def test_of_commands_read_together_only_the_newest_runs() -> None:
    unit = Unit()
    unit.replies.clear()
    first, stop, newest = unit.cmd(0.01, left=1.7), unit.stop(), unit.cmd(0.02, left=-1.0)
    unit.firmware.receive([first, stop, newest], now=0.05)
    assert unit.kinds() == ["stopped", "ack"]
    assert isinstance(unit.replies[-1], pr.Ack) and unit.replies[-1].ack == newest.seq
    unit.robot.step()
    assert unit.robot.wheels == (-1.0, -1.0)


def test_a_malformed_line_after_a_command_supersedes_it() -> None:
    unit = Unit()
    unit.replies.clear()
    unit.firmware.receive([unit.cmd(0.01), pr.ProtocolError("json", "bad")], now=0.05)
    assert unit.kinds() == ["json"] and not unit.robot.moving


def test_a_command_read_after_its_deadline_is_refused_and_stops_the_robot() -> None:
    unit = Unit()
    unit.firmware.receive([unit.cmd(0.1)], now=0.1)
    assert unit.robot.moving
    unit.replies.clear()
    unit.firmware.receive([unit.cmd(0.2, ttl=0.1)], now=0.6)  # waited 0.4 s in a buffer
    assert unit.kinds() == ["expired"] and not unit.robot.moving


def test_the_lease_stops_the_wheels_when_no_fresh_command_follows() -> None:
    unit = Unit()
    unit.firmware.receive([unit.cmd(0.1, ttl=0.3)], now=0.1)
    for now in (0.2, 0.3, 0.39):
        unit.beat(now)  # a live link, but no new command
        assert unit.firmware.watch(now) is None
        assert unit.robot.moving
    unit.beat(0.41)
    assert unit.firmware.watch(0.41) is None
    assert not unit.robot.moving


def test_a_silent_client_stops_the_wheels_then_is_declared_idle() -> None:
    unit = Unit()
    unit.firmware.receive([unit.cmd(0.0, ttl=10.0)], now=0.0)
    options = unit.firmware.options
    assert unit.firmware.watch(options.link_timeout / 2) is None and unit.robot.moving
    assert unit.firmware.watch(options.link_timeout + 0.01) is None
    assert not unit.robot.moving
    reason = unit.firmware.watch(options.idle_timeout + 0.01)
    assert reason is not None and "no valid message" in reason


@pytest.mark.parametrize("rate", [-5e-4, 0.0, 5e-4])
def test_host_clock_follows_drifting_clocks_and_ignores_late_messages(rate: float) -> None:
    clock = pr.HostClock()
    offset = -HOST
    for k in range(600):  # 60 s of messages 0.1 s apart, 1 ms transport delay
        now = k * 0.1
        clock.observe(stamp=now * (1 + rate) - offset, now=now + 0.001)
    late_now = 60.0
    stamp = (late_now - 0.4) * (1 + rate) - offset
    clock.observe(stamp=stamp, now=late_now)  # a 0.4 s stall
    assert clock.offset is not None
    true_offset = late_now - (late_now * (1 + rate) - offset)
    assert abs(clock.offset - true_offset) < 0.01
    assert clock.age(stamp, late_now) == pytest.approx(0.4, abs=0.01)


@pytest.mark.parametrize("step", [1e6, -1e6, 30.0, -30.0, 0.4, -0.4])
def test_a_step_of_the_host_clock_is_forgotten_by_the_next_command(step: float) -> None:
    """One command stamped far ahead (or behind) and then the clock as before, or the clock
    stepped for good: either way the command after it runs."""
    for lasting in (False, True):
        unit = Unit()
        unit.firmware.receive([unit.cmd(0.1)], now=0.1)
        jumped = unit.cmd(0.2)
        jumped = replace(jumped, stamp=jumped.stamp + step)
        unit.firmware.receive([jumped], now=0.2)
        unit.replies.clear()
        after = unit.cmd(0.3)
        if lasting:
            after = replace(after, stamp=after.stamp + step)
        unit.firmware.receive([after], now=0.3)
        assert unit.kinds() == ["ack"], (step, lasting)
        assert unit.robot.moving


@pytest.mark.parametrize(("stamp", "ttl"), [(HOST, 1e300), (1e308, 1e308), (HOST, 1e308)])
def test_no_stamp_or_ttl_holds_the_wheels_past_the_lease(stamp: float, ttl: float) -> None:
    unit = Unit()
    command = pr.Command(seq=unit.next(), omega_left=1.7, omega_right=1.7, stamp=stamp, ttl=ttl)
    unit.firmware.receive([command], now=0.0)
    max_lease = unit.firmware.options.max_lease
    for now in (0.1, 0.2, 0.3, 0.4, max_lease - 0.01):
        unit.beat(now)  # a live link, but no new command
        unit.firmware.watch(now)
    assert unit.robot.moving
    unit.beat(max_lease)
    unit.firmware.watch(max_lease)
    assert not unit.robot.moving


def test_a_replayed_or_older_seq_is_refused_and_stops_the_wheels() -> None:
    unit = Unit()
    command = unit.cmd(0.1)
    unit.firmware.receive([command], now=0.1)
    assert unit.robot.moving
    unit.replies.clear()
    unit.firmware.receive([command], now=0.15)  # the same line again
    older = replace(unit.cmd(0.2), seq=command.seq - 1)
    unit.firmware.receive([older], now=0.2)
    assert unit.kinds() == ["replay", "replay"] and not unit.robot.moving
    unit.firmware.receive([unit.cmd(0.3)], now=0.3)  # the next one in order runs
    assert unit.kinds()[-1] == "ack" and unit.robot.moving


def test_nothing_more_is_applied_once_the_connection_drops_mid_batch() -> None:
    unit = Unit()
    unit.replies.clear()
    firmware = unit.firmware

    def drop_on_first_reply(build: Callable[[int], pr.Message]) -> None:
        unit.replies.append(build(0))
        firmware.closed = True  # what the server does when the reply overflows the queue

    firmware.reply = drop_on_first_reply
    firmware.receive([pr.Heartbeat(seq=unit.next(), stamp=HOST + 0.1), unit.cmd(0.1)], now=0.1)
    assert unit.kinds() == ["heartbeat"] and not unit.robot.moving
