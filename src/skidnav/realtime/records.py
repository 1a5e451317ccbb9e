"""What a real-time run writes down: the outcome of each episode and the JSON-lines run log
(docs/realtime.md, "Files written")."""

from __future__ import annotations

import json
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any


@dataclass
class EpisodeResult:
    """Outcome of one episode (``return_`` is the undiscounted return)."""

    episode: int
    actions: int = 0
    return_: float = 0.0
    collisions: int = 0
    reached_goal: bool = False
    aborted: bool = False
    reason: str | None = None
    wall_time: float = 0.0


class RunLog:
    """Thread-safe JSON-lines log; every record gets ``mono`` (monotonic clock [s])."""

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
