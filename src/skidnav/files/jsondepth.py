"""How deeply a JSON text nests, found before it is parsed, in memory linear in its length.

:func:`json_depth` is the nesting pre-check of :func:`skidnav.files.saved.parse_json`: a document
nested thousands of levels deep is refused before Python's parser recurses into it. It scans the
UTF-8 bytes in blocks of :data:`BLOCK_BYTES` with a small state machine vectorised over each
block — inside a string or not, whether the previous byte was an unfinished escape, the current
depth — so its working memory is a few times the block, whatever the length of the text or of
its strings (a regular expression over a string literal would keep state per character).

Per block: a byte is escaped when the run of backslashes just before it has odd length (a run
may continue from the previous block); an unescaped ``"`` toggles the string state; ``[`` and
``{`` outside strings go one level down, ``]`` and ``}`` one up. Only the bytes ``"``, ``\\``,
``[``, ``]``, ``{``, ``}`` matter, and all are ASCII, so multi-byte UTF-8 characters never match
them. For malformed JSON the depth is that of its brackets; the parser refuses the rest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

BLOCK_BYTES = 1 << 18
"""Bytes scanned at a time (the working memory is a small multiple of this)."""
QUOTE, BACKSLASH = ord('"'), ord("\\")
OPENING, CLOSING = (ord("["), ord("{")), (ord("]"), ord("}"))


@dataclass
class _Scan:
    """The state carried from one block to the next."""

    in_string: bool = False
    escape_pending: bool = False
    """The previous block ended in an odd run of backslashes: the next byte is escaped."""
    depth: int = 0
    deepest: int = 0

    def escaped(self, block: np.ndarray) -> np.ndarray:
        """Which bytes of ``block`` follow an odd run of backslashes (bool, same shape)."""
        escaped = np.zeros(block.shape, dtype=bool)
        slashes = np.flatnonzero(block == BACKSLASH)
        if slashes.size == 0:
            escaped[:1] = self.escape_pending
            self.escape_pending = False
            return escaped
        breaks = np.flatnonzero(np.diff(slashes) != 1)
        starts = slashes[np.concatenate(([0], breaks + 1))]
        ends = slashes[np.concatenate((breaks, [slashes.size - 1]))] + 1  # one past each run
        lengths = ends - starts
        if self.escape_pending:
            if starts[0] == 0:
                lengths[0] += 1  # the run goes on from the previous block
            else:
                escaped[0] = True
        odd_ends = ends[lengths % 2 == 1]
        self.escape_pending = bool(odd_ends.size) and int(odd_ends[-1]) == block.size
        escaped[odd_ends[odd_ends < block.size]] = True
        return escaped

    def feed(self, block: np.ndarray) -> None:
        """Scan one block of bytes (uint8)."""
        quotes = (block == QUOTE) & ~self.escaped(block)
        opening = (block == OPENING[0]) | (block == OPENING[1])
        closing = (block == CLOSING[0]) | (block == CLOSING[1])
        marks = np.flatnonzero(quotes | opening | closing)
        is_quote = quotes[marks]
        toggles = np.cumsum(is_quote, dtype=np.int64)
        inside = ((toggles - is_quote) % 2 == 1) ^ self.in_string  # the state before each mark
        steps = np.where(opening[marks], 1, -1) * ~(inside | is_quote)
        levels = self.depth + np.cumsum(steps, dtype=np.int64)
        if levels.size:
            self.deepest = max(self.deepest, int(levels.max()))
            self.depth = int(levels[-1])
        self.in_string ^= bool(toggles[-1] % 2) if toggles.size else False


def json_depth(text: str | bytes) -> int:
    """Deepest nesting of arrays and objects in JSON ``text`` (brackets inside strings ignored).

    >>> json_depth('{"a": [1, {"b": "[[[\\\\"]]"}]}'), json_depth(b"3"), json_depth("[" * 50)
    (3, 0, 50)
    """
    data = text.encode("utf-8", "surrogatepass") if isinstance(text, str) else text
    scan = _Scan()
    view = memoryview(data).cast("B")
    for start in range(0, len(view), BLOCK_BYTES):
        scan.feed(np.frombuffer(view[start : start + BLOCK_BYTES], dtype=np.uint8))
    return scan.deepest
