"""The transfer study's table, from its results directory (docs/physics.md, "The sim-to-sim gap").

Per agent: the share of greedy rollouts reaching the goal and their mean length [actions], on the
kinematic simulator and on the MuJoCo robot, means over seeds with 95 % bootstrap intervals
(:mod:`skidnav.statistics.intervals`, one generator seeded 0, drawn in table order); and one row
per run.
``skidnav study transfer`` prints it as text, ``skidnav report`` shows it as HTML
(:func:`report_section`).
"""

from __future__ import annotations

from collections.abc import Sequence
from html import escape
from pathlib import Path

import numpy as np
import pandas as pd

from skidnav.statistics.intervals import bootstrap_interval
from skidnav.studies.agent_grid import html_table, interval_cell, results_table, study_results
from skidnav.studies.transfer.evaluation import TransferResult
from skidnav.studies.transfer.grid import LAYOUT

METRICS = ("success_kinematic", "success_physics", "length_kinematic", "length_physics")
"""The per-run values the table summarises, in column order."""
HEADER = ("agent", "success, kinematic", "success, physics", "length, kinematic",
          "length, physics")  # fmt: skip
"""The columns of the table."""


def results_of(summaries: pd.DataFrame) -> list[TransferResult]:
    """One result per run of a results directory's summaries (agent: the agent's label)."""
    return [
        TransferResult(str(row["agent"]), int(row["seed"]), *(float(row[k]) for k in METRICS))
        for row in summaries.to_dict("records")
    ]


def summary_rows(results: Sequence[TransferResult]) -> list[tuple[str, ...]]:
    """The table's rows (:data:`HEADER`), agents in order of first run."""
    rng = np.random.default_rng(0)
    rows = []
    for name in dict.fromkeys(result.agent for result in results):
        mine = [result for result in results if result.agent == name]
        cells = [
            interval_cell(bootstrap_interval([getattr(row, key) for row in mine], rng))
            for key in METRICS
        ]
        rows.append((name, *cells))
    return rows


def summary_text(results: Sequence[TransferResult]) -> str:
    """The table as fixed-width text."""
    lines = [f"{HEADER[0]:24s} " + " ".join(f"{name:>22s}" for name in HEADER[1:])]
    for name, *cells in summary_rows(results):
        lines.append(f"{name:24s} " + " ".join(f"{cell:>22s}" for cell in cells))
    return "\n".join(lines)


def report_section(run_dir: Path) -> str:
    """The study's section of the HTML report of ``run_dir`` (UserError if it is not a transfer
    study's results directory)."""
    grid, summaries = study_results(run_dir, LAYOUT)
    results = results_of(summaries)
    floor = f"one material, {grid.floor}" if grid.floor else "the preset's materials"
    note = (
        f"Per seed one {grid.map_kind} world on the {grid.slip} preset; each agent trained for "
        f"{grid.episodes} episodes of at most {grid.max_steps} actions on the kinematic "
        f"simulator, then its greedy policy rolled out {grid.rollouts} times on it and on the "
        f"MuJoCo robot ({floor}). Means over the {len(results)} finished runs with 95 % "
        "bootstrap intervals; lengths in actions, of the rollouts that reached the goal (n/a: "
        'none did). docs/physics.md, "The sim-to-sim gap".'
    )
    return (
        "<h2>The sim-to-sim gap</h2>"
        f"<p class='note'>{escape(note)}</p>"
        + html_table([dict(zip(HEADER, row, strict=True)) for row in summary_rows(results)])
        + "<h3>Runs</h3>"
        + results_table(results)
    )
