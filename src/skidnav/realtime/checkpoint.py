"""Per-episode checkpoints of a real-time run, written so that a crash never leaves a torn one.

Layout under ``OUT/checkpoints/``::

    ep-00004/agent.npz, agent.json   the agent (agent.save)
    ep-00004/loop.json               the loop state (episode results, wheel-speed statistics, …)
    latest.json                      {"episode": 4, "directory": "ep-00004"}

A checkpoint directory is complete before ``latest.json`` (replaced atomically with
``os.replace``) points to it; the newest ``keep`` directories are kept.
"""

from __future__ import annotations

import json
import logging
import os
import shutil
from pathlib import Path
from typing import Any

from skidnav.errors import CorruptFileError

log = logging.getLogger(__name__)

LATEST = "latest.json"


def _write_json_atomic(path: Path, data: Any) -> None:
    temporary = path.with_name(path.name + ".tmp")
    with temporary.open("w", encoding="utf-8") as stream:
        json.dump(data, stream, indent=1)
        stream.flush()
        os.fsync(stream.fileno())
    os.replace(temporary, path)


class Checkpoints:
    """The checkpoint directory of one run (see module doc)."""

    def __init__(self, root: Path, keep: int = 3) -> None:
        self.root = root
        self.keep = keep

    def save(self, episode: int, agent: Any, loop_state: dict[str, Any]) -> Path:
        """Write the checkpoint after ``episode`` (0-based) and point ``latest.json`` to it."""
        name = f"ep-{episode:05d}"
        directory = self.root / name
        if directory.exists():
            shutil.rmtree(directory)
        directory.mkdir(parents=True)
        agent.save(directory / "agent")
        _write_json_atomic(directory / "loop.json", loop_state)
        _write_json_atomic(self.root / LATEST, {"episode": episode, "directory": name})
        self._prune(name)
        log.info("checkpoint %s written", directory)
        return directory

    def _prune(self, newest: str) -> None:
        directories = sorted(p for p in self.root.glob("ep-*") if p.is_dir())
        for old in directories[: -self.keep]:
            if old.name != newest:
                shutil.rmtree(old, ignore_errors=True)

    def latest(self) -> tuple[int, Path, dict[str, Any]] | None:
        """(episode, directory, loop state) of the newest checkpoint, or None if there is none.

        Raises:
            CorruptFileError: ``latest.json`` or ``loop.json`` unreadable.
        """
        pointer = self.root / LATEST
        if not pointer.exists():
            return None
        try:
            latest = json.loads(pointer.read_text(encoding="utf-8"))
            directory = self.root / str(latest["directory"])
            state = json.loads((directory / "loop.json").read_text(encoding="utf-8"))
            return int(latest["episode"]), directory, state
        except (OSError, ValueError, KeyError, TypeError) as error:
            raise CorruptFileError(f"{pointer}: unreadable checkpoint: {error}") from None
