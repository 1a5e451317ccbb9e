"""The lock of a results or study directory: one process at a time writes there."""

from __future__ import annotations

import contextlib
import fcntl
import os
from collections.abc import Iterator
from pathlib import Path

from skidnav.errors import UserError

LOCK_FILE = ".skidnav.lock"
"""The lock file of a results or study directory."""


@contextlib.contextmanager
def directory_lock(root: Path | str) -> Iterator[Path]:
    """Hold ``root``'s lock (``fcntl.flock`` on :data:`LOCK_FILE`, our pid written inside) while
    writing there; creates ``root``. The kernel releases the lock when its holder dies (even by
    SIGKILL), so a later process takes it over. A directory this call created is removed again
    on the way out if nothing but the lock was written in it.

    Raises:
        UserError: ``root`` is not a directory, or another process holds the lock (named by pid).
    """
    root = Path(root)
    created = not root.exists()
    try:
        root.mkdir(parents=True, exist_ok=True)
        descriptor = os.open(root / LOCK_FILE, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
    except (FileExistsError, NotADirectoryError):
        raise UserError(f"{root}: not a directory; choose another --out") from None
    except OSError as error:
        raise UserError(f"{root}: cannot write there ({error.strerror or error})") from None
    try:
        try:
            fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise UserError(
                f"{root}: in use by another skidnav process{_holder(descriptor)}; wait for it "
                "to finish or choose another --out"
            ) from None
        os.ftruncate(descriptor, 0)
        os.pwrite(descriptor, f"{os.getpid()}\n".encode(), 0)
        try:
            yield root
        finally:
            os.ftruncate(descriptor, 0)
            if created and [entry.name for entry in root.iterdir()] == [LOCK_FILE]:
                (root / LOCK_FILE).unlink()
                root.rmdir()
    finally:
        os.close(descriptor)


def _holder(descriptor: int) -> str:
    """`` (pid N)`` of the lock's holder as written in the lock file (empty if unreadable)."""
    text = os.pread(descriptor, 24, 0).decode("ascii", errors="replace").strip()
    return f" (pid {text})" if text.isdigit() else ""
