"""The robot end of the line protocol as a pure function of bytes and time: feed it what was
read and the robot's clock [s]; it returns the bytes to send and the wheel speeds to apply.

:class:`ProtocolCore` is one host's session on the robot: :class:`~.lines.LineReader` frames
the bytes, :class:`~.authentication.RobotKey` checks and seals the lines of an authenticated
link, :mod:`.messages` parses and formats them, :class:`~.rules.Rules` decides, and the core
numbers what the robot sends. It does no I/O and never reads a clock, so it runs unchanged on a
board and in a test that sets the time.

A serial line has no connections: a host that opens the port again just sends a new ``hello``.
With ``restart_on_hello`` a ``hello`` therefore starts a new session (the wheels stop, the
host's ``seq`` and nonce start afresh); the robot's own ``seq`` keeps counting, so lines of the
old session still in the line can never look newer than the new ``hello``.
"""

import os

from .authentication import RobotKey
from .lines import LineError, LineReader
from .messages import NONCE_BYTES, decode, encode
from .rules import Rules

TYPE_CHECKING = False  # MicroPython has no typing module: its names are for the type checker
if TYPE_CHECKING:
    from collections.abc import Callable
    from typing import Any

    from .messages import Message
    from .rules import Effect


class ProtocolCore:
    """One host's session on the robot (see module doc).

    Args:
        name: the robot's name (sent in its ``hello``).
        period: its control period [s] (sent in its ``hello``; :meth:`pose` once per period).
        wheel_limit: the largest wheel speed it runs [rad/s].
        now: the time of connection [s, robot clock].
        secret: the link secret (at least 16 bytes), or None for no authentication.
        max_lease, link_timeout, idle_timeout: the timeouts of :class:`~.rules.Rules` [s].
        restart_on_hello: a ``hello`` starts a new session (serial lines, see module doc).
        random_bytes: the source of nonces, ``random_bytes(n)`` → n random bytes.
        on_note: called as ``on_note(event, fields)`` for every note of the rules, or None.
    """

    def __init__(
        self,
        name: str,
        period: float,
        wheel_limit: float,
        now: float,
        secret: bytes | None = None,
        max_lease: float = 0.5,
        link_timeout: float = 0.5,
        idle_timeout: float = 2.0,
        restart_on_hello: bool = False,
        random_bytes: "Callable[[int], bytes]" = os.urandom,
        on_note: "Callable[[str, dict[str, Any]], None] | None" = None,
    ) -> None:
        self.settings = (name, period, wheel_limit, max_lease, link_timeout, idle_timeout)
        self.secret, self.random_bytes, self.on_note = secret, random_bytes, on_note
        self.restart_on_hello = restart_on_hello
        self.reader = LineReader()
        self.seq = 0  # the next seq the robot sends
        self.hang_up: str | None = None  # why the host is to be dropped
        self.wheels: tuple[float, float] = (0.0, 0.0)  # the speeds last asked for [rad/s]
        self._start(now)

    def _start(self, now: float) -> None:
        """A fresh session: new rules and, with a secret, a new robot nonce."""
        name, period, limit, max_lease, link_timeout, idle_timeout = self.settings
        self.key: RobotKey | None = None
        if self.secret is not None:
            self.key = RobotKey(self.secret, self.random_bytes(NONCE_BYTES))
        nonce = self.key.hello_nonce if self.key is not None else ""
        self.rules = Rules(name, period, limit, now, max_lease, link_timeout, idle_timeout, nonce)

    @property
    def greeted(self) -> bool:
        """True once the host's ``hello`` was answered: poses are due from then on."""
        return self.rules.greeted

    # --- input ----------------------------------------------------------------------------
    def feed(self, data: bytes, now: float) -> "tuple[bytes, tuple[float, float] | None]":
        """Take the bytes read at ``now`` [s] as one batch; returns the bytes to send and the
        wheel speeds to apply [rad/s] (None: unchanged)."""
        self.reader.feed(data)
        out: list[bytes] = []
        wheels = None
        items: list[Any] = []
        for line in self.reader.take():
            if self._starts_session(line):
                wheels = self._apply(self.rules.receive(items, now), out, wheels)
                items = []
                self._start(now)
                wheels = (0.0, 0.0)
            items.append(self._decode(line))
        wheels = self._apply(self.rules.receive(items, now), out, wheels)
        return b"".join(out), wheels

    def _starts_session(self, line: "bytes | LineError") -> bool:
        """With ``restart_on_hello``, True for a host ``hello`` after the session began."""
        rules = self.rules
        if not self.restart_on_hello or isinstance(line, LineError):
            return False
        if not (rules.greeted or rules.last_seq is not None or rules.closed):
            return False
        try:
            return bool(decode(line)["type"] == "hello")
        except LineError:
            return False

    def _decode(self, line: "bytes | LineError") -> "Message | LineError":
        """One line as a message or the error it is; with a secret, its MAC checked once the
        host's ``hello`` gave its nonce (a ``hello`` without one fails ``auth``)."""
        if isinstance(line, LineError):
            return line
        try:
            if self.key is not None and self.key.keyed:
                self.key.verify(line)
            message = decode(line)
            if self.key is not None and not self.key.keyed and message["type"] == "hello":
                self.key.greet(message["nonce"])
        except LineError as error:
            return error
        return message

    # --- time -----------------------------------------------------------------------------
    def watch(self, now: float) -> "tuple[bytes, tuple[float, float] | None]":
        """The robot's own safety at ``now`` [s] (lease, link timeout, idle host), every control
        period before the wheel speeds go to the motors; returns as :meth:`feed`."""
        out: list[bytes] = []
        wheels = self._apply(self.rules.watch(now), out, None)
        return b"".join(out), wheels

    def pose(self, stamp: float, x: float, y: float, heading: float) -> bytes:
        """The ``pose`` line of this period: ``stamp`` [s, robot clock], ``x``, ``y`` [m],
        ``heading`` [rad, counter-clockwise from +x]; nothing before the host's ``hello``."""
        if not self.greeted or self.hang_up is not None:
            return b""
        fields = {"type": "pose", "stamp": stamp, "x": x, "y": y, "heading": heading}
        return self._line(fields)

    # --- output ---------------------------------------------------------------------------
    def _line(self, message: "Message") -> bytes:
        line = encode(self.seq, message)
        self.seq += 1
        if self.key is not None and self.key.keyed:
            line = self.key.seal(line)
        return line

    def _apply(
        self, effects: "list[Effect]", out: list[bytes], wheels: "tuple[float, float] | None"
    ) -> "tuple[float, float] | None":
        """Carry out the rules' effects: lines to ``out``; returns the wheel speeds."""
        for effect in effects:
            kind = effect[0]
            if kind == "send":
                out.append(self._line(effect[1]))
            elif kind == "wheels":
                wheels = (effect[1], effect[2])
            elif kind == "stop":
                wheels = (0.0, 0.0)
            elif kind == "hang_up":
                self.hang_up = effect[1]
            elif self.on_note is not None:
                self.on_note(effect[1], effect[2])
        if wheels is not None:
            self.wheels = wheels
        return wheels
