"""The reference robot's portable parts on their own: the import restriction that keeps the
package runnable on MicroPython, HMAC-SHA256 against CPython's ``hmac``, framing and parsing
against the host's own :mod:`~skidnav.realtime.link.protocol`, the worked example of
docs/protocol.md, the running clock and the simulated base's kinematics."""

from __future__ import annotations

import ast
import hashlib
import hmac
import math
import time
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from skidnav.realtime.link import auth
from skidnav.realtime.link import protocol as pr
from skidnav.realtime.reference_robot import authentication, lines, messages
from skidnav.realtime.reference_robot.clock import running_clock
from skidnav.realtime.reference_robot.core import ProtocolCore
from skidnav.realtime.reference_robot.hmac_sha256 import hmac_sha256, same_bytes
from skidnav.realtime.reference_robot.simulated_base import SimulatedBase
from skidnav.robot.kinematics import body_velocities, exact_step
from tests.realtime.test_link_auth import documented_example

PACKAGE = Path(__file__).resolve().parents[2] / "src/skidnav/realtime/reference_robot"
PORTABLE_IMPORTS = {"json", "time", "hashlib", "binascii", "math", "select", "socket", "sys", "os"}
CPYTHON_ONLY = {"cli.py", "__main__.py", "serial_port.py", "secret_file.py"}
"""The adapters and the command line, which a board does not run."""


def imports(tree: ast.Module) -> list[tuple[str, int]]:
    """(module, level) of every import that runs: those under ``if TYPE_CHECKING:`` do not."""
    found: list[tuple[str, int]] = []
    skipped: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING":
            skipped.update(id(child) for child in ast.walk(node))
    for node in ast.walk(tree):
        if id(node) in skipped:
            continue
        if isinstance(node, ast.Import):
            found += [(alias.name, 0) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            found.append((node.module or "", node.level))
    return found


def test_portable_modules_import_only_what_micropython_has() -> None:
    portable = sorted(p for p in PACKAGE.glob("*.py") if p.name not in CPYTHON_ONLY)
    assert len(portable) >= 12
    for path in portable:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for module, level in imports(tree):
            if level:  # a sibling: itself portable, never one of the CPython-only modules
                assert f"{module}.py" not in CPYTHON_ONLY, (path.name, module)
                assert (PACKAGE / f"{module}.py").exists(), (path.name, module)
            else:
                assert module.split(".")[0] in PORTABLE_IMPORTS, (path.name, module)
        for node in ast.walk(tree):  # no dataclasses or threads behind another name
            assert not (isinstance(node, ast.Name) and node.id in ("dataclass", "Thread"))


def test_the_import_check_catches_what_a_board_lacks() -> None:
    guarded = "TYPE_CHECKING = False\nif TYPE_CHECKING:\n    from typing import Any\n"
    assert imports(ast.parse(guarded)) == []
    caught = imports(ast.parse("import numpy\nfrom .cli import main\nimport hmac\n"))
    assert caught == [("numpy", 0), ("cli", 1), ("hmac", 0)]


@settings(max_examples=400, deadline=None)
@given(st.binary(max_size=200), st.binary(max_size=300))
def test_hmac_sha256_is_cpythons_hmac(key: bytes, message: bytes) -> None:
    assert hmac_sha256(key, message) == hmac.new(key, message, hashlib.sha256).digest()


@pytest.mark.parametrize("key_length", [0, 1, 63, 64, 65, 128, 1000])
def test_hmac_sha256_at_the_block_edges(key_length: int) -> None:
    key = bytes(range(256)) * 4
    key = key[:key_length]
    for message in (b"", b"x" * 55, b"x" * 64, b"x" * 1024):
        assert hmac_sha256(key, message) == hmac.new(key, message, hashlib.sha256).digest()


def test_same_bytes_compares_every_byte() -> None:
    tag = bytes(range(64))
    assert same_bytes(tag, bytes(tag))
    for index in (0, 31, 63):
        other = bytearray(tag)
        other[index] ^= 1
        assert not same_bytes(tag, bytes(other))
    assert not same_bytes(tag, tag[:-1])


# --- framing and parsing, against the host's protocol module --------------------------------

LINE_PIECES = st.sampled_from(
    [
        b'{"v":2,"type":"cmd","seq":1,"omega_left":1.7,"omega_right":-1,"stamp":5,"ttl":0.5}',
        b'{"v":2,"type":"cmd","seq":1,"omega_left":1.7,"omega_right":0,"stamp":5,"ttl":0}',
        b'{"v":2,"type":"hello","seq":0,"name":"h","nonce":"000102030405060708090a0b0c0d0e0f"}',
        b'{"v":2,"type":"hello","seq":0,"name":"h","nonce":"0001"}',
        b'{"v":2,"type":"stop","seq":9223372036854775807}',
        b'{"v":2,"type":"stop","seq":9223372036854775808}',
        b'{"v":2,"type":"heartbeat","seq":3,"stamp":1e999}',
        b'{"v":2,"type":"heartbeat","seq":3,"stamp":NaN}',
        b'{"v":2,"type":"heartbeat","seq":true,"stamp":1}',
        b'{"v":2,"type":"error","seq":3,"code":"x","message":"\\ud800"}',
        b'{"v":1,"type":"stop","seq":1}',
        b'{"v":2.0,"type":"stop","seq":1}',
        b'{"v":2,"type":"teleport","seq":1}',
        b'{"v":2,"type":"pose","seq":1,"stamp":0,"x":' + b"9" * 400 + b',"y":0,"heading":0}',
        b"[1,2]",
        b"\xff\xfe",
        b"{",
        b"",
        b"\n",
        b"\r\n",
        b"x" * 700,
    ]
)


def host_items(data: bytes) -> list[object]:
    """What the host's protocol module makes of ``data``: each line's message, or the code of
    its error."""
    buffer, items = pr.LineBuffer(), []
    buffer.feed(data)
    while True:
        try:
            for line in buffer.lines():
                try:
                    message = pr.decode(line.rstrip(b"\r"))
                except pr.ProtocolError as error:
                    items.append(error.code)
                else:
                    items.append({"type": message.TYPE, **message.wire_fields()})
            return items
        except pr.ProtocolError as error:
            items.append(error.code)


def robot_items(data: bytes) -> list[object]:
    """What the reference robot makes of ``data``, in the same terms."""
    reader, items = lines.LineReader(), []
    reader.feed(data)
    for line in reader.take():
        try:
            if isinstance(line, lines.LineError):
                raise line
            message = messages.decode(line)
        except lines.LineError as error:
            items.append(error.code)
        else:
            if not message.get("nonce"):
                message.pop("nonce", None)
            items.append(message)
    return items


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(LINE_PIECES, st.sampled_from([b"\n", b"\r\n", b""])), max_size=8))
def test_the_robot_reads_lines_as_the_host_module_does(pieces: list[tuple[bytes, bytes]]) -> None:
    data = b"".join(line + end for line, end in pieces)
    assert robot_items(data) == host_items(data)


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=3000))
def test_random_bytes_give_the_same_verdicts(data: bytes) -> None:
    assert robot_items(data) == host_items(data)


@settings(max_examples=200, deadline=None)
@given(
    st.floats(allow_nan=False, allow_infinity=False),
    st.integers(0, 2**63 - 1),
    st.text(max_size=60).filter(lambda text: not any(0xD800 <= ord(c) < 0xE000 for c in text)),
)
def test_what_the_robot_formats_the_host_reads_back(value: float, seq: int, text: str) -> None:
    sent = [
        {"type": "pose", "stamp": value, "x": value, "y": -value, "heading": 0.5},
        {"type": "heartbeat", "stamp": value},
        {"type": "error", "code": "range", "message": text},
        {"type": "hello", "name": text, "period": 0.1, "nonce": ""},
        {"type": "stopped", "ack": seq},
    ]
    for message in sent:
        line = messages.encode(seq, message)
        assert line.endswith(b"}\n") and b"\n" not in line[:-1]
        decoded = pr.decode(line)
        assert decoded.seq == seq and message["type"] == decoded.TYPE
        for name, value_sent in message.items():
            if name != "type":
                assert getattr(decoded, name) == value_sent, (name, line)


def test_the_limits_are_the_host_modules() -> None:
    assert lines.MAX_LINE_BYTES == pr.MAX_LINE_BYTES
    assert (messages.PROTOCOL_VERSION, messages.MAX_INTEGER) == (
        pr.PROTOCOL_VERSION,
        pr.MAX_INTEGER,
    )
    assert messages.NONCE_BYTES == pr.NONCE_BYTES
    assert authentication.TRAILER_BYTES == auth.TRAILER_BYTES
    assert authentication.MIN_SECRET_BYTES == auth.MIN_SECRET_BYTES


def test_the_reference_robot_answers_the_worked_example_of_the_docs() -> None:
    """With the documented secret and nonces, the robot's two lines are the documented ones
    (its name and period set to the example's)."""
    values, example = documented_example()
    secret = values["secret"].encode()
    robot_nonce = bytes.fromhex(values["robot nonce"])
    core = ProtocolCore(
        "skidnav-sim", 0.1, 1.7, now=0.0, secret=secret, random_bytes=lambda n: robot_nonce
    )
    (_, host_hello), (_, robot_hello), (_, host_cmd), (_, robot_ack) = example
    out, wheels = core.feed(host_hello, now=0.0)
    assert out == robot_hello and wheels is None
    core.seq = 1  # the example's ack is the robot's second line
    out, wheels = core.feed(host_cmd, now=0.01)  # its stamp is the first: the command is fresh
    assert out == robot_ack and wheels == (1.7, 1.7)
    out, wheels = core.feed(host_cmd, now=0.02)  # the same line again: a replay
    assert b'"code":"replay"' in out and wheels == (0.0, 0.0)
    assert out.endswith(b'"}\n') and authentication.MAC_FIELD in out


def test_running_clock_sums_wrapping_ticks_and_defaults_to_monotonic() -> None:
    period = 2**30
    ticks = iter([period - 10, period - 1, 5, 3000, 3000 + period // 2 - 1])
    clock = running_clock(lambda: next(ticks), lambda new, old: (new - old) % period)
    assert [clock(), clock(), clock()] == [0.009, 0.015, 3.01]
    assert clock() == pytest.approx(3.01 + (period // 2 - 1) / 1000)
    assert running_clock() is time.monotonic  # on CPython


@pytest.mark.parametrize("wheels", [(1.7, 1.7), (-1.7, 1.7), (1.0, -0.4), (0.0, 0.0)])
def test_the_simulated_base_takes_the_exact_constant_twist_step(
    wheels: tuple[float, float],
) -> None:
    base = SimulatedBase(0.2, 0.25, 0.3, x_icr=0.04)
    base.pose(10.0)
    base.set_wheels(*wheels)
    for k in range(1, 8):  # read at uneven times: the result depends only on the total
        base.pose(10.0 + 0.9 * k**2 / 49)
    x, y, heading = base.pose(10.9)
    twist = body_velocities(wheels[0], wheels[1], 0.04, 0.0225, 0.06)
    expected = exact_step(0.2, 0.25, 0.3, *twist, 0.9)
    assert (x, y) == pytest.approx(expected[:2], abs=1e-12)
    assert math.isclose(math.remainder(heading - expected[2], 2 * math.pi), 0, abs_tol=1e-12)
    base.stop()
    assert base.pose(20.0) == (x, y, heading)
