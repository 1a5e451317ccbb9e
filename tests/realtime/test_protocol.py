"""The line protocol: round trips, every rejection, the line buffer, and fuzzing."""

from __future__ import annotations

import contextlib
import json

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from skidnav.realtime.link import protocol as pr

EXAMPLES = [
    pr.Hello(seq=0, name="skidnav"),
    pr.Hello(seq=1, name="robot-7", period=0.1),
    pr.Command(seq=2, omega_left=1.7, omega_right=-1.7, stamp=812.5, ttl=0.1),
    pr.Ack(seq=3, ack=2),
    pr.PoseReport(seq=4, stamp=12.5, x=0.31, y=0.2, heading=-3.0),
    pr.Stop(seq=5),
    pr.Stopped(seq=6, ack=5),
    pr.Heartbeat(seq=7, stamp=1.0),
    pr.Error(seq=8, code="json", message="line is not valid JSON ✗"),
]


@pytest.mark.parametrize("message", EXAMPLES, ids=lambda m: m.TYPE)
def test_every_message_round_trips(message: pr.Message) -> None:
    line = pr.encode(message)
    assert line.endswith(b"\n") and line.count(b"\n") == 1
    assert pr.decode(line) == message
    body = json.loads(line)
    assert body["v"] == pr.PROTOCOL_VERSION and body["type"] == message.TYPE


CMD = '{"v":2,"type":"cmd","seq":1,"stamp":5,"ttl":0.5,'


def test_integers_are_accepted_as_floats() -> None:
    message = pr.decode((CMD + '"omega_left":0,"omega_right":2}').encode())
    assert message == pr.Command(seq=1, omega_left=0.0, omega_right=2.0, stamp=5.0, ttl=0.5)
    assert isinstance(message, pr.Command) and isinstance(message.omega_left, float)


def test_version_1_lines_are_refused_naming_both_versions() -> None:
    with pytest.raises(pr.ProtocolError) as caught:
        pr.decode(b'{"v":1,"type":"cmd","seq":1,"omega_left":0,"omega_right":2}')
    assert caught.value.code == "version"
    assert str(caught.value) == "expected protocol version 2, got 1"


@pytest.mark.parametrize(
    ("line", "code"),
    [
        (b"\xff\xfe{}", "encoding"),
        (b"not json", "json"),
        (b"[1, 2]", "json"),
        (b'{"v":2,"type":"stop","seq":1', "json"),
        (b'{"v":1,"type":"stop","seq":1}', "version"),
        (b'{"v":2.0,"type":"stop","seq":1}', "version"),
        (b'{"v":true,"type":"stop","seq":1}', "version"),
        (b'{"type":"stop","seq":1}', "version"),
        (b'{"v":2,"type":"fly","seq":1}', "unknown_type"),
        (b'{"v":2,"type":7,"seq":1}', "unknown_type"),
        (b'{"v":2,"type":"stop"}', "field"),
        (b'{"v":2,"type":"stop","seq":-1}', "field"),
        (b'{"v":2,"type":"stop","seq":1.5}', "field"),
        (b'{"v":2,"type":"stop","seq":9223372036854775808}', "field"),
        ((CMD + '"omega_left":1}').encode(), "field"),
        ((CMD + '"omega_left":true,"omega_right":1}').encode(), "field"),
        ((CMD + '"omega_left":NaN,"omega_right":1}').encode(), "json"),
        ((CMD + '"omega_left":1e999,"omega_right":1}').encode(), "field"),
        ((CMD + '"omega_left":' + "9" * 400 + ',"omega_right":1}').encode(), "field"),
        ((CMD + '"omega_left":"1","omega_right":1}').encode(), "field"),
        (b'{"v":2,"type":"cmd","seq":1,"omega_left":0,"omega_right":0}', "field"),
        (b'{"v":2,"type":"cmd","seq":1,"stamp":0,"ttl":0,"omega_left":0,"omega_right":0}', "field"),
        (b'{"v":2,"type":"error","seq":1,"code":3,"message":"x"}', "field"),
        (b'{"v":2,"type":"error","seq":1,"code":"\\ud800","message":"x"}', "field"),
        (b"[" * 1000, "json"),
        (b"{" + b" " * pr.MAX_LINE_BYTES + b"}", "oversized"),
    ],
)
def test_bad_lines_raise_protocol_error_with_code(line: bytes, code: str) -> None:
    with pytest.raises(pr.ProtocolError) as caught:
        pr.decode(line)
    assert caught.value.code == code


def test_encode_refuses_oversized_and_non_finite() -> None:
    with pytest.raises(pr.ProtocolError) as caught:
        pr.encode(pr.Error(seq=0, code="x", message="m" * pr.MAX_LINE_BYTES))
    assert caught.value.code == "oversized"
    with pytest.raises(pr.ProtocolError):
        pr.encode(pr.Command(seq=0, omega_left=float("nan"), omega_right=0.0, stamp=0, ttl=1))


def test_line_buffer_joins_split_lines_and_resyncs_after_oversized() -> None:
    buffer = pr.LineBuffer(max_line=64)
    stop = pr.encode(pr.Stop(seq=1))
    buffer.feed(stop[:5])
    assert list(buffer.lines()) == []
    buffer.feed(stop[5:] + b"x" * 100)
    lines = buffer.lines()
    assert next(lines) == stop[:-1]
    with pytest.raises(pr.ProtocolError) as caught:
        next(lines)
    assert caught.value.code == "oversized"
    buffer.feed(b"y" * 50 + b"\n" + stop)  # the rest of the oversized line is skipped
    assert [pr.decode(line) for line in buffer.lines()] == [pr.Stop(seq=1)]


@settings(max_examples=400, deadline=None)
@given(st.binary(max_size=2 * pr.MAX_LINE_BYTES))
def test_decode_of_arbitrary_bytes_raises_only_protocol_error(data: bytes) -> None:
    try:
        message = pr.decode(data)
    except pr.ProtocolError:
        return
    assert isinstance(message, pr.Message)


json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=20),
    lambda children: (
        st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=8), children, max_size=4)
    ),
    max_leaves=10,
)


@settings(max_examples=150, deadline=None)
@given(
    st.sampled_from(sorted(pr.MESSAGE_TYPES)),
    st.dictionaries(
        st.sampled_from(["v", "seq", "omega_left", "omega_right", "x", "stamp", "ack", "code"]),
        json_values,
    ),
)
def test_decode_of_arbitrary_json_objects_raises_only_protocol_error(
    kind: str, fields: dict[str, object]
) -> None:
    line = json.dumps({"type": kind, **fields}).encode()
    with contextlib.suppress(pr.ProtocolError):
        pr.decode(line)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.binary(max_size=300), max_size=12))
def test_line_buffer_never_raises_anything_else_and_caps_lines(chunks: list[bytes]) -> None:
    buffer = pr.LineBuffer(max_line=128)
    for chunk in chunks:
        buffer.feed(chunk)
        while True:
            try:
                for line in buffer.lines():
                    assert len(line) < 128 and b"\n" not in line
                break
            except pr.ProtocolError as error:
                assert error.code == "oversized"


finite = st.floats(allow_nan=False, allow_infinity=False, width=64)


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 2**53), finite, finite, finite, finite)
def test_pose_round_trip_is_exact(seq: int, stamp: float, x: float, y: float, h: float) -> None:
    message = pr.PoseReport(seq=seq, stamp=stamp, x=x, y=y, heading=h)
    assert pr.decode(pr.encode(message)) == message
