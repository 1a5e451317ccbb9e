"""The sim server against hostile and broken clients: nothing a client sends or fails to read
stalls the robot's period or crashes it, no client keeps the robot from the next one, no stamp
or ttl keeps the wheels turning past the server's lease, and no seq is acknowledged twice."""

from __future__ import annotations

import selectors
import socket
import struct
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from skidnav.realtime.link import protocol as pr
from tests.realtime.realtime_helpers import RawClient, ServerThread, wait_for

TIME_SCALE = 10.0


def busy_or_closed(sock: socket.socket, timeout: float = 5.0) -> str:
    """What a refused client reads: the error code, or "closed" (end of stream or reset)."""
    sock.settimeout(timeout)
    try:
        data = sock.recv(4096)
    except ConnectionError:
        return "closed"
    if not data:
        return "closed"
    message = pr.decode(data.split(b"\n")[0])
    return message.code if isinstance(message, pr.Error) else message.TYPE


def test_a_client_that_never_reads_is_dropped_and_the_period_goes_on(tmp_path: Path) -> None:
    log = tmp_path / "server.jsonl"
    with ServerThread(TIME_SCALE, log=log) as server:
        flooder = socket.socket()
        flooder.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        flooder.connect(("127.0.0.1", server.port))
        flooder.sendall(pr.encode(pr.Hello(seq=0, name="flooder")))
        started, robot_start = time.monotonic(), server.robot.time
        beat = b"".join(pr.encode(pr.Heartbeat(seq=n, stamp=0.0)) for n in range(1, 4000))
        with pytest.raises(OSError):  # every heartbeat asks for a reply it never reads
            for _ in range(50):
                flooder.sendall(beat)
                time.sleep(0.01)
        wait_for(lambda: any(e["event"] == "disconnect" for e in server.events()), 5.0, "the drop")
        elapsed = time.monotonic() - started
        flooder.close()
        robot_elapsed = server.robot.time - robot_start
        # blocking writes froze robot time at the first full buffer; now it keeps its pace
        assert robot_elapsed > 0.1 * TIME_SCALE * elapsed
        drops = [e for e in server.events() if e["event"] == "disconnect"]
        assert "not reading" in drops[0]["reason"]
        client = RawClient(server.port)  # the slot is free
        assert client.hello().name == "skidnav-sim"
        client.close()


@pytest.mark.parametrize("behaviour", ["silent", "one byte per 50 ms", "heartbeats without hello"])
def test_a_client_without_valid_messages_is_dropped_for_the_next(behaviour: str) -> None:
    options = {"link_timeout": 0.1, "idle_timeout": 0.3}
    with ServerThread(TIME_SCALE, options=options) as server:
        stale = RawClient(server.port)
        if behaviour == "silent":
            stale.hello()
        refused = socket.create_connection(("127.0.0.1", server.port), timeout=2.0)
        assert busy_or_closed(refused) == "busy"
        refused.close()
        deadline = time.monotonic() + 5.0
        while server.server.connected and time.monotonic() < deadline:
            if behaviour == "one byte per 50 ms":
                stale.sock.send(b"{")
            elif behaviour == "heartbeats without hello":
                stale.send(lambda seq: pr.Heartbeat(seq=seq, stamp=time.monotonic()))
            time.sleep(0.05)
        assert not server.server.connected, "the stale client is still attached"
        operator = RawClient(server.port)
        assert operator.hello().name == "skidnav-sim"
        operator.close()
        stale.close()


def test_resets_while_a_client_is_attached_leave_the_server_serving(
    server_thread: ServerThread,
) -> None:
    client = RawClient(server_thread.port)
    client.hello()
    for _ in range(20):
        rude = socket.socket()
        rude.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        rude.connect(("127.0.0.1", server_thread.port))
        rude.close()  # linger 0: the close is a reset
    time.sleep(0.2)
    assert server_thread.thread.is_alive()
    before = client.receive_until(pr.PoseReport)
    after = client.latest_pose(window=0.1)
    assert isinstance(before, pr.PoseReport) and after.stamp > before.stamp
    client.close()


def test_two_hundred_simultaneous_connects_are_all_answered_busy_at_once(
    server_thread: ServerThread,
) -> None:
    holder = RawClient(server_thread.port)
    holder.hello()
    started = time.monotonic()
    sockets = []
    with selectors.DefaultSelector() as selector:
        for _ in range(200):
            sock = socket.socket()
            sock.setblocking(False)
            sock.connect_ex(("127.0.0.1", server_thread.port))
            selector.register(sock, selectors.EVENT_READ)
            sockets.append(sock)
        answers: dict[socket.socket, bytes] = {}
        while len(answers) < len(sockets) and time.monotonic() - started < 30.0:
            for key, _ in selector.select(timeout=1.0):
                sock = key.fileobj
                assert isinstance(sock, socket.socket)
                try:
                    answers[sock] = sock.recv(4096)
                except ConnectionError:
                    answers[sock] = b""
                selector.unregister(sock)
    elapsed = time.monotonic() - started
    for sock in sockets:
        sock.close()
    holder.close()
    busy = [a for a in answers.values() if a.startswith(b'{"v":2,"type":"error"')]
    assert len(busy) == 200 and all(b'"code":"busy"' in a for a in busy)
    assert elapsed < 10.0  # a listen backlog of 2 made this take over a minute


@pytest.mark.parametrize(
    ("line", "code"),
    [
        (b'"omega_left":1e308,"omega_right":-1e308', "range"),
        (b'"omega_left":1.7000001,"omega_right":0', "range"),
        (b'"omega_left":' + b"9" * 400 + b',"omega_right":0', "field"),
    ],
)
def test_commands_the_robot_cannot_run_are_refused_and_stop_it(
    server_thread: ServerThread, line: bytes, code: str
) -> None:
    client = RawClient(server_thread.port)
    client.hello()
    client.command(1.7, 1.7)
    client.receive_until(pr.Ack)
    stamp = f'{{"v":2,"type":"cmd","seq":9,"stamp":{time.monotonic()},"ttl":1.0,'.encode()
    client.sock.sendall(stamp + line + b"}\n")
    error = client.receive_until(pr.Error)
    assert isinstance(error, pr.Error) and error.code == code
    assert server_thread.robot.wheels == (0.0, 0.0)
    pose = client.latest_pose(window=0.1)
    assert 0 <= pose.x <= 0.62 and 0 <= pose.y <= 0.505
    assert server_thread.thread.is_alive()
    client.close()


def test_a_command_read_after_its_deadline_is_refused(tmp_path: Path) -> None:
    with ServerThread(TIME_SCALE, log=tmp_path / "server.jsonl") as server:
        client = RawClient(server.port)
        client.hello()
        client.send(lambda seq: pr.Heartbeat(seq=seq, stamp=time.monotonic()))  # the clock
        client.command(1.7, 1.7, ttl=0.2, age=0.5)
        error = client.receive_until(pr.Error)
        assert isinstance(error, pr.Error) and error.code == "expired"
        assert not server.robot.moving
        fresh = client.command(1.7, 1.7, ttl=0.2, age=0.05)
        ack = client.receive_until(pr.Ack)
        assert isinstance(ack, pr.Ack) and ack.ack == fresh
        client.close()
        applied = [e["seq"] for e in server.events() if e["event"] == "cmd"]
        assert applied == [fresh]


def heartbeats_until_the_wheels_stop(client: RawClient, server: ServerThread, sent: float) -> None:
    """Once the wheels turn, keep the link alive with heartbeats (no new command) until they
    stop, or 3 s after ``sent`` (monotonic [s])."""
    wait_for(lambda: server.robot.moving, 1.0, "the wheels to turn")
    while server.robot.moving and time.monotonic() - sent < 3.0:
        client.send(lambda seq: pr.Heartbeat(seq=seq, stamp=time.monotonic()))
        time.sleep(0.02)


def test_the_wheels_stop_when_the_lease_runs_out_on_a_live_link(tmp_path: Path) -> None:
    with ServerThread(TIME_SCALE, log=tmp_path / "server.jsonl") as server:
        client = RawClient(server.port)
        client.hello()
        client.command(1.7, 1.7, ttl=0.15)
        client.receive_until(pr.Ack)
        sent = time.monotonic()
        heartbeats_until_the_wheels_stop(client, server, sent)
        assert not server.robot.moving
        assert time.monotonic() - sent >= 0.15
        events = [e["event"] for e in server.events()]
        assert "lease" in events and "watchdog" not in events
        assert server.server.connected  # the link itself is fine
        client.close()


def raw_command(seq: int, stamp: float, ttl: float) -> pr.Command:
    return pr.Command(seq=seq, omega_left=1.7, omega_right=1.7, stamp=stamp, ttl=ttl)


@pytest.mark.parametrize(
    ("stamp_ahead", "ttl"), [(0.0, 1e300), (1e308, 1e308)], ids=["ttl-1e300", "stamp-ttl-1e308"]
)
def test_no_stamp_or_ttl_keeps_the_wheels_turning_past_the_bounded_lease(
    tmp_path: Path, stamp_ahead: float, ttl: float
) -> None:
    with ServerThread(TIME_SCALE, log=tmp_path / "server.jsonl") as server:
        max_lease = server.server.options.max_lease
        client = RawClient(server.port)
        client.hello()
        stamp = stamp_ahead or time.monotonic()
        client.send(lambda seq: raw_command(seq, stamp, ttl))
        client.receive_until(pr.Ack)
        sent = time.monotonic()
        heartbeats_until_the_wheels_stop(client, server, sent)
        stopped_after = time.monotonic() - sent
        assert not server.robot.moving
        assert stopped_after < max_lease + 0.2  # the lease plus a few (busy) periods
        assert "lease" in [e["event"] for e in server.events()]
        assert server.server.connected
        client.close()


def test_a_command_stamped_a_million_seconds_ahead_is_forgotten_by_the_next(
    server_thread: ServerThread,
) -> None:
    client = RawClient(server_thread.port)
    client.hello()
    for ahead in (0.0, 1e6, 0.0, 0.0):  # the host's clock jumps ahead once, then back
        stamp = time.monotonic() + ahead
        seq = client.send(lambda s, stamp=stamp: raw_command(s, stamp, 0.5))
        reply = client.receive_until(pr.Ack)
        assert isinstance(reply, pr.Ack) and reply.ack == seq, ahead
    assert server_thread.robot.moving
    client.close()


def next_reply(client: RawClient) -> pr.Message:
    """The next ``ack`` or ``error`` (poses skipped)."""
    while True:
        message = client.receive_until(pr.Message)
        if isinstance(message, pr.Ack | pr.Error):
            return message


def check_replays_refused(client: RawClient, stopped: Callable[[], bool]) -> None:
    """After a ``hello`` and an acknowledged ``cmd``: the same line again, and a correctly
    authenticated older ``seq``, are refused (``replay``), the robot standing (``stopped()``) after
    the replay; a newer ``seq`` is acknowledged again. Closes ``client``."""
    client.hello()
    client.command(1.7, 1.7)
    assert isinstance(next_reply(client), pr.Ack)
    client.sock.sendall(client.sent[-1])  # the very same line again
    replayed = next_reply(client)
    assert isinstance(replayed, pr.Error) and replayed.code == "replay"
    assert stopped()
    client.seq -= 2  # an older seq, correctly authenticated
    client.command(1.7, 1.7)
    older = next_reply(client)
    assert isinstance(older, pr.Error) and older.code == "replay"
    client.seq += 5
    fresh = client.command(1.7, 1.7)
    ack = next_reply(client)
    assert isinstance(ack, pr.Ack) and ack.ack == fresh
    client.close()


@pytest.mark.parametrize("secret", [None, b"a shared secret of the lab"], ids=["plain", "auth"])
def test_a_replayed_or_older_command_is_refused_not_acknowledged(secret: bytes | None) -> None:
    with ServerThread(TIME_SCALE, options={"secret": secret}) as server:
        check_replays_refused(
            RawClient(server.port, secret=secret), lambda: not server.robot.moving
        )
