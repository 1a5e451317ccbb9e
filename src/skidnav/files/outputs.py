"""Where a command will write, checked before it starts its work.

A command may run for minutes before it writes its first file; an output path in a directory
that does not exist, that names a file, or that cannot be written must end it at once, in one
line, not after the work. :func:`check_output_file` and :func:`check_output_dir` check the path
as the writer will meet it (``os.access`` for the permission, which also refuses a read-only file
system) and create nothing; :func:`make_output_dir` then creates a results directory. A full
disk shows only when writing: writers report it in one line and keep what was written before
(:mod:`skidnav.files.atomic`).
"""

from __future__ import annotations

import os
from pathlib import Path

from skidnav.errors import UserError

WRITABLE = os.W_OK | os.X_OK
"""What a directory must allow to create files in it."""


def _existing_ancestor(path: Path) -> Path:
    """The nearest of ``path``'s parents that exists (the root at worst)."""
    return next(parent for parent in path.absolute().parents if parent.exists())


def _refuse(path: Path, flag: str, problem: str) -> UserError:
    return UserError(f"{path}: {problem}; choose another {flag}")


def _check_directory(directory: Path, path: Path, flag: str) -> None:
    """UserError unless ``directory`` (``path`` or one of its parents) is a directory this
    process may create files in."""
    if not directory.is_dir():
        if directory == path:
            raise _refuse(path, flag, "not a directory")
        raise _refuse(path, flag, f"cannot write there ({directory} is not a directory)")
    if not os.access(directory, WRITABLE):
        raise _refuse(path, flag, f"cannot write there (no permission to write in {directory})")


def check_output_file(path: Path, flag: str = "--out", *, parents: bool = False) -> Path:
    """``path``, if the command can write a file there: not a directory, in a directory that
    exists (with ``parents``: or that the command creates below one that exists) and may be
    written; UserError ``"PATH: problem; choose another FLAG"`` otherwise.

    >>> check_output_file(Path("/dev/null/x.csv"))
    Traceback (most recent call last):
    ...
    skidnav.errors.UserError: /dev/null/x.csv: cannot write there (/dev/null is not a ...
    """
    if path.is_dir():
        raise _refuse(path, flag, "a directory, not a file")
    directory = path.absolute().parent
    if not directory.exists():
        if not parents:
            raise _refuse(path, flag, f"cannot write there (no directory {path.parent})")
        directory = _existing_ancestor(path)
    _check_directory(directory, path, flag)
    return path


def check_output_dir(path: Path, flag: str = "--out") -> Path:
    """``path``, if the command can write its files in it: a directory that may be written, or
    one it can create below a directory that exists and may be written; UserError otherwise."""
    _check_directory(path if path.exists() else _existing_ancestor(path), path, flag)
    return path


def make_output_dir(path: Path, flag: str = "--out") -> Path:
    """:func:`check_output_dir`, then create ``path`` and its parents; UserError if that fails."""
    check_output_dir(path, flag)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise _refuse(path, flag, f"cannot create it ({error.strerror or error})") from None
    return path
