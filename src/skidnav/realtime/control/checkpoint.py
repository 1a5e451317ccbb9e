"""Per-episode checkpoints of a real-time run, written so that a crash never leaves a torn one.

Layout under ``OUT/checkpoints/``::

    ep-00004/agent.npz, agent.json   the agent (agent.save: a tabular agent's tables,
                                     mppi-kinematic's model, map and plan; absent in a frozen
                                     policy's run: it does not learn)
    ep-00004/loop.json               the loop state (episode results, wheel-speed statistics, …)
    latest.json                      {"episode": 4, "directory": "ep-00004"}

Every file is written with :func:`~skidnav.files.atomic.write_atomic` and a checkpoint directory
is complete before ``latest.json`` points to it; the newest ``keep`` directories are kept, and
the temporaries of a writer that was killed are removed at the next checkpoint.

Reading trusts neither JSON file (:func:`~skidnav.files.saved.read_json`: size, nesting, no
``NaN``): ``latest.json`` must name the checkpoint directory of its episode (nothing outside
``checkpoints/``), and ``loop.json`` hold episode results and statistics the loop can restore.
"""

from __future__ import annotations

import json
import logging
import shutil
from pathlib import Path
from typing import Any

import numpy as np

from skidnav.agents.interface import Agent
from skidnav.errors import CorruptFileError, first_line, shown
from skidnav.files.atomic import remove_stale_temporaries, write_atomic
from skidnav.files.saved import read_json
from skidnav.realtime.control.records import EpisodeResult

log = logging.getLogger(__name__)

LATEST = "latest.json"
MAX_POINTER_BYTES = 4096
"""Largest ``latest.json`` read [bytes] (it is about 40)."""
MAX_LOOP_STATE_BYTES = 64 * 2**20
"""Largest ``loop.json`` read [bytes] (about 200 per episode plus 30 per slip region)."""


def _write_json(path: Path, data: Any) -> None:
    write_atomic(path, json.dumps(data, indent=1).encode("utf-8"))


def directory_name(episode: int) -> str:
    """The checkpoint directory of ``episode`` (0-based), e.g. ``ep-00004``."""
    return f"ep-{episode:05d}"


class Checkpoints:
    """The checkpoint directory of one run (see module doc)."""

    def __init__(self, root: Path, keep: int = 3) -> None:
        self.root = root
        self.keep = keep

    def save(self, episode: int, agent: Agent | None, loop_state: dict[str, Any]) -> Path:
        """Write the checkpoint after ``episode`` (0-based) and point ``latest.json`` to it;
        ``agent`` None (a frozen policy) writes the loop state only."""
        name = directory_name(episode)
        directory = self.root / name
        if directory.exists():
            shutil.rmtree(directory)
        directory.mkdir(parents=True)
        remove_stale_temporaries(self.root, LATEST)
        if agent is not None:
            agent.save(directory / "agent")
        _write_json(directory / "loop.json", loop_state)
        _write_json(self.root / LATEST, {"episode": episode, "directory": name})
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
            CorruptFileError: ``latest.json`` or ``loop.json`` unreadable or not what a
                checkpoint writes (one line naming the file).
        """
        pointer = self.root / LATEST
        if not pointer.exists():
            return None
        latest = read_json(pointer, max_bytes=MAX_POINTER_BYTES, what="checkpoint pointer")
        episode, name = latest.get("episode"), latest.get("directory")
        if not (isinstance(episode, int) and not isinstance(episode, bool) and episode >= 0):
            raise CorruptFileError(f"{pointer}: expected an episode >= 0, got {shown(episode)}")
        if name != directory_name(episode):
            raise CorruptFileError(
                f"{pointer}: expected directory {directory_name(episode)!r} for episode "
                f"{episode}, got {shown(name)}"
            )
        directory = self.root / directory_name(episode)
        state_path = directory / "loop.json"
        state = read_json(state_path, max_bytes=MAX_LOOP_STATE_BYTES, what="checkpoint file")
        problem = _loop_state_problem(state)
        if problem is not None:
            raise CorruptFileError(f"{state_path}: {problem}")
        return episode, directory, state


REQUIRED_LOOP_KEYS = ("results", "wheel_speed_stats")
"""Keys of ``loop.json`` the loop cannot restore without (``icr_sums`` is optional: older
checkpoints lack it)."""


def _loop_state_problem(state: dict[str, Any]) -> str | None:
    """What keeps the loop from restoring ``state`` (None if nothing): episode results it
    cannot rebuild, statistics that are not tables of finite numbers, a key the loop needs
    missing."""
    results = state.get("results", [])
    if not isinstance(results, list) or not all(isinstance(r, dict) for r in results):
        return "expected 'results' to be a list of episode results"
    fields = set(EpisodeResult.__dataclass_fields__)
    try:
        for result in results:
            unknown = sorted(set(result) - fields)
            if unknown:
                raise ValueError(f"unexpected episode result field {shown(unknown[0])}")
            EpisodeResult(**result)
        for key in ("wheel_speed_stats", "icr_sums"):
            if key in state:
                _finite_table(state[key], key)
    except (ValueError, TypeError) as error:
        return f"unusable loop state ({first_line(error, 120)})"
    missing = [key for key in REQUIRED_LOOP_KEYS if key not in state]
    return f"unusable loop state (no {missing[0]!r})" if missing else None


def _finite_table(value: Any, key: str) -> None:
    """ValueError (quoting nothing of the file) unless ``value`` is a table of finite numbers."""
    try:
        values = np.asarray(value, dtype=np.float64)
    except (ValueError, TypeError):
        values = np.full(1, np.nan)
    if values.ndim > 2 or not np.isfinite(values).all():
        raise ValueError(f"{key} is not a table of finite numbers")
