"""Framing of the line protocol on the robot's side: bytes in, complete lines out
(docs/protocol.md, "Framing").

A line ends in ``\\n`` and is at most :data:`MAX_LINE_BYTES` bytes long, newline included. A
longer one is skipped up to its newline and reported once as a :class:`LineError` ``oversized``;
the stream then carries on with the next line. One trailing ``\\r`` is dropped (``\\r\\n``
works). The buffer never holds more than one line's worth of bytes: a board's RAM bounds it.
"""

MAX_LINE_BYTES = 1024
"""Longest accepted line [bytes], the newline included."""


class LineError(Exception):
    """A line that is no valid message; ``code`` is the ``error`` code to answer with
    (``oversized``, ``encoding``, ``json``, ``field``, ``version``, ``unknown_type``, ``auth``)."""

    def __init__(self, code: str, message: str) -> None:
        super().__init__(message)
        self.code = code


class LineReader:
    """Splits the bytes read into lines (see module doc).

    >>> reader = LineReader()
    >>> reader.feed(b'{"a":1}\\r\\n{"b"')
    >>> reader.take()
    [b'{"a":1}']
    >>> reader.feed(b":2}\\n")
    >>> reader.take()
    [b'{"b":2}']
    """

    def __init__(self, max_line: int = MAX_LINE_BYTES) -> None:
        self.max_line = max_line
        self._pending = b""
        self._skipping = False  # inside an oversized line: drop bytes up to its newline

    def feed(self, data: bytes) -> None:
        """Append bytes read from the host."""
        self._pending += data

    def take(self) -> list[bytes | LineError]:
        """The complete lines (bytes, without the newline) and :class:`LineError`\\ s of the
        oversized ones, in the order they arrived; the rest waits for more bytes."""
        items: list[bytes | LineError] = []
        while True:
            end = self._pending.find(b"\n")
            if end < 0:
                if not self._skipping and len(self._pending) >= self.max_line:
                    items.append(self._oversized())
                    self._skipping = True
                if self._skipping:
                    self._pending = b""
                return items
            line, self._pending = self._pending[:end], self._pending[end + 1 :]
            if self._skipping:
                self._skipping = False
            elif end + 1 > self.max_line:
                items.append(self._oversized())
            else:
                items.append(line[:-1] if line.endswith(b"\r") else line)

    def _oversized(self) -> LineError:
        return LineError("oversized", "line longer than " + str(self.max_line) + " bytes")
