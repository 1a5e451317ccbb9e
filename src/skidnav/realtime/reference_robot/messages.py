"""The messages of the line protocol, version 2, parsed and formatted on the robot's side
(docs/protocol.md, "Messages").

A message is a ``dict`` with ``"type"``, ``"seq"`` and the fields of its type (:data:`FIELDS`,
in wire order; units SI: rad/s, s, m, rad). :func:`decode` checks a line as the protocol
requires — UTF-8, one JSON object, ``"v": 2``, a known type, every field present with the right
kind (a finite float, an integer in [0, :data:`MAX_INTEGER`], a string) — and raises
:class:`~.lines.LineError` with the code to answer. :func:`encode` writes the compact line a
robot sends. Fields the protocol does not know are ignored.
"""

import json
import math

from .lines import MAX_LINE_BYTES, LineError

TYPE_CHECKING = False  # MicroPython has no typing module: its names are for the type checker
if TYPE_CHECKING:
    from typing import Any

    Message = dict[str, Any]
    """A message: ``"type"``, ``"seq"`` and the fields of its type."""

PROTOCOL_VERSION = 2
MAX_INTEGER = 2**63 - 1
"""Largest ``seq`` or ``ack`` [–]: what a signed 64-bit counter holds."""
NONCE_BYTES = 16
"""Length of a ``hello`` nonce [bytes]; twice as many lowercase hex digits on the wire."""

FIELDS = {
    "hello": (("name", "str"), ("period", "float?"), ("nonce", "str?")),
    "cmd": (
        ("omega_left", "float"),
        ("omega_right", "float"),
        ("stamp", "float"),
        ("ttl", "float"),
    ),
    "ack": (("ack", "int"),),
    "pose": (("stamp", "float"), ("x", "float"), ("y", "float"), ("heading", "float")),
    "stop": (),
    "stopped": (("ack", "int"),),
    "heartbeat": (("stamp", "float"),),
    "error": (("code", "str"), ("message", "str")),
}
"""Each message type's fields in wire order with their kind (``?``: optional)."""
DEFAULTS = {"period": 0.0, "nonce": ""}
"""What an optional field left out of a line stands for."""
_HEX_DIGITS = "0123456789abcdef"


def _json_object(line: bytes) -> "Message":
    """The JSON object of one line (without its newline)."""
    if len(line) >= MAX_LINE_BYTES:
        raise LineError("oversized", "line of " + str(len(line)) + " bytes")
    try:
        text = line.decode("utf-8")
    except ValueError:  # UnicodeError on MicroPython, UnicodeDecodeError on CPython
        raise LineError("encoding", "line is not valid UTF-8") from None
    try:
        body = _loads(text)
    except (ValueError, RuntimeError):  # RuntimeError: nested too deep
        raise LineError("json", "line is not valid JSON") from None
    if not isinstance(body, dict):
        raise LineError("json", "line is not a JSON object")
    return body


def _refuse_constant(name: str) -> None:
    raise ValueError(name + " is not allowed")


def _loads(text: str) -> "Any":
    """JSON ``text`` parsed, ``NaN`` and ``Infinity`` refused as invalid JSON (CPython's parser
    takes them unless told not to; MicroPython's, which takes no options, never does)."""
    try:
        return json.loads(text, parse_constant=_refuse_constant)
    except TypeError:
        return json.loads(text)


def _checked(value: "Any", kind: str) -> object:
    """``value`` as ``kind`` (float, int or str), or None if it is not a valid one."""
    if kind == "float":
        if type(value) not in (int, float):  # bool is neither
            return None
        try:
            number = float(value)
        except OverflowError:  # an integer beyond the double range
            return None
        return number if math.isfinite(number) else None
    if kind == "int":
        return value if type(value) is int and 0 <= value <= MAX_INTEGER else None
    if type(value) is not str:
        return None
    try:
        value.encode("utf-8")  # a JSON escape can spell a lone surrogate, which UTF-8 cannot
    except ValueError:
        return None
    return value


def _field(body: "Message", name: str, kind: str) -> object:
    optional = kind.endswith("?")
    kind = kind.rstrip("?")
    if name not in body:
        if optional:
            return DEFAULTS[name]
        raise LineError("field", str(body.get("type")) + " lacks field '" + name + "'")
    value = _checked(body[name], kind)
    if value is None:
        raise LineError("field", "field '" + name + "' is not a valid " + kind)
    return value


def decode(line: bytes) -> "Message":
    """The message of one line (without its newline); :class:`~.lines.LineError` if the line
    is no valid version-2 message.

    >>> decode(b'{"v":2,"type":"stop","seq":7,"later":"ignored"}')
    {'type': 'stop', 'seq': 7}
    """
    body = _json_object(line)
    version = body.get("v")
    if type(version) is not int or version != PROTOCOL_VERSION:
        seen = "none" if version is None else json.dumps(version)[:20]
        raise LineError(
            "version", "expected protocol version " + str(PROTOCOL_VERSION) + ", got " + seen
        )
    kind = body.get("type")
    if type(kind) is not str or kind not in FIELDS:
        raise LineError("unknown_type", "unknown message type")
    message = {"type": kind, "seq": _field(body, "seq", "int")}
    for name, field_kind in FIELDS[kind]:
        message[name] = _field(body, name, field_kind)
    _check_values(message)
    return message


def _check_values(message: "Message") -> None:
    """The rules on values beyond their kind: a ``cmd``'s ``ttl`` > 0, a nonce of hex digits."""
    if message["type"] == "cmd" and not message["ttl"] > 0:
        raise LineError("field", "field 'ttl' must be > 0 s, got " + repr(message["ttl"]))
    nonce = message.get("nonce", "")
    if nonce and not (len(nonce) == 2 * NONCE_BYTES and all(c in _HEX_DIGITS for c in nonce)):
        raise LineError("field", "field 'nonce' must be " + str(2 * NONCE_BYTES) + " hex digits")


def _value_text(value: object) -> str:
    if type(value) is float:
        if not math.isfinite(value):
            raise ValueError("a message holds a non-finite number")
        return repr(value)
    if type(value) is int:
        return str(value)
    return json.dumps(value)


def encode(seq: int, message: "Message") -> bytes:
    """The line (``\\n``-terminated) of ``message`` numbered ``seq``: its fields in wire
    order, an empty ``nonce`` left out; ValueError for a non-finite number.

    >>> encode(3, {"type": "ack", "ack": 1})
    b'{"v":2,"type":"ack","seq":3,"ack":1}\\n'
    """
    kind = message["type"]
    parts = ['{"v":' + str(PROTOCOL_VERSION), '"type":' + json.dumps(kind), '"seq":' + str(seq)]
    for name, field_kind in FIELDS[kind]:
        value = message.get(name, DEFAULTS.get(name))
        if field_kind.endswith("?") and name == "nonce" and not value:
            continue
        if field_kind.startswith("float"):
            value = float(value)
        parts.append(json.dumps(name) + ":" + _value_text(value))
    return (",".join(parts) + "}\n").encode("utf-8")
