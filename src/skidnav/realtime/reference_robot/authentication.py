"""The robot's side of an authenticated link (docs/protocol.md, "Authentication").

Both ends share a secret of at least :data:`MIN_SECRET_BYTES`. Each connection, the host's
``hello`` brings its nonce and the robot answers with its own; from the robot's ``hello`` on,
every line either side sends ends in ``,"mac":"<64 hex digits>"}``: HMAC-SHA256 (RFC 2104, see
:mod:`.hmac_sha256`) keyed by the secret over the direction byte (``H`` on what the host sends,
``R`` on what the robot sends), the host nonce, the robot nonce (16 raw bytes each) and the
line's bytes before ``,"mac":"``.
"""

import binascii

from .hmac_sha256 import hmac_sha256_hex, same_bytes
from .lines import MAX_LINE_BYTES, LineError
from .messages import NONCE_BYTES

MIN_SECRET_BYTES = 16
"""Shortest accepted secret [bytes]."""
MAC_FIELD = b',"mac":"'
MAC_HEX_DIGITS = 64
TRAILER_BYTES = len(MAC_FIELD) + MAC_HEX_DIGITS + 2
"""Length of ``,"mac":"<64 hex digits>"}`` at the end of an authenticated line [bytes]."""
FROM_HOST, FROM_ROBOT = b"H", b"R"


class RobotKey:
    """The robot's side of one authenticated connection.

    Args:
        secret: the shared secret (ValueError if shorter than :data:`MIN_SECRET_BYTES`).
        nonce: this connection's robot nonce, :data:`~.messages.NONCE_BYTES` fresh random
            bytes (from a hardware random source on a board, never a clock-seeded PRNG).
    """

    def __init__(self, secret: bytes, nonce: bytes) -> None:
        if len(secret) < MIN_SECRET_BYTES:
            raise ValueError(
                "expected a link secret of at least "
                + str(MIN_SECRET_BYTES)
                + " bytes, got "
                + str(len(secret))
            )
        if len(nonce) != NONCE_BYTES:
            raise ValueError("expected a nonce of " + str(NONCE_BYTES) + " bytes")
        self._secret = secret
        self.nonce = nonce
        self._host_nonce = b""

    @property
    def hello_nonce(self) -> str:
        """The robot nonce as its ``hello`` carries it (lowercase hex)."""
        return binascii.hexlify(self.nonce).decode()

    @property
    def keyed(self) -> bool:
        """True once the host's nonce is known: every line is authenticated from then on."""
        return bool(self._host_nonce)

    def greet(self, host_nonce: str) -> None:
        """Take the nonce of the host's ``hello`` (hex, checked by the decoder); LineError
        ``auth`` if it has none: that host does not authenticate."""
        if not host_nonce:
            raise LineError("auth", "the peer's hello has no nonce: it does not authenticate")
        self._host_nonce = binascii.unhexlify(host_nonce)

    def _mac(self, direction: bytes, body: bytes) -> bytes:
        message = direction + self._host_nonce + self.nonce + body
        return hmac_sha256_hex(self._secret, message).encode()

    def seal(self, line: bytes) -> bytes:
        """``line`` (one formatted message ending in ``}\\n``) with the robot's MAC as its last
        field; ValueError if that makes it longer than a line may be."""
        body = line[:-2]
        sealed = body + MAC_FIELD + self._mac(FROM_ROBOT, body) + b'"}\n'
        if len(sealed) > MAX_LINE_BYTES:
            raise ValueError("an authenticated line of " + str(len(sealed)) + " bytes")
        return sealed

    def verify(self, line: bytes) -> None:
        """Check the host's MAC on a received line (without its newline); LineError ``auth``
        if it has none or a wrong one."""
        body, trailer = line[:-TRAILER_BYTES], line[-TRAILER_BYTES:]
        shaped = len(line) > TRAILER_BYTES and trailer.startswith(MAC_FIELD)
        if not (shaped and trailer.endswith(b'"}')):
            raise LineError("auth", "line without a MAC")
        if not same_bytes(self._mac(FROM_HOST, body), trailer[len(MAC_FIELD) : -2]):
            raise LineError("auth", "wrong MAC")
