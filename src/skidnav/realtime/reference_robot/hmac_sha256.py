"""HMAC-SHA256 (RFC 2104) over ``hashlib.sha256`` alone, for boards without an ``hmac`` module.

RFC 2104 with the SHA-256 block of :data:`BLOCK_BYTES` bytes: a key longer than a block is
first hashed; the key, zero-padded to a block, is XORed with 0x36 for the inner hash and with
0x5c for the outer one, and ``HMAC(K, m) = H((K ⊕ opad) ‖ H((K ⊕ ipad) ‖ m))``. Only
``update`` and ``digest`` of the hash object are used (MicroPython's has no ``copy``), so it
runs unchanged on MicroPython.

>>> hmac_sha256_hex(b"key", b"The quick brown fox jumps over the lazy dog")[:16]
'f7bc83f430538424'
"""

import binascii
import hashlib

BLOCK_BYTES = 64
"""Block length of SHA-256 [bytes]; keys are padded (or first hashed) to it."""
DIGEST_BYTES = 32
"""Length of a SHA-256 digest [bytes]."""


def _padded_key(key: bytes) -> bytes:
    """``key`` as one block: hashed if longer, then zero-padded."""
    if len(key) > BLOCK_BYTES:
        key = hashlib.sha256(key).digest()
    return bytes(key) + bytes(BLOCK_BYTES - len(key))


def hmac_sha256(key: bytes, message: bytes) -> bytes:
    """The HMAC-SHA256 of ``message`` under ``key`` (RFC 2104): :data:`DIGEST_BYTES` bytes."""
    block = _padded_key(key)
    inner = hashlib.sha256(bytes(byte ^ 0x36 for byte in block))
    inner.update(message)
    outer = hashlib.sha256(bytes(byte ^ 0x5C for byte in block))
    outer.update(inner.digest())
    return outer.digest()


def hmac_sha256_hex(key: bytes, message: bytes) -> str:
    """:func:`hmac_sha256` as 2 × :data:`DIGEST_BYTES` lowercase hex digits."""
    return binascii.hexlify(hmac_sha256(key, message)).decode()


def same_bytes(first: bytes, second: bytes) -> bool:
    """True if the two byte strings are equal, in a time that does not depend on where they
    differ (a MAC compared byte by byte with an early exit would leak how much of it is right)."""
    if len(first) != len(second):
        return False
    difference = 0
    for index in range(len(first)):
        difference |= first[index] ^ second[index]
    return difference == 0
