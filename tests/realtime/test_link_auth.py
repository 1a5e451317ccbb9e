"""Authentication of the robot link: the MAC of each line and its worked example in
docs/protocol.md, the secret's sources, and real servers and clients on loopback that refuse
each other without the right secret — the robot never moving for an unproven host."""

from __future__ import annotations

import re
import socket
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from skidnav.errors import UserError
from skidnav.realtime.link import auth
from skidnav.realtime.link import protocol as pr
from skidnav.realtime.link.line_client import LineClient, TcpLink
from tests.realtime.realtime_helpers import RawClient, ServerThread, wait_for

SECRET = b"the lab's shared secret, 33 bytes"
DOCS = Path(__file__).resolve().parents[2] / "docs" / "protocol.md"


def keyed_pair(secret: bytes = SECRET) -> tuple[auth.Session, auth.Session]:
    """A host and a robot session that exchanged their nonces."""
    host, robot = auth.Session(secret, "host"), auth.Session(secret, "robot")
    host.greet(robot.hello_nonce)
    robot.greet(host.hello_nonce)
    return host, robot


STOP = pr.encode(pr.Stop(seq=4))


def test_a_sealed_line_is_checked_by_the_peer_only() -> None:
    host, robot = keyed_pair()
    line = host.seal(STOP)
    assert line.endswith(b'"}\n') and pr.decode(line) == pr.Stop(seq=4)
    robot.verify(line.rstrip(b"\n"))
    robot.verify(line.rstrip(b"\n") + b"\r")  # CRLF
    with pytest.raises(pr.ProtocolError, match="wrong MAC") as caught:
        host.verify(line.rstrip(b"\n"))  # sent back to its sender: the direction differs
    assert caught.value.code == "auth"
    _, other_robot = keyed_pair()
    with pytest.raises(pr.ProtocolError, match="wrong MAC"):
        other_robot.verify(line.rstrip(b"\n"))  # replayed on another connection
    tampered = line.replace(b'"seq":4', b'"seq":5').rstrip(b"\n")
    with pytest.raises(pr.ProtocolError, match="wrong MAC"):
        robot.verify(tampered)
    for bare in (STOP.rstrip(b"\n"), b"", b"}", line[:-3] + b"X"):
        with pytest.raises(pr.ProtocolError, match="without a MAC"):
            robot.verify(bare)


def test_a_wrong_secret_fails_and_short_secrets_are_refused() -> None:
    host, _ = keyed_pair()
    robot = auth.Session(b"another secret of the lab", "robot")
    robot.greet(host.hello_nonce)
    with pytest.raises(pr.ProtocolError, match="wrong MAC"):
        robot.verify(host.seal(STOP).rstrip(b"\n"))
    with pytest.raises(ValueError, match="expected a link secret of at least 16 bytes, got 5"):
        auth.Session(b"short", "host")
    with pytest.raises(pr.ProtocolError, match="no nonce") as caught:
        robot.greet("")
    assert caught.value.code == "auth"


def test_the_secret_comes_from_a_file_or_the_environment_never_shown(tmp_path: Path) -> None:
    key = tmp_path / "robot.key"
    key.write_bytes(SECRET + b"\n")
    assert auth.load_secret(key, {}) == SECRET
    assert auth.load_secret(None, {auth.SECRET_ENV: SECRET.decode()}) == SECRET
    assert auth.load_secret(None, {}) is None
    key.write_bytes(b"hunter2\n")
    with pytest.raises(UserError) as caught:
        auth.load_secret(key, {})
    assert str(caught.value) == f"{key}: expected a link secret of at least 16 bytes, got 7"
    with pytest.raises(UserError, match=r"^SKIDNAV_LINK_SECRET: expected a link secret"):
        auth.load_secret(None, {auth.SECRET_ENV: "hunter2"})
    with pytest.raises(UserError, match="no such secret file"):
        auth.load_secret(tmp_path / "missing.key", {})


def documented_example() -> tuple[dict[str, str], list[tuple[str, bytes]]]:
    """The worked example of docs/protocol.md: its settings and its (sender, line) pairs."""
    text = DOCS.read_text(encoding="utf-8")
    block = text.split("### Worked example", 1)[1].split("```", 2)[1]
    settings_ = dict(re.findall(r"^(secret|host nonce|robot nonce) +(.+)$", block, re.M))
    lines = re.findall(r"^(host|robot) +→ (.+)$", block, re.M)
    return settings_, [(sender, line.encode() + b"\n") for sender, line in lines]


def test_the_worked_example_of_the_docs_is_what_skidnav_sends() -> None:
    values, lines = documented_example()
    secret = values["secret"].encode()
    nonces = {side: bytes.fromhex(values[f"{side} nonce"]) for side in ("host", "robot")}
    sessions = {side: auth.Session(secret, side, nonces[side]) for side in ("host", "robot")}
    sessions["host"].greet(nonces["robot"].hex())
    sessions["robot"].greet(nonces["host"].hex())
    assert [sender for sender, _ in lines] == ["host", "robot", "host", "robot"]
    for index, (sender, line) in enumerate(lines):
        encoded = pr.encode(pr.decode(line))
        expected = encoded if index == 0 else sessions[sender].seal(encoded)  # hello: no MAC
        assert line == expected, f"line {index + 1} of the example"
    body = lines[2][1].split(auth.MAC_FIELD)[0]
    tag = auth.mac(secret, b"H", nonces["host"], nonces["robot"], body)
    assert tag.encode() in lines[2][1]
    text = DOCS.read_text(encoding="utf-8")
    assert body.decode() in text  # the MAC input spelled out
    assert (b"H" + nonces["host"] + nonces["robot"]).hex() in text.replace(" ", "")


@settings(max_examples=300, deadline=1000)
@given(st.lists(st.binary(max_size=3 * pr.MAX_LINE_BYTES), max_size=6), st.booleans())
def test_random_bytes_through_the_authenticated_reader_raise_only_one_line_protocol_errors(
    chunks: list[bytes], keyed: bool
) -> None:
    """What a robot does with each line it reads — split, check the MAC, decode — never
    raises anything but ProtocolError, whose message is one line, and never hangs."""
    _, robot = keyed_pair() if keyed else (None, auth.Session(SECRET, "robot"))
    buffer = pr.LineBuffer()
    started = time.monotonic()
    for chunk in chunks:
        buffer.feed(chunk)
        while True:
            try:
                for line in buffer.lines():
                    try:
                        if robot.keyed:
                            robot.verify(line)
                        pr.decode(line)
                    except pr.ProtocolError as error:
                        assert "\n" not in str(error) and error.code
                break
            except pr.ProtocolError as error:  # an oversized line
                assert error.code == "oversized"
    assert time.monotonic() - started < 1.0


@settings(max_examples=200, deadline=1000)
@given(st.binary(min_size=1, max_size=200))
def test_a_forged_mac_never_passes(noise: bytes) -> None:
    host, robot = keyed_pair()
    line = host.seal(STOP).rstrip(b"\n")
    forged = line[: -auth.TRAILER_BYTES] + auth.MAC_FIELD + noise.hex()[:64].encode() + b'"}'
    if forged != line:
        with pytest.raises(pr.ProtocolError):
            robot.verify(forged)


# --- real servers and clients on loopback ----------------------------------------------------


@pytest.fixture
def secured() -> Iterator[ServerThread]:
    """A sim server that requires SECRET (time scale 10), logging nothing."""
    with ServerThread(options={"secret": SECRET}) as server:
        yield server


def refused(client: RawClient) -> str:
    """The error code the server answered with; it must then close the connection."""
    error = client.receive_until(pr.Error)
    assert isinstance(error, pr.Error)
    client.sock.settimeout(2.0)  # a server that does not hang up fails with TimeoutError
    try:
        while client.sock.recv(4096):
            pass
    except ConnectionResetError:
        pass
    client.close()
    return error.code


def test_a_client_without_the_secret_is_refused_and_the_robot_never_moves(
    secured: ServerThread,
) -> None:
    start = secured.robot.pose
    plain = RawClient(secured.port)  # hello without a nonce, then a command
    plain.send(lambda seq: pr.Hello(seq=seq, name="intruder"))
    plain.command(1.7, 1.7)
    assert refused(plain) == "auth"
    wait_for(lambda: not secured.server.connected, 2.0, "the intruder to be dropped")
    unsealed = RawClient(secured.port, secret=SECRET)  # a nonce, then a command without a MAC
    unsealed.hello()
    command = pr.Command(seq=9, omega_left=1.7, omega_right=1.7, stamp=time.monotonic(), ttl=0.5)
    unsealed.sock.sendall(pr.encode(command))
    assert refused(unsealed) == "auth"
    time.sleep(0.1)
    assert not secured.robot.moving and secured.robot.pose == start


def test_a_client_with_the_wrong_secret_is_refused_and_the_robot_never_moves(
    secured: ServerThread,
) -> None:
    start = secured.robot.pose
    wrong = RawClient(secured.port, secret=b"not the lab's secret at all")
    with pytest.raises(pr.ProtocolError, match="wrong MAC"):  # the robot's hello fails here
        wrong.hello()
    wrong.command(1.7, 1.7)  # press on regardless, with the wrong key
    wrong.session = None  # the robot's error is sealed with the right one
    assert refused(wrong) == "auth"
    client = LineClient(TcpLink("127.0.0.1", secured.port), secret=b"not the lab's secret at all")
    with pytest.raises(ConnectionError, match="robot not authenticated"):
        client.connect()
    time.sleep(0.1)
    assert not secured.robot.moving and secured.robot.pose == start


def test_the_right_secret_drives_the_robot_and_stops_it(secured: ServerThread) -> None:
    client = LineClient(TcpLink("127.0.0.1", secured.port), secret=SECRET)
    client.connect()
    try:
        wait_for(lambda: client.latest_pose() is not None, 1.0, "a first pose")
        client.command(1.7, 1.7)
        wait_for(lambda: secured.robot.wheels == (1.7, 1.7), 1.0, "the command")
        time.sleep(0.1)  # heartbeats and poses, all authenticated
        assert client.stop() is True
        assert secured.robot.wheels == (0.0, 0.0) and client.fault is None
    finally:
        client.close()


@pytest.mark.parametrize("server_secret", [None, b"a different secret of the lab"])
def test_a_client_with_a_secret_refuses_a_robot_that_cannot_prove_it(
    server_secret: bytes | None,
) -> None:
    with ServerThread(options={"secret": server_secret}) as server:
        client = LineClient(TcpLink("127.0.0.1", server.port), secret=SECRET)
        with pytest.raises(ConnectionError, match="robot not authenticated"):
            client.connect()
        assert not server.robot.moving


class ForgingRobot:
    """A robot on a loopback socket that knows SECRET and shakes hands correctly, then sends a
    pose with a forged MAC (``forge="mac"``), a ``stopped`` without one (``"unsealed"``) or one
    genuine pose twice (``"replay"``)."""

    def __init__(self, forge: str) -> None:
        self.forge = forge
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port = self.listener.getsockname()[1]
        self.thread = threading.Thread(target=self._serve)
        self.thread.start()

    def _serve(self) -> None:
        conn, _ = self.listener.accept()
        session = auth.Session(SECRET, "robot")
        with conn:
            hello = pr.decode(conn.recv(4096).split(b"\n")[0])
            assert isinstance(hello, pr.Hello)
            session.greet(hello.nonce)
            conn.sendall(session.seal(pr.encode(
                pr.Hello(seq=0, name="forger", period=0.1, nonce=session.hello_nonce)
            )))  # fmt: skip
            pose = session.seal(pr.encode(pr.PoseReport(seq=1, stamp=0.1, x=0.3, y=0.2, heading=0)))
            if self.forge == "mac":
                body = pose.split(auth.MAC_FIELD)[0]
                conn.sendall(body + auth.MAC_FIELD + b"0" * 64 + b'"}\n')
            elif self.forge == "unsealed":
                conn.sendall(pr.encode(pr.Stopped(seq=1, ack=1)))
            elif self.forge == "replay":
                conn.sendall(pose + pose)
            time.sleep(0.5)

    def close(self) -> None:
        self.thread.join(timeout=5)
        self.listener.close()


@pytest.mark.parametrize(
    ("forge", "fault"),
    [
        ("mac", "robot not authenticated (auth): wrong MAC"),
        ("unsealed", "robot not authenticated (auth): line without a MAC"),
        ("replay", "malformed message (replay): robot pose 1 after 1"),
    ],
)
def test_a_forged_or_replayed_robot_line_is_a_fault(forge: str, fault: str) -> None:
    robot = ForgingRobot(forge=forge)
    client = LineClient(TcpLink("127.0.0.1", robot.port), secret=SECRET)
    seen: list[str] = []
    client.on_fault = seen.append
    try:
        client.connect()  # the robot's hello is genuine
        wait_for(lambda: bool(seen), 2.0, "the fault")
        assert seen[0] == fault
    finally:
        client.close()
        robot.close()
