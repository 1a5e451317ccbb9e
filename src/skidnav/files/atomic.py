"""Files written all-or-nothing (the writing half of :mod:`skidnav.files.saved`).

:func:`write_atomic` writes a temporary file beside the target, fsyncs it and moves it into
place with ``os.replace``: a reader, or a kill at any moment, sees the old file or the new one.
:func:`writing` turns an OSError into one user-error line (:func:`write_user_file` is the two
together: a full disk is one line, the previous file kept); :func:`write_npz_atomic`
writes an ``.npz`` built in memory; :func:`remove_stale_temporaries` removes the temporaries of
writers that died (their pid is in the name).

Append-only logs (the JSON lines of a real-time run) are the exception: they are appended to and
flushed line by line, so a kill can cut only their last line.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import secrets
from collections.abc import Iterator, Mapping
from pathlib import Path

import numpy as np

from skidnav.errors import UserError

_TEMPORARY = re.compile(r"^\.?(?P<name>.+?)\.(?P<pid>\d+)(?:-[0-9a-f]{8})?\.tmp$")


def write_atomic(path: Path | str, data: bytes) -> None:
    """Write ``data`` to ``path`` all-or-nothing: a temporary file in the same directory, flushed
    and fsynced, then ``os.replace``; on any failure (also KeyboardInterrupt) the temporary is
    removed and the old file, if any, is left as it was. Raises OSError."""
    path = Path(path)
    temporary = path.with_name(f".{path.name}.{os.getpid()}-{secrets.token_hex(4)}.tmp")
    try:
        with open(temporary, "xb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(OSError):
            temporary.unlink()
        raise
    with contextlib.suppress(OSError):  # make the rename itself durable (not on every system)
        descriptor = os.open(path.parent, os.O_RDONLY)
        try:
            os.fsync(descriptor)
        finally:
            os.close(descriptor)


@contextlib.contextmanager
def writing(path: Path | str, what: str = "file") -> Iterator[None]:
    """Report an OSError of the writes in the block (missing folder, no permission, disk full)
    as one :class:`~skidnav.errors.UserError` line, ``"PATH: cannot write the WHAT (reason)"``;
    an atomic write has left the previous file as it was.

    >>> with writing("/dev/null/x.csv", "table"):
    ...     write_atomic("/dev/null/x.csv", b"")
    Traceback (most recent call last):
    ...
    skidnav.errors.UserError: /dev/null/x.csv: cannot write the table (Not a directory)
    """
    try:
        yield
    except OSError as error:
        raise UserError(f"{path}: cannot write the {what} ({error.strerror or error})") from None


def write_user_file(path: Path | str, data: bytes, what: str = "file") -> None:
    """:func:`write_atomic` for a file the user asked for, an OSError reported by
    :func:`writing`."""
    with writing(path, what):
        write_atomic(path, data)


def write_npz_atomic(
    path: Path | str, arrays: Mapping[str, np.ndarray], *, compress: bool = False
) -> None:
    """Write ``arrays`` (names without ``/``; numeric, boolean or string dtypes, never objects)
    as an ``.npz`` archive, deflated with ``compress``, through :func:`write_atomic`: the archive
    is built in memory first, so a failure leaves the old file.

    >>> import tempfile
    >>> path = Path(tempfile.mkdtemp()) / "a.npz"
    >>> write_npz_atomic(path, {"q": np.zeros((2, 3))}, compress=True)
    >>> np.load(path)["q"].shape
    (2, 3)
    """
    buffer = io.BytesIO()
    save = np.savez_compressed if compress else np.savez
    save(buffer, **arrays)  # type: ignore[arg-type]
    write_atomic(path, buffer.getvalue())


def _running(pid: int) -> bool:
    """Whether a process ``pid`` exists (ours counts: its temporaries may be in use)."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except PermissionError:
        return True  # another user's process
    except (ProcessLookupError, OverflowError, ValueError):
        return False
    return pid > 0


def remove_stale_temporaries(directory: Path | str, target: str | None = None) -> int:
    """Remove the temporaries of :func:`write_atomic` in ``directory`` (only those of ``target``
    when given) whose writing process no longer runs; returns how many were removed. Those of
    live processes are left alone, so a concurrent writer is never disturbed."""
    removed = 0
    try:
        entries = list(Path(directory).iterdir())
    except OSError:
        return 0
    for entry in entries:
        match = _TEMPORARY.match(entry.name)
        if match is None or (target is not None and match["name"] != target):
            continue
        if not _running(int(match["pid"])):
            with contextlib.suppress(OSError):
                entry.unlink()
                removed += 1
    return removed
