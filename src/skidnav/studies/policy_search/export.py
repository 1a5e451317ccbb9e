"""The files of one search, written from a policy-search study's results: the policy file
(``policy.npz`` + ``policy.json``, :mod:`skidnav.agents.policies.search.policy_file`), the
learning curve (``curve.csv``) and ``search.json`` (the search's config and last curve row).
``skidnav study search`` writes them into its ``--out``; any run of a study can be exported the
same way (:func:`export_search`)."""

from __future__ import annotations

import csv
import dataclasses
import io
import json
from pathlib import Path
from typing import Any

from skidnav.agents.policies.search.curve import record_rows
from skidnav.agents.policies.search.policy_file import save_policy
from skidnav.experiments.store import ResultStore
from skidnav.files.atomic import write_user_file, writing
from skidnav.studies.policy_search.grid import LAYOUT
from skidnav.studies.policy_search.trial import policy_of_run, records_of_run


def export_search(run_dir: Path, run_id: str, out: Path) -> list[Path]:
    """Write ``policy.npz``, ``policy.json``, ``curve.csv`` and ``search.json`` of run
    ``run_id`` of the study in ``run_dir`` into the folder ``out`` (which must exist); returns
    their paths. The policy's provenance holds the search's config, the last curve row and
    where it came from.

    Raises:
        UserError: ``run_dir`` holds no such run, or a file cannot be written.
    """
    store = ResultStore(run_dir, LAYOUT)
    grid = store.config()
    result = store.read_run(run_id)
    preset, seed = str(result.coordinates["preset"]), int(result.summary["search_seed"])
    config = dataclasses.replace(grid.search, slip=preset, seed=seed)
    rows = record_rows(records_of_run(result))
    provenance = {"config": config.to_dict(), "last": rows[-1], "results": str(run_dir)}
    provenance["run_id"] = run_id
    with writing(out / "policy.npz", "policy"):
        paths = list(save_policy(policy_of_run(grid, result), out / "policy", provenance))
    write_user_file(out / "curve.csv", curve_csv(rows), "learning curve")
    summary = {"config": config.to_dict(), "last": rows[-1], "policy": "policy.npz"}
    write_user_file(out / "search.json", json.dumps(summary, indent=1).encode(), "summary")
    return [*paths, out / "curve.csv", out / "search.json"]


def curve_csv(rows: list[dict[str, Any]]) -> bytes:
    """The learning curve as CSV bytes (None: an empty cell)."""
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, list(rows[0]))
    writer.writeheader()
    writer.writerows(
        {key: "" if value is None else value for key, value in row.items()} for row in rows
    )
    return buffer.getvalue().encode()
