"""The output folder of ``skidnav robot run`` (``--out``, docs/realtime.md, "Files written"),
and the outcome a run leaves there (:func:`summarize`).

A run writes :data:`MARKER` into its folder before anything else: the fingerprint of its config
(:func:`config_fingerprint`). :func:`check_run_folder` then takes, before the robot is contacted
or anything is written:

- a folder that does not exist, or an empty one: a new run;
- a folder of a run of the same config: to continue with ``--resume``, or to start again when
  that run left no checkpoint (it ended before its first episode did: the robot was
  unreachable, say);

and refuses anything else in one line: a folder of other files (a home folder, a source tree,
another command's results), a run of another config, a run with checkpoints without
``--resume`` (a new run would mix its episodes with them). A run folder of an earlier version
without :data:`MARKER` is taken with ``--resume`` alone (its config cannot be checked; the
checkpoint's own checks remain) and gets its marker then.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from pathlib import Path
from typing import NamedTuple

from skidnav.errors import UserError
from skidnav.files.atomic import write_user_file
from skidnav.files.saved import read_json
from skidnav.realtime.config import DRIVER_TABLES, RealtimeConfig
from skidnav.realtime.control.checkpoint import LATEST
from skidnav.realtime.control.episodes import EXIT_ALL_ABORTED, EXIT_SAFETY, EpisodeLoop
from skidnav.statistics.formatting import plural

MARKER = "robot-run.json"
"""The file that makes a folder a robot run's: ``{"format": FORMAT, "fingerprint": …}``."""
FORMAT = "skidnav-robot-run"
MAX_MARKER_BYTES = 4096
"""Largest :data:`MARKER` read [bytes] (it is about 120)."""
OVERRIDDEN = ("episodes", "time_scale", "reset")
"""The ``[run]`` settings a resumed run may change (``--episodes``, ``--time-scale``,
``--reset``): they are not part of the fingerprint."""


def config_fingerprint(config: RealtimeConfig) -> str:
    """SHA-256 (hex) of what makes two runs the same: every table of ``config`` as applied
    (after its preset), except the drivers' (how the robot is reached: address, port, secret
    file) and the ``[run]`` settings of :data:`OVERRIDDEN`."""
    document = dataclasses.asdict(config)
    for name in DRIVER_TABLES:
        del document[name]
    for name in OVERRIDDEN:
        del document["run"][name]
    text = json.dumps(document, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def check_run_folder(out: Path, config: RealtimeConfig, resume: bool) -> None:
    """UserError in one line ending ``choose another --out`` unless ``out`` may hold this run
    (see module doc); creates nothing."""
    if not out.is_dir() or not any(out.iterdir()):
        return  # new, empty, or not a folder (check_output_dir words that)
    checkpointed = (out / "checkpoints" / LATEST).is_file()
    marker = out / MARKER
    if marker.is_file():
        document = read_json(marker, max_bytes=MAX_MARKER_BYTES, what="robot run marker")
        if document.get("format") != FORMAT:
            raise UserError(f"{marker}: not a robot run's marker; choose another --out")
        if document.get("fingerprint") != config_fingerprint(config):
            raise UserError(f"{out}: holds a robot run of another config; choose another --out")
    elif not (checkpointed and (out / "run.jsonl").is_file()):  # nor a run of before MARKER
        raise UserError(f"{out}: not empty and not a robot run; choose another --out")
    if checkpointed and not resume:
        raise UserError(
            f"{out}: holds a robot run; continue it with --resume or choose another --out"
        )


def mark_run_folder(out: Path, config: RealtimeConfig) -> None:
    """Write :data:`MARKER` into ``out`` (which exists) for a run of ``config``."""
    document = {"format": FORMAT, "fingerprint": config_fingerprint(config)}
    write_user_file(out / MARKER, json.dumps(document, indent=1).encode(), "robot run marker")


class RunOutcome(NamedTuple):
    """What a real-time run ended with: its exit code (:mod:`.episodes`), the one-line summary
    of its episodes, and the one line that says why the code is not 0 (None when it is 0 or
    the run was interrupted)."""

    code: int
    summary: str
    problem: str | None = None


def summarize(loop: EpisodeLoop, out: Path, code: int) -> RunOutcome:
    """The outcome of the run of ``loop`` that ended with exit ``code``, its ``summary.json``
    written in ``out``."""
    results = loop.results
    summary = {
        "exit_code": code,
        "episodes": len(results),
        "goals": sum(r.reached_goal for r in results),
        "aborted": sum(r.aborted for r in results),
        "actions": sum(r.actions for r in results),
        "last_abort_reason": next((r.reason for r in reversed(results) if r.aborted), None),
        **loop.summary_fields(),
    }
    write_user_file(out / "summary.json", json.dumps(summary, indent=1).encode(), "run summary")
    line = (
        f"{plural(len(results), 'episode')}, {summary['goals']} reached the goal, "
        f"{summary['aborted']} aborted; results in {out}"
    )
    last = summary["last_abort_reason"]
    problems = {
        EXIT_SAFETY: "the run ended on a safety trip it could not recover from: "
        f"{loop.monitor.reason or last}",
        EXIT_ALL_ABORTED: f"every episode run was aborted, the last by: {last}",
    }
    return RunOutcome(code, line, problems.get(code))
