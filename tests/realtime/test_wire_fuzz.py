"""Hostile lines against the decoder and the robot firmware: every field of every message type
filled with huge integers, out-of-range and non-finite numbers, wrong types and deep nesting,
and oversized lines. Decoding raises ProtocolError and nothing else; what it accepts is a valid
message; the firmware refuses what the robot cannot do and its pose stays finite."""

from __future__ import annotations

import json
import math
from dataclasses import fields

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from skidnav.realtime.config import ServerOptions
from skidnav.realtime.control.records import EventLog
from skidnav.realtime.link import protocol as pr
from skidnav.realtime.robot_server.simulated_robot import Firmware, SimRobot
from tests.realtime.realtime_helpers import bench_robot

FIELDS = sorted({f.name for cls in pr.MESSAGE_TYPES.values() for f in fields(cls)} | {"v", "type"})

# JSON text fragments: what a peer can put after a key, valid JSON or not
huge_ints = st.integers(min_value=300, max_value=700).map(lambda n: "9" * n)
out_of_range = st.sampled_from(["1e309", "-1e400", "1e-400", "123456789e300", "-0"])
non_finite = st.sampled_from(["NaN", "Infinity", "-Infinity", "nan", "inf"])
wrong_types = st.sampled_from(["true", "false", "null", '"1.7"', "[]", "{}", '"\\ud800"', '""'])
nesting = st.integers(1, 600).map(lambda depth: "[" * depth + "]" * depth)
objects = st.integers(1, 300).map(lambda depth: '{"a":' * depth + "1" + "}" * depth)
numbers = st.one_of(
    st.integers(-(2**70), 2**70).map(str),
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
)
hostile = st.one_of(huge_ints, out_of_range, non_finite, wrong_types, nesting, objects, numbers)


def valid_body(kind: str) -> dict[str, object]:
    """A valid message of ``kind`` as a dict (v, type and every field)."""
    values: dict[str, object] = {"v": pr.PROTOCOL_VERSION, "type": kind, "seq": 3}
    cls = pr.MESSAGE_TYPES[kind]
    values.update({name: 0.5 for name in cls.FLOATS})
    values.update({name: 2 for name in cls.INTS})
    values.update({name: "x" for name in cls.STRS})
    return values


def assert_valid(message: pr.Message) -> None:
    """A decoded message is finite, in range and survives a round trip."""
    for name in message.FLOATS:
        value = getattr(message, name)
        assert isinstance(value, float) and math.isfinite(value)
    for name in (*message.INTS, "seq"):
        assert 0 <= getattr(message, name) <= pr.MAX_INTEGER
    assert pr.decode(pr.encode(message)) == message


@settings(max_examples=400, deadline=None)
@given(
    st.sampled_from(sorted(pr.MESSAGE_TYPES)),
    st.dictionaries(st.sampled_from(FIELDS), hostile, min_size=1, max_size=4),
    st.booleans(),
)
def test_hostile_fields_raise_only_protocol_error(
    kind: str, replaced: dict[str, str], drop_newline: bool
) -> None:
    body = {key: json.dumps(value) for key, value in valid_body(kind).items()}
    body.update(replaced)
    line = ("{" + ",".join(f"{json.dumps(k)}:{v}" for k, v in body.items()) + "}").encode()
    line += b"" if drop_newline else b"\n"
    try:
        message = pr.decode(line)
    except pr.ProtocolError as error:
        assert error.code in ("oversized", "encoding", "json", "field", "version", "unknown_type")
        return
    assert_valid(message)


@pytest.mark.parametrize("kind", sorted(pr.MESSAGE_TYPES))
def test_each_field_with_a_400_digit_integer_is_a_field_error(kind: str) -> None:
    names = [n for n in valid_body(kind) if n not in ("v", "type")]
    for name in names:
        body = {key: json.dumps(value) for key, value in valid_body(kind).items()}
        body[name] = "9" * 400
        line = "{" + ",".join(f"{json.dumps(k)}:{v}" for k, v in body.items()) + "}"
        with pytest.raises(pr.ProtocolError) as caught:
            pr.decode(line.encode())
        assert caught.value.code == "field", name


@settings(max_examples=100, deadline=None)
@given(st.integers(pr.MAX_LINE_BYTES, 4 * pr.MAX_LINE_BYTES), st.sampled_from(b" 9[{x"))
def test_oversized_lines_are_refused_before_parsing(size: int, filler: int) -> None:
    line = b'{"v":2,"type":"stop","seq":1,"pad":"' + bytes([filler]) * size + b'"}'
    with pytest.raises(pr.ProtocolError) as caught:
        pr.decode(line)
    assert caught.value.code == "oversized"


def firmware() -> tuple[Firmware, SimRobot, list[pr.Message]]:
    robot = bench_robot("rough")
    replies: list[pr.Message] = []
    unit = Firmware(robot, ServerOptions(), EventLog(None), lambda b: replies.append(b(0)), 0.0)
    unit.receive([pr.Hello(seq=0, name="fuzz")], 0.0)
    return unit, robot, replies


speeds = st.floats(-1e308, 1e308, allow_nan=False)


@settings(max_examples=150, deadline=None)
@given(st.lists(st.tuples(speeds, speeds, st.floats(1e-3, 1e3)), min_size=1, max_size=8))
def test_firmware_refuses_commands_beyond_the_wheel_limit(
    commands: list[tuple[float, float, float]],
) -> None:
    unit, robot, replies = firmware()
    limit = robot.robot.wheel_speed
    for seq, (left, right, ttl) in enumerate(commands, start=1):
        command = pr.Command(seq=seq, omega_left=left, omega_right=right, stamp=seq, ttl=ttl)
        unit.receive([command], now=float(seq))
        for _ in range(3):
            robot.step()
        assert all(abs(w) <= limit for w in robot.wheels)
        assert all(math.isfinite(v) for v in robot.pose)
        beyond = max(abs(left), abs(right)) > limit
        last = replies[-1]
        if beyond:
            assert isinstance(last, pr.Error) and last.code == "range"
            assert robot.wheels == (0.0, 0.0)
        else:
            assert isinstance(last, pr.Ack) and last.ack == seq
