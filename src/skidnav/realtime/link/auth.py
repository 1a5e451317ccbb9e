"""Authentication of the robot line protocol (docs/protocol.md, "Authentication").

With a shared secret on both ends, each side draws a fresh 16-byte nonce per connection and sends
it in its ``hello`` (``"nonce"``, 32 lowercase hex digits). From then on every line a side sends
ends with a ``"mac"`` field, HMAC-SHA256 keyed by the secret over::

    direction (1 byte: b"H" host → robot, b"R" robot → host)
    ‖ host nonce (16 bytes) ‖ robot nonce (16 bytes)
    ‖ the line's bytes before ',"mac":"'

as 64 lowercase hex digits, and nothing after it but ``"}`` and the newline. The robot's
``hello`` is the first line it authenticates (it proves the robot knows the secret and answers
this host's fresh nonce); the host's first ``cmd`` or ``heartbeat`` proves the host. Both nonces
and the direction are in every MAC, so no line can be replayed on another connection or sent back
to its sender; the ``seq`` inside it, which must increase, stops replays on the same connection.

:class:`Session` is one side of one connection; :func:`load_secret` reads the secret from a file
or the environment (never from the command line, which other users of the machine can see).
"""

from __future__ import annotations

import hashlib
import hmac
import secrets

from skidnav.realtime.link.protocol import MAX_LINE_BYTES, NONCE_BYTES, ProtocolError
from skidnav.realtime.reference_robot.authentication import (
    FROM_HOST,
    FROM_ROBOT,
    MAC_FIELD,
    MAC_HEX_DIGITS,
    MIN_SECRET_BYTES,
)
from skidnav.realtime.reference_robot.secret_file import (
    MAX_SECRET_BYTES,
    SECRET_ENV,
    load_secret,
    require_secret,
)

__all__ = [
    "MAX_SECRET_BYTES", "MIN_SECRET_BYTES", "SECRET_ENV", "Session", "load_secret", "mac",
    "require_secret",
]  # fmt: skip

TRAILER_BYTES = len(MAC_FIELD) + MAC_HEX_DIGITS + len(b'"}')
"""Bytes of ``,"mac":"<64 hex digits>"}`` at the end of an authenticated line (newline aside)."""
HOST, ROBOT = FROM_HOST, FROM_ROBOT
"""The direction bytes: what the host sends, what the robot sends."""


def mac(secret: bytes, direction: bytes, host_nonce: bytes, robot_nonce: bytes, body: bytes) -> str:
    """The MAC of one line (see module doc): 64 lowercase hex digits.

    >>> mac(b"0123456789abcdef", HOST, bytes(16), bytes(16), b'{"v":2,"type":"stop","seq":1')[:16]
    '99dcfde4a4878ab7'
    """
    message = direction + host_nonce + robot_nonce + body
    return hmac.new(secret, message, hashlib.sha256).hexdigest()


class Session:
    """One side of one authenticated connection.

    Args:
        secret: the shared secret (at least :data:`MIN_SECRET_BYTES`).
        side: ``"host"`` or ``"robot"``.
        nonce: this side's nonce (16 bytes); a fresh random one by default (a fixed one only
            reproduces the worked example of docs/protocol.md).
    """

    def __init__(self, secret: bytes, side: str, nonce: bytes | None = None) -> None:
        if side not in ("host", "robot"):
            raise ValueError(f"expected side 'host' or 'robot', got {side!r}")
        self._secret = require_secret(secret)
        self.nonce = nonce if nonce is not None else secrets.token_bytes(NONCE_BYTES)
        self._host = side == "host"
        self._peer: bytes | None = None

    @property
    def hello_nonce(self) -> str:
        """This side's nonce as sent in its ``hello``."""
        return self.nonce.hex()

    @property
    def keyed(self) -> bool:
        """True once the peer's nonce is known: every line is authenticated from then on."""
        return self._peer is not None

    def greet(self, peer_nonce: str) -> None:
        """Take the nonce of the peer's ``hello``; ProtocolError ``auth`` if it sent none."""
        if not peer_nonce:
            raise ProtocolError("auth", "the peer's hello has no nonce: it does not authenticate")
        self._peer = bytes.fromhex(peer_nonce)  # checked as 32 hex digits by the decoder

    def _mac(self, direction: bytes, body: bytes) -> str:
        assert self._peer is not None, "greet the peer first"
        host, robot = (self.nonce, self._peer) if self._host else (self._peer, self.nonce)
        return mac(self._secret, direction, host, robot, body)

    def seal(self, line: bytes) -> bytes:
        """``line`` (one encoded message, ``}\\n``-terminated) with this side's MAC appended;
        ProtocolError ``oversized`` if that makes it too long."""
        body = line.rstrip(b"\n")[:-1]
        tag = self._mac(HOST if self._host else ROBOT, body)
        sealed = body + MAC_FIELD + tag.encode("ascii") + b'"}\n'
        if len(sealed) > MAX_LINE_BYTES:
            raise ProtocolError("oversized", f"authenticated line of {len(sealed)} bytes")
        return sealed

    def verify(self, line: bytes) -> None:
        """Check the MAC of a received line (newline removed, a ``\\r`` tolerated); ProtocolError
        ``auth`` if it has none or a wrong one."""
        text = line[:-1] if line.endswith(b"\r") else line
        body, trailer = text[:-TRAILER_BYTES], text[-TRAILER_BYTES:]
        shaped = len(text) > TRAILER_BYTES and trailer.startswith(MAC_FIELD)
        if not (shaped and trailer.endswith(b'"}')):
            raise ProtocolError("auth", "line without a MAC")
        expected = self._mac(ROBOT if self._host else HOST, body).encode("ascii")
        if not hmac.compare_digest(expected, trailer[len(MAC_FIELD) : -2]):
            raise ProtocolError("auth", "wrong MAC")
