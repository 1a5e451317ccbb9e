"""The tune journal (Optuna's ``JournalStorage`` on one JSON-lines file) checked before use.

Optuna replays a journal line by line and trusts it: an unknown op code fails an ``assert``, a
missing field is a ``KeyError`` deep in the replay, a directory an ``IsADirectoryError``. So
:func:`check_journal` reads the file first (:func:`skidnav.files.user.read_limited`: a regular
file of at most :data:`MAX_JOURNAL_BYTES`) and checks every complete line — a JSON object
(:func:`skidnav.files.saved.parse_json`) with a known integer ``op_code`` and a string
``worker_id`` — then replays them into a scratch storage in memory. Only a journal that passes
may have its last line repaired: a line cut short by a kill during a write is a prefix of what
Optuna writes (``{"op_code":…``), and nothing else is ever truncated. Every problem is one
:class:`~skidnav.errors.CorruptFileError` line ``"JOURNAL:LINE: problem"``.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any, NamedTuple

import optuna
from optuna.storages.journal import BaseJournalBackend

from skidnav.errors import CorruptFileError, excerpt, first_line, shown
from skidnav.files.saved import parse_json
from skidnav.files.user import read_limited

MAX_JOURNAL_BYTES = 256 * 2**20
"""Largest journal read [bytes]: a trial writes a few kilobytes, so this holds tens of
thousands."""
LINE_START = b'{"op_code":'
"""How Optuna begins every line it writes (``json.dumps`` of a log whose first key is the op
code): a cut last line begins with a prefix of it."""


class JournalCheck(NamedTuple):
    """What :func:`check_journal` found."""

    lines: int
    """Complete lines, each checked."""
    complete_bytes: int
    """Bytes up to the end of the last complete line."""
    torn_bytes: int
    """Bytes of a last line cut short (0 when the file ends with a newline)."""


def _op_codes() -> frozenset[int]:
    """The op codes this Optuna writes and replays."""
    from optuna.storages.journal._storage import JournalOperation

    return frozenset(int(operation) for operation in JournalOperation)


def _checked_logs(lines: list[bytes], journal: Path) -> list[dict[str, Any]]:
    """The logs of the complete ``lines``, each a JSON object with a known integer op code and
    a string worker id; CorruptFileError naming the first line that is not."""
    known = _op_codes()
    logs = []
    for number, line in enumerate(lines, start=1):
        log = parse_json(line, f"{journal}:{number}", allow_nonfinite=True)
        op_code = log.get("op_code")
        if type(op_code) is not int or op_code not in known:
            raise CorruptFileError(
                f"{journal}:{number}: unknown op code {shown(op_code)} (not an Optuna journal "
                f"of version {optuna.__version__})"
            )
        if not isinstance(log.get("worker_id"), str):
            raise CorruptFileError(f"{journal}:{number}: expected a string worker_id")
        logs.append(log)
    return logs


class _Replay(BaseJournalBackend):
    """Checked logs offered to a scratch ``JournalStorage``; ``given`` counts those it took."""

    def __init__(self, logs: list[dict[str, Any]]) -> None:
        self.logs, self.given = logs, 0

    def read_logs(self, log_number_from: int) -> Iterator[dict[str, Any]]:
        for number in range(log_number_from, len(self.logs)):
            self.given = number + 1
            yield self.logs[number]

    def append_logs(self, logs: list[dict[str, Any]]) -> None:
        raise RuntimeError("a replay writes nothing")


def _replay(logs: list[dict[str, Any]], journal: Path) -> None:
    """Replay ``logs`` in memory as Optuna will; CorruptFileError naming the line it fails at
    (any exception: the replay is Optuna's, and the file is only data)."""
    backend = _Replay(logs)
    try:
        optuna.storages.JournalStorage(backend)
    except Exception as error:
        problem = f"{type(error).__name__}: {first_line(error, 80)}"
        where = f"{journal}:{backend.given}"
        raise CorruptFileError(f"{where}: cannot be replayed ({problem})") from None


def check_journal(journal: Path) -> JournalCheck:
    """Check ``journal`` (module doc) without changing it.

    Raises:
        CorruptFileError: unreadable, not a regular file, too large, a line that is not a
            valid log, a replay that fails, or a last line that is not a cut log line.
    """
    data = read_limited(journal, MAX_JOURNAL_BYTES, "tune journal")
    end = data.rfind(b"\n") + 1
    torn = data[end:]
    lines = data[:end].split(b"\n")[:-1]
    _replay(_checked_logs(lines, journal), journal)
    if torn and not (torn.startswith(LINE_START) or LINE_START.startswith(torn)):
        raise CorruptFileError(
            f"{journal}:{len(lines) + 1}: not an Optuna journal line ({excerpt(torn)})"
        )
    return JournalCheck(len(lines), end, len(torn))
