"""What a real-time run writes down: the outcome of each episode, the JSON-lines run log, and
the sim server's event log (docs/realtime.md, "Files written").

The two logs are append-only, the one exception to writing files atomically
(:mod:`skidnav.files.atomic`): a log grows for the whole run, so each record is one line, written
and flushed at once, and a kill can cut only the last line (a reader should skip a torn one).
Checkpoints are written with :func:`~skidnav.files.atomic.write_atomic`."""

from __future__ import annotations

import json
import math
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from skidnav.errors import shown


@dataclass
class EpisodeResult:
    """Outcome of one episode (``return_`` is the undiscounted return, ``wall_time`` [s]).

    Checked on construction (a checkpoint's ``loop.json`` is read back through it): ValueError
    unless the counts are integers >= 0, the flags booleans, the reason None or a string and the
    return and wall time finite numbers.
    """

    episode: int
    actions: int = 0
    return_: float = 0.0
    collisions: int = 0
    reached_goal: bool = False
    aborted: bool = False
    reason: str | None = None
    wall_time: float = 0.0

    def __post_init__(self) -> None:
        for name in ("episode", "actions", "collisions"):
            value = getattr(self, name)
            if not (isinstance(value, int) and not isinstance(value, bool) and value >= 0):
                raise ValueError(f"expected {name} to be an integer >= 0, got {shown(value)}")
        for name in ("return_", "wall_time"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value)):
                raise ValueError(f"expected {name} to be a finite number, got {shown(value)}")
        if not (isinstance(self.reached_goal, bool) and isinstance(self.aborted, bool)):
            raise ValueError("expected reached_goal and aborted to be true or false")
        if not (self.reason is None or isinstance(self.reason, str)):
            raise ValueError(f"expected reason to be a string, got {shown(self.reason)}")


class RunLog:
    """Thread-safe append-only JSON-lines log (one flushed line per record; never rewritten);
    every record gets ``mono`` (monotonic clock [s])."""

    def __init__(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        self._stream = path.open("a", encoding="utf-8")
        self._lock = threading.Lock()

    def write(self, event: str, fields: dict[str, Any]) -> None:
        record = {"mono": time.monotonic(), "event": event, **fields}
        with self._lock:
            if not self._stream.closed:
                self._stream.write(json.dumps(record) + "\n")
                self._stream.flush()

    def close(self) -> None:
        with self._lock:
            self._stream.close()


class EventLog:
    """Append-only JSON-lines log of the sim server (flushed per line); a no-op without a file.

    Every record gets ``mono`` (the system-wide monotonic clock [s], comparable with the host's
    run log on the same machine) and ``wall`` (Unix time [s]).
    """

    def __init__(self, stream: IO[str] | None) -> None:
        self.stream = stream

    def write(self, event: str, **fields: object) -> None:
        if self.stream is None:
            return
        record = {"mono": time.monotonic(), "wall": time.time(), "event": event, **fields}
        self.stream.write(json.dumps(record) + "\n")
        self.stream.flush()
