"""Sessions of a results directory: which code produced which runs.

Every ``skidnav run`` on a directory is a *session*. Each run file records the code of the session
that wrote it (:func:`skidnav.experiments.provenance.code_version` plus the session's start time),
so a resume can tell how many finished runs came from other code, and ``metadata.json`` keeps the
list of sessions (start, code, runs done), including sessions that were killed before they could
write it (rebuilt from the run files' records).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping
from typing import Any

from skidnav.experiments.provenance import CODE_KEYS, describe_code

MAX_LISTED = 3
"""Other code versions named in the resume warning."""


def code_of(record: Mapping[str, Any]) -> dict[str, Any]:
    """The :data:`CODE_KEYS` fields of a run's (or session's) record."""
    return {key: record.get(key) for key in CODE_KEYS}


def other_code(records: Mapping[str, Mapping[str, Any]], current: Mapping[str, Any]) -> list[str]:
    """Ids of the runs whose record names other code than ``current`` (or none at all)."""
    wanted = code_of(current)
    return sorted(run_id for run_id, record in records.items() if code_of(record) != wanted)


def mixed_code_message(
    records: Mapping[str, Mapping[str, Any]], foreign: list[str], current: Mapping[str, Any]
) -> str:
    """The resume warning: how many finished runs came from which other code."""
    versions = Counter(describe_code(dict(records[run_id])) for run_id in foreign)
    named = [f"{count} × {text}" for text, count in versions.most_common(MAX_LISTED)]
    if len(versions) > MAX_LISTED:
        named.append("…")
    return (
        f"{len(foreign)} of {len(records)} finished runs were produced by other code than this "
        f"session ({describe_code(dict(current))}): {'; '.join(named)}. Resuming anyway: the "
        "results will mix code versions (choose another --out for a clean sweep)"
    )


def update_sessions(
    previous: list[dict[str, Any]],
    records: Mapping[str, Mapping[str, Any]],
    session: dict[str, Any],
) -> list[dict[str, Any]]:
    """The session list after ``session``: the ``previous`` list, sessions found only in the run
    records (killed before they wrote ``metadata.json``, marked ``completed: false``) and
    ``session``, in start order; every entry's ``runs_done`` counted from the run records."""
    counts = Counter(record.get("session") for record in records.values())
    sessions = [dict(entry) for entry in previous if entry.get("started") != session["started"]]
    known = {entry.get("started") for entry in sessions} | {session["started"]}
    for record in records.values():
        started = record.get("session")
        if started and started not in known:
            sessions.append({"started": started, **code_of(record), "completed": False})
            known.add(started)
    sessions.append(dict(session))
    for entry in sessions:
        if entry.get("started") in counts or "runs_done" not in entry:
            entry["runs_done"] = counts.get(entry.get("started"), 0)
    return sorted(sessions, key=lambda entry: str(entry.get("started")))
