"""Files a user names, opened and read without trusting them (the opening half of
:mod:`skidnav.files.saved`).

Every file skidnav reads on a user's word (a config, a map, an action script, a saved agent,
policy, checkpoint or run file, a tune journal, an image) is opened by :func:`open_user_file`,
so that no path can make a command hang or fill the memory:

* the path is checked with ``stat`` first: a directory, a device (``/dev/urandom``, ``/dev/zero``)
  or a socket is refused, and so is a FIFO unless the caller reads text a pipe may carry
  (``pipes=True``: a config, an action script);
* it is opened with ``O_NONBLOCK``, so a FIFO that no process writes does not block the open,
  and the opened descriptor is checked again with ``fstat`` (the path may have been swapped
  between the two);
* :func:`read_limited` refuses a file whose size is above ``max_bytes`` and reads at most
  ``max_bytes + 1`` bytes, refusing more: the size ``stat`` reports is 0 for files such as
  ``/proc/self/environ``, and a file may grow while it is read.

A FIFO allowed by ``pipes`` stays non-blocking and is read as its data arrive (``poll``) until
its writer closes it, all within :data:`PIPE_TIMEOUT_S`: a writer may open it after skidnav
did, and one that never comes, or never finishes, ends the read in one line instead of a hang.
Each problem is one line naming the file, of the error type the caller gives.
"""

from __future__ import annotations

import math
import os
import select
import stat
import time
from pathlib import Path
from typing import BinaryIO

from skidnav.errors import CorruptFileError, UserError

_KINDS = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)
READ_BLOCK_BYTES = 1 << 16
"""Bytes asked for at a time beyond a file's reported size."""
PIPE_TIMEOUT_S = 60.0
"""Longest wait for a pipe's writer to send everything and close it [s]."""
_OPEN_FLAGS = os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC | os.O_NOCTTY


def _kind(mode: int) -> str:
    """What a file of ``mode`` is: ``"a regular file"``, ``"a FIFO"``, ``"a directory"``…"""
    if stat.S_ISREG(mode):
        return "a regular file"
    return next((name for test, name in _KINDS if test(mode)), "a special file")


def _refuse_kind(
    path: Path | str, mode: int, what: str, error: type[UserError], pipes: bool
) -> None:
    """``error`` unless a file of ``mode`` may be read (a regular file; a FIFO with ``pipes``)."""
    if stat.S_ISREG(mode) or (pipes and stat.S_ISFIFO(mode)):
        return
    raise error(f"{path}: cannot read {what} ({_kind(mode)}, not a regular file)")


def open_user_file(
    path: Path | str,
    what: str = "file",
    error: type[UserError] = CorruptFileError,
    *,
    pipes: bool = False,
) -> BinaryIO:
    """``path`` opened for reading bytes (module doc); ``error`` ``"PATH: problem"`` when it is
    missing, unreadable, or not a regular file (a FIFO is accepted with ``pipes``, left
    non-blocking: :func:`read_limited` reads it). The caller closes the file (use it as a
    context manager).

    >>> open_user_file("/dev/null", "policy file")
    Traceback (most recent call last):
    ...
    skidnav.errors.CorruptFileError: /dev/null: cannot read policy file (a character device, ...)
    """
    try:
        _refuse_kind(path, os.stat(path).st_mode, what, error, pipes)
        descriptor = os.open(path, _OPEN_FLAGS)
    except FileNotFoundError:
        raise error(f"{path}: no such {what}") from None
    except (OSError, ValueError) as failure:  # ValueError: a NUL byte in the path
        reason = failure.strerror if isinstance(failure, OSError) else None
        raise error(f"{path}: cannot read {what} ({reason or failure})") from None
    try:
        _refuse_kind(path, os.fstat(descriptor).st_mode, what, error, pipes)
        return os.fdopen(descriptor, "rb")
    except BaseException:
        os.close(descriptor)
        raise


def read_limited(
    path: Path | str,
    max_bytes: int,
    what: str = "file",
    error: type[UserError] = CorruptFileError,
    *,
    pipes: bool = False,
) -> bytes:
    """The bytes of ``path`` (opened by :func:`open_user_file`); ``error`` when that refuses it or
    the file holds more than ``max_bytes`` bytes (at most ``max_bytes + 1`` are read).

    >>> read_limited("/proc/self/environ", 10, "config file", UserError)
    Traceback (most recent call last):
    ...
    skidnav.errors.UserError: /proc/self/environ: config file larger than 10 bytes
    """
    with open_user_file(path, what, error, pipes=pipes) as handle:
        status = os.fstat(handle.fileno())
        size = status.st_size
        try:
            if stat.S_ISFIFO(status.st_mode):
                data = _read_pipe(handle.fileno(), max_bytes + 1)
            else:
                data = _read_at_most(handle, max_bytes + 1, size) if size <= max_bytes else b""
        except TimeoutError:
            problem = f"its writer did not finish within {PIPE_TIMEOUT_S:g} s"
            raise error(f"{path}: cannot read {what} ({problem})") from None
        except OSError as failure:
            raise error(f"{path}: cannot read {what} ({failure.strerror or failure})") from None
    if size > max_bytes or len(data) > max_bytes:
        raise error(f"{path}: {what} larger than {max_bytes:,} bytes")
    return data


def _read_at_most(handle: BinaryIO, limit: int, size: int) -> bytes:
    """Up to ``limit`` bytes of ``handle``, whose reported size is ``size``: read in one piece of
    that size (plus one byte, to see a file that grew), then in blocks while more comes (a file
    of ``/proc`` reporting 0), so nothing larger than what arrives is ever allocated."""
    parts, total = [], 0
    request = size + 1
    while total < limit:
        part = handle.read(min(limit - total, request))
        if not part:
            break
        parts.append(part)
        total += len(part)
        request = READ_BLOCK_BYTES
    return b"".join(parts)


def _read_pipe(descriptor: int, limit: int) -> bytes:
    """Up to ``limit`` bytes of the non-blocking FIFO ``descriptor``, read as they arrive until
    its writer closes it; TimeoutError if that takes longer than :data:`PIPE_TIMEOUT_S` (a FIFO
    no writer has opened yet is not readable, so a late writer is waited for)."""
    deadline = time.monotonic() + PIPE_TIMEOUT_S
    poller = select.poll()
    poller.register(descriptor, select.POLLIN)
    parts, total = [], 0
    while total < limit:
        remaining = deadline - time.monotonic()
        if remaining <= 0 or not poller.poll(max(1, math.ceil(remaining * 1000))):
            raise TimeoutError
        try:
            part = os.read(descriptor, min(READ_BLOCK_BYTES, limit - total))
        except BlockingIOError:
            continue
        if not part:
            break
        parts.append(part)
        total += len(part)
    return b"".join(parts)
