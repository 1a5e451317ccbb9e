"""The reference robot's protocol core with a clock the test sets, fed the lines skidnav's host
module writes (and seals): the handshake, commands and their errors, the stall rule (batches,
expiry, the lease), the link timeout and idle hang-up, replays, oversized lines, authentication,
and the serial line's new session on ``hello``."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from skidnav.realtime.link import protocol as pr
from skidnav.realtime.link.auth import Session
from skidnav.realtime.reference_robot.core import ProtocolCore

HOST = 1000.0  # the host's clock reads 1000 s when the robot's reads 0
SECRET = b"a secret of the lab, 31 bytes.."


class Bench:
    """A reference robot core and a host writing to it with skidnav's own protocol module."""

    def __init__(self, secret: bytes | None = None, **options: object) -> None:
        self.core = ProtocolCore("bench", 0.1, 1.7, now=0.0, secret=secret, **options)  # type: ignore[arg-type]
        self.session = Session(secret, "host") if secret is not None else None
        self.seq = -1
        self.wheels: tuple[float, float] = (0.0, 0.0)
        self.buffer = pr.LineBuffer()

    def line(self, build: Callable[[int], pr.Message], seq: int | None = None) -> bytes:
        """One host line: the next seq (or ``seq``), sealed once the session is keyed."""
        self.seq = self.seq + 1 if seq is None else seq
        line = pr.encode(build(self.seq))
        if self.session is not None and self.session.keyed:
            line = self.session.seal(line)
        return line

    def hello(self) -> bytes:
        nonce = self.session.hello_nonce if self.session is not None else ""
        return self.line(lambda s: pr.Hello(seq=s, name="host", nonce=nonce))

    def cmd(self, sent: float, left: float = 1.7, ttl: float = 0.5) -> bytes:
        return self.line(
            lambda s: pr.Command(
                seq=s, omega_left=left, omega_right=left, stamp=HOST + sent, ttl=ttl
            )
        )

    def beat(self, sent: float) -> bytes:
        return self.line(lambda s: pr.Heartbeat(seq=s, stamp=HOST + sent))

    def stop(self) -> bytes:
        return self.line(lambda s: pr.Stop(seq=s))

    def replies(self, out: bytes) -> list[pr.Message]:
        """The robot's lines, decoded (and their MACs checked) as the host does."""
        self.buffer.feed(out)
        messages = []
        for line in self.buffer.lines():
            message = pr.decode(line)
            if self.session is not None and not isinstance(message, pr.Error):
                if not self.session.keyed:
                    self.session.greet(message.nonce)  # type: ignore[attr-defined]
                self.session.verify(line)
            elif self.session is not None and self.session.keyed:
                self.session.verify(line)
            messages.append(message)
        return messages

    def feed(self, data: bytes, now: float) -> list[str]:
        """Feed ``data`` at ``now``; the kinds of the replies (an error's code)."""
        out, wheels = self.core.feed(data, now)
        if wheels is not None:
            self.wheels = wheels
        return [m.code if isinstance(m, pr.Error) else m.TYPE for m in self.replies(out)]

    def watch(self, now: float) -> list[str]:
        out, wheels = self.core.watch(now)
        if wheels is not None:
            self.wheels = wheels
        return [m.code if isinstance(m, pr.Error) else m.TYPE for m in self.replies(out)]

    @property
    def moving(self) -> bool:
        return self.wheels != (0.0, 0.0)


def greeted(secret: bytes | None = None, **options: object) -> Bench:
    bench = Bench(secret, **options)
    assert bench.feed(bench.hello(), 0.0) == ["hello"]
    assert bench.feed(bench.beat(0.0), 0.0) == ["heartbeat"]
    return bench


def test_hello_then_a_command_is_acknowledged_and_poses_follow() -> None:
    bench = Bench()
    assert bench.core.pose(0.0, 0.3, 0.2, 0.0) == b""  # nothing before the host's hello
    assert bench.feed(bench.cmd(0.0), 0.0) == ["state"] and not bench.moving
    hello = bench.hello()
    out, _ = bench.core.feed(hello[:10], 0.0)  # half a line waits for the rest
    assert out == b""
    assert bench.feed(hello[10:], 0.0) == ["hello"]
    assert bench.feed(bench.cmd(0.01), 0.01) == ["ack"] and bench.wheels == (1.7, 1.7)
    pose = bench.replies(bench.core.pose(0.1, 0.3, 0.2, 0.5))
    assert pose == [pr.PoseReport(seq=3, stamp=0.1, x=0.3, y=0.2, heading=0.5)]
    assert bench.feed(bench.stop() + bench.stop(), 0.15) == ["stopped", "stopped"]
    assert not bench.moving


def test_of_a_batch_only_the_newest_motion_runs_and_every_stop_is_answered() -> None:
    bench = greeted()
    batch = bench.cmd(0.01) + bench.stop() + bench.cmd(0.02, left=-1.0) + bench.beat(0.02)
    assert bench.feed(batch, 0.05) == ["stopped", "ack", "heartbeat"]
    assert bench.wheels == (-1.0, -1.0)
    assert bench.feed(bench.cmd(0.06) + bench.stop(), 0.07) == ["stopped"] and not bench.moving
    assert bench.feed(bench.cmd(0.08) + b"not json\n", 0.09) == ["json"] and not bench.moving


@pytest.mark.parametrize(
    ("line", "code"),
    [
        (
            b'{"v":2,"type":"cmd","seq":9,"omega_left":1.7000001,"omega_right":0,"stamp":1000,"ttl":1}',
            "range",
        ),
        (
            b'{"v":2,"type":"cmd","seq":9,"omega_left":1e308,"omega_right":0,"stamp":1000,"ttl":1}',
            "range",
        ),
        (
            b'{"v":2,"type":"cmd","seq":9,"omega_left":'
            + b"9" * 400
            + b',"omega_right":0,"stamp":1000,"ttl":1}',
            "field",
        ),
        (b'{"v":2,"type":"cmd","seq":9}', "field"),
        (b'{"v":1,"type":"stop","seq":9}', "version"),
        (b'{"v":2,"type":"warp","seq":9}', "unknown_type"),
        (b"\xff\xfe junk", "encoding"),
        (b"{" + b"x" * 5000 + b"}", "oversized"),
        (b'{"v":2,"type":"pose","seq":9,"stamp":0,"x":0,"y":0,"heading":0}', "state"),
    ],
)
def test_a_line_the_robot_cannot_run_is_refused_and_stops_it(line: bytes, code: str) -> None:
    bench = greeted()
    bench.feed(bench.cmd(0.0), 0.0)
    assert bench.moving
    assert bench.feed(line + b"\n", 0.01) == [code]
    assert not bench.moving
    bench.seq = 9
    assert bench.feed(bench.cmd(0.02), 0.02) == ["ack"]  # and it carries on


def test_an_oversized_line_is_skipped_to_its_newline_once() -> None:
    bench = greeted()
    assert bench.feed(b"x" * 3000, 0.01) == ["oversized"]
    assert bench.feed(b"y" * 3000, 0.02) == []  # the same line still
    assert bench.feed(b"\n" + bench.cmd(0.03), 0.03) == ["ack"]


def test_a_command_read_after_its_deadline_is_refused() -> None:
    bench = greeted()
    assert bench.feed(bench.cmd(0.1), 0.1) == ["ack"]
    assert bench.feed(bench.cmd(0.2, ttl=0.1), 0.6) == ["expired"]  # waited 0.4 s in a buffer
    assert not bench.moving


def test_the_lease_stops_the_wheels_on_a_live_link_and_no_ttl_stretches_it() -> None:
    bench = greeted()
    bench.feed(bench.cmd(0.1, ttl=1e300), 0.1)
    for now in (0.2, 0.3, 0.4, 0.59):
        bench.feed(bench.beat(now), now)  # a live link, no new command
        assert bench.watch(now) == [] and bench.moving
    bench.feed(bench.beat(0.6), 0.6)
    assert bench.watch(0.6) == [] and not bench.moving  # max_lease 0.5 s after arrival
    assert bench.core.hang_up is None


def test_a_quiet_link_stops_the_wheels_then_the_host_is_hung_up() -> None:
    bench = greeted(max_lease=5.0, link_timeout=0.3, idle_timeout=1.0)
    bench.feed(bench.cmd(0.0, ttl=5.0), 0.0)
    assert bench.watch(0.25) == [] and bench.moving
    assert bench.watch(0.31) == [] and not bench.moving
    assert bench.core.hang_up is None
    bench.feed(b"{" * 10, 0.9)  # bytes that never make a valid line do not count
    bench.watch(1.01)
    assert bench.core.hang_up == "no valid message for 1.010 s"


def test_a_replayed_or_older_seq_is_refused_and_stops_the_wheels() -> None:
    bench = greeted()
    line = bench.cmd(0.1)
    assert bench.feed(line, 0.1) == ["ack"]
    assert bench.feed(line, 0.15) == ["replay"] and not bench.moving
    older = bench.line(lambda s: pr.Heartbeat(seq=s, stamp=HOST), seq=1)
    assert bench.feed(older, 0.2) == ["replay"]
    bench.seq = 50
    assert bench.feed(bench.cmd(0.3), 0.3) == ["ack"] and bench.moving


def test_an_authenticated_host_drives_the_robot() -> None:
    bench = greeted(SECRET, random_bytes=lambda n: bytes(range(n)))
    assert bench.core.key is not None and bench.core.key.keyed
    assert bench.feed(bench.cmd(0.01), 0.01) == ["ack"] and bench.moving


@pytest.mark.parametrize("attack", ["no nonce", "unsealed", "wrong secret", "tampered"])
def test_a_host_that_does_not_prove_itself_never_moves_the_robot(attack: str) -> None:
    bench = Bench(SECRET)
    if attack == "no nonce":
        bench.session = None
        data = bench.hello() + bench.cmd(0.0)
    else:
        if attack == "wrong secret":
            bench.session = Session(b"not the lab's secret, no", "host")
        hello, _ = bench.core.feed(bench.hello(), 0.0)
        assert pr.decode(hello.rstrip(b"\n")).TYPE == "hello"
        bench.session.greet(bench.core.key.hello_nonce)  # type: ignore[union-attr]
        data = bench.cmd(0.0)
        if attack == "unsealed":
            data = data.split(b',"mac"')[0] + b"}\n"
        elif attack == "tampered":
            data = data.replace(b'"omega_left":1.7', b'"omega_left":1.6')
    out, wheels = bench.core.feed(data, 0.01)
    assert wheels in (None, (0.0, 0.0)) and b'"code":"auth"' in out
    assert bench.core.hang_up is not None and bench.core.hang_up.startswith("authentication failed")
    assert bench.core.feed(bench.cmd(0.02), 0.02) == (b"", None)  # nothing more is taken


def test_on_a_serial_line_a_new_hello_starts_a_new_session() -> None:
    bench = greeted(restart_on_hello=True)
    assert bench.feed(bench.cmd(0.0), 0.0) == ["ack"]
    sent = bench.core.seq
    bench.seq = -1  # the host opened the port again: its seq starts afresh
    assert bench.feed(bench.hello() + bench.cmd(0.1, left=1.0), 0.1) == ["hello", "ack"]
    assert bench.wheels == (1.0, 1.0)
    assert bench.core.seq == sent + 2  # the robot's own seq goes on increasing
    tcp = greeted()
    tcp.seq = -1
    assert tcp.feed(tcp.hello(), 0.1) == ["replay"]  # on TCP a connection is one session
