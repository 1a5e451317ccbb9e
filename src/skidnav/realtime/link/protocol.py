"""The skidnav robot line protocol, version 2 (docs/protocol.md).

One message is one JSON object on one UTF-8 line ending in ``\\n``, at most :data:`MAX_LINE_BYTES`
bytes including the newline. Every message carries ``"v"`` (protocol version), ``"type"`` and
``"seq"`` (the sender's own counter, a non-negative integer that increases by one per message).
The same messages travel over TCP, a serial line or a pty, so a microcontroller only needs a
line reader, a JSON formatter and a float parser. With a shared secret, both ``hello`` messages
carry a ``nonce`` and every later line ends with a ``mac`` field (:mod:`.auth`).

Message types and their fields (units SI):

==============  =========  ==========================================================
type            direction  fields besides v, type, seq
==============  =========  ==========================================================
``hello``       both       ``name`` (str), ``period`` (s, robot → host; 0 from host),
                           ``nonce`` (32 hex digits; only with authentication)
``cmd``         host→robot ``omega_left``, ``omega_right`` (rad/s), ``stamp`` (host clock, s),
                           ``ttl`` (s > 0): held at most ``ttl`` after arrival (the robot
                           bounds it), not run if older than ``ttl`` when read
``ack``         robot→host ``ack`` (seq of the acknowledged ``cmd``)
``pose``        robot→host ``stamp`` (robot clock, s), ``x``, ``y`` (m), ``heading`` (rad)
``stop``        host→robot (none): zero both wheels now
``stopped``     robot→host ``ack`` (seq of the ``stop``): the wheels are at zero
``heartbeat``   both       ``stamp`` (sender clock, s)
``error``       both       ``code`` (str), ``message`` (str)
==============  =========  ==========================================================

Any line that is not valid UTF-8 JSON, is too long, lacks a field, has a field of the wrong type,
a number that is not finite or out of range, another version or an unknown type raises
:class:`ProtocolError` — the only exception :func:`decode` and :class:`LineBuffer` raise.

:class:`HostClock` is the robot's half of the stall rule (docs/protocol.md, "Stale commands"): it
maps the host's ``stamp`` onto the robot's own clock, so a command that waited in a buffer while
either side stalled is recognised as stale however late it is read, while a step of the host's
clock is forgotten by the next message. It lives with the reference robot
(:mod:`skidnav.realtime.reference_robot.host_clock`), whose rules the sim server shares.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from dataclasses import asdict, dataclass
from typing import Any, ClassVar

from skidnav.errors import UserError
from skidnav.realtime.reference_robot.host_clock import HostClock as HostClock

PROTOCOL_VERSION = 2
MAX_LINE_BYTES = 1024
"""Longest accepted line [bytes], the terminating newline included."""
MAX_INTEGER = 2**63 - 1
"""Largest accepted integer field (``seq``, ``ack``): what a signed 64-bit counter holds."""
NONCE_BYTES = 16
"""Length of a ``hello`` nonce [bytes]; on the wire, twice as many lowercase hex digits."""


class ProtocolError(UserError):
    """A line that is not a valid protocol message.

    Attributes:
        code: ``"oversized"``, ``"encoding"``, ``"json"``, ``"field"``, ``"version"`` or
            ``"unknown_type"`` (the line cannot be parsed), ``"auth"`` (its MAC is missing or
            wrong, :mod:`.auth`) or ``"replay"`` (its ``seq`` does not increase) — the ``code``
            of the ``error`` reply a peer may send back. (Robots also send ``"state"``,
            ``"busy"``, ``"range"`` and ``"expired"``; see :class:`Error`.)
    """

    def __init__(self, code: str, message: str) -> None:
        super().__init__(message)
        self.code = code


@dataclass(frozen=True)
class Message:
    """Base of every message: ``seq`` is the sender's message counter (≥ 0)."""

    TYPE: ClassVar[str] = ""
    FLOATS: ClassVar[tuple[str, ...]] = ()
    INTS: ClassVar[tuple[str, ...]] = ()
    STRS: ClassVar[tuple[str, ...]] = ()
    OPTIONAL: ClassVar[tuple[str, ...]] = ()
    """Fields a line may leave out (they take their default)."""
    seq: int

    def wire_fields(self) -> dict[str, Any]:
        """The fields as sent (all of them; :class:`Hello` leaves out an empty nonce)."""
        return asdict(self)


@dataclass(frozen=True)
class Hello(Message):
    """Handshake: the host sends it first; the robot answers with its own, ``period`` [s] > 0.
    ``nonce``: this side's fresh :data:`NONCE_BYTES` in lowercase hex with authentication
    (:mod:`.auth`), empty (and left off the line) without; anything else is a ProtocolError."""

    TYPE: ClassVar[str] = "hello"
    FLOATS: ClassVar[tuple[str, ...]] = ("period",)
    STRS: ClassVar[tuple[str, ...]] = ("name", "nonce")
    OPTIONAL: ClassVar[tuple[str, ...]] = ("period", "nonce")
    name: str
    period: float = 0.0
    nonce: str = ""

    def __post_init__(self) -> None:
        digits = set("0123456789abcdef")
        if self.nonce and not (len(self.nonce) == 2 * NONCE_BYTES and set(self.nonce) <= digits):
            raise ProtocolError("field", f"field 'nonce' must be {2 * NONCE_BYTES} hex digits")

    def wire_fields(self) -> dict[str, Any]:
        fields = asdict(self)
        if not self.nonce:
            del fields["nonce"]
        return fields


@dataclass(frozen=True)
class Command(Message):
    """Wheel angular speeds [rad/s] to hold until the next command, for at most ``ttl`` [s]
    after it arrived (a robot bounds ``ttl`` by its own largest lease); ``stamp`` [s] is the
    host's clock at sending, by which the robot refuses a command older than ``ttl`` when read;
    ``ttl`` > 0 (ProtocolError otherwise)."""

    TYPE: ClassVar[str] = "cmd"
    FLOATS: ClassVar[tuple[str, ...]] = ("omega_left", "omega_right", "stamp", "ttl")
    omega_left: float
    omega_right: float
    stamp: float
    ttl: float

    def __post_init__(self) -> None:
        if not self.ttl > 0:
            raise ProtocolError("field", f"field 'ttl' must be > 0 s, got {self.ttl}")


@dataclass(frozen=True)
class Ack(Message):
    """The robot received command number ``ack``."""

    TYPE: ClassVar[str] = "ack"
    INTS: ClassVar[tuple[str, ...]] = ("ack",)
    ack: int


@dataclass(frozen=True)
class PoseReport(Message):
    """A pose measurement: ``stamp`` [s, robot clock], x, y [m], heading [rad, CCW from +x]."""

    TYPE: ClassVar[str] = "pose"
    FLOATS: ClassVar[tuple[str, ...]] = ("stamp", "x", "y", "heading")
    stamp: float
    x: float
    y: float
    heading: float


@dataclass(frozen=True)
class Stop(Message):
    """Zero both wheels at once, bypassing any command queue."""

    TYPE: ClassVar[str] = "stop"


@dataclass(frozen=True)
class Stopped(Message):
    """The wheels are at zero after stop number ``ack``."""

    TYPE: ClassVar[str] = "stopped"
    INTS: ClassVar[tuple[str, ...]] = ("ack",)
    ack: int


@dataclass(frozen=True)
class Heartbeat(Message):
    """Keep-alive; ``stamp`` is the sender's clock [s]."""

    TYPE: ClassVar[str] = "heartbeat"
    FLOATS: ClassVar[tuple[str, ...]] = ("stamp",)
    stamp: float


@dataclass(frozen=True)
class Error(Message):
    """A problem report; ``code`` as :attr:`ProtocolError.code`, or from a robot ``"state"``
    (a message at the wrong time), ``"busy"`` (another host is connected), ``"range"`` (a
    command beyond the wheel-speed limit) or ``"expired"`` (a command read after its deadline)."""

    TYPE: ClassVar[str] = "error"
    STRS: ClassVar[tuple[str, ...]] = ("code", "message")
    code: str
    message: str


MESSAGE_TYPES: dict[str, type[Message]] = {
    cls.TYPE: cls for cls in (Hello, Command, Ack, PoseReport, Stop, Stopped, Heartbeat, Error)
}


def encode(message: Message) -> bytes:
    """One protocol line (UTF-8, ``\\n``-terminated) for ``message``.

    Raises ProtocolError if the result would exceed :data:`MAX_LINE_BYTES` or holds a
    non-finite number.

    >>> encode(Command(seq=3, omega_left=1.7, omega_right=-1.7, stamp=52.5, ttl=0.5))
    b'{"v":2,"type":"cmd","seq":3,"omega_left":1.7,"omega_right":-1.7,"stamp":52.5,"ttl":0.5}\\n'
    """
    body: dict[str, Any] = {"v": PROTOCOL_VERSION, "type": message.TYPE}
    body.update(message.wire_fields())
    try:
        text = json.dumps(body, separators=(",", ":"), ensure_ascii=False, allow_nan=False)
        line = text.encode("utf-8") + b"\n"
    except ValueError as error:  # a non-finite number, or a lone surrogate in a string
        raise ProtocolError("field", f"cannot encode {message.TYPE}: {error}") from None
    if len(line) > MAX_LINE_BYTES:
        raise ProtocolError("oversized", f"{message.TYPE} line of {len(line)} bytes")
    return line


def _parse_json(line: bytes) -> dict[str, Any]:
    """The JSON object of one line (newline optional)."""
    if len(line) > MAX_LINE_BYTES:
        raise ProtocolError("oversized", f"line of {len(line)} bytes > {MAX_LINE_BYTES}")
    try:
        text = line.decode("utf-8")
    except UnicodeDecodeError:
        raise ProtocolError("encoding", "line is not valid UTF-8") from None
    try:
        body = json.loads(text, parse_constant=_reject_constant)
    except (ValueError, RecursionError):
        raise ProtocolError("json", "line is not valid JSON") from None
    if not isinstance(body, dict):
        raise ProtocolError("json", "line is not a JSON object")
    return body


def _reject_constant(name: str) -> float:
    raise ValueError(f"{name} is not allowed")


def _field(body: dict[str, Any], name: str, kind: str) -> Any:
    """Field ``name`` checked as ``kind``: "float" (a finite JSON number, as float), "int" (an
    integer in [0, :data:`MAX_INTEGER`]) or "str" (text without lone surrogates)."""
    if name not in body:
        raise ProtocolError("field", f"{body.get('type')} lacks field {name!r}")
    value = body[name]
    checked = {"str": _as_str, "int": _as_int}.get(kind, _as_float)(value)
    if checked is None:
        raise ProtocolError("field", f"field {name!r} is not a valid {kind}")
    return checked


def _as_float(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    try:
        number = float(value)  # an integer beyond ±1.8e308 overflows
    except OverflowError:
        return None
    return number if math.isfinite(number) else None


def _as_int(value: Any) -> int | None:
    ok = isinstance(value, int) and not isinstance(value, bool) and 0 <= value <= MAX_INTEGER
    return value if ok else None


def _as_str(value: Any) -> str | None:
    if not isinstance(value, str):
        return None
    try:
        value.encode("utf-8")  # JSON escapes can spell lone surrogates, which UTF-8 cannot
    except UnicodeEncodeError:
        return None
    return value


def _brief(value: Any) -> str:
    """``value`` as JSON, cut to 20 characters (for error messages)."""
    text = json.dumps(value, ensure_ascii=True)
    return text if len(text) <= 20 else text[:17] + "..."


def decode(line: bytes) -> Message:
    """Parse one line (with or without its newline) into a message.

    Raises:
        ProtocolError: for anything that is not a valid version-2 message; never anything else.

    >>> decode(b'{"v":2,"type":"stop","seq":7}\\n')
    Stop(seq=7)
    """
    body = _parse_json(line.rstrip(b"\n"))
    version = body.get("v")
    if type(version) is not int or version != PROTOCOL_VERSION:
        seen = "none" if version is None else _brief(version)
        raise ProtocolError("version", f"expected protocol version {PROTOCOL_VERSION}, got {seen}")
    kind = body.get("type")
    cls = MESSAGE_TYPES.get(kind) if isinstance(kind, str) else None
    if cls is None:
        raise ProtocolError("unknown_type", "unknown message type")
    fields: dict[str, Any] = {"seq": _field(body, "seq", "int")}
    for names, kind_name in ((cls.FLOATS, "float"), (cls.INTS, "int"), (cls.STRS, "str")):
        for name in names:
            if name in cls.OPTIONAL and name not in body:
                continue
            fields[name] = _field(body, name, kind_name)
    return cls(**fields)  # may raise ProtocolError (Command.ttl, Hello.nonce)


class LineBuffer:
    """Splits a byte stream into protocol lines, enforcing :data:`MAX_LINE_BYTES`.

    Feed raw bytes with :meth:`feed`; iterate the completed lines with :meth:`lines`. A line that
    grows past the limit is discarded up to its newline and reported once as a ProtocolError
    ("oversized"); the stream then resynchronizes on the next line.
    """

    def __init__(self, max_line: int = MAX_LINE_BYTES) -> None:
        self._max_line = max_line
        self._pending = bytearray()
        self._discarding = False

    def feed(self, data: bytes) -> None:
        """Append received bytes."""
        self._pending += data

    def lines(self) -> Iterator[bytes]:
        """Yield each complete line (without newline); raises ProtocolError on an oversized one.

        After an error, call again to continue with the following lines.
        """
        while True:
            end = self._pending.find(b"\n")
            if self._discarding:
                if end < 0:
                    self._pending.clear()
                    return
                del self._pending[: end + 1]
                self._discarding = False
                continue
            if end < 0:
                if len(self._pending) >= self._max_line:
                    self._pending.clear()
                    self._discarding = True
                    raise ProtocolError("oversized", f"line longer than {self._max_line} bytes")
                return
            line = bytes(self._pending[:end])
            del self._pending[: end + 1]
            if end + 1 > self._max_line:
                raise ProtocolError("oversized", f"line longer than {self._max_line} bytes")
            yield line
