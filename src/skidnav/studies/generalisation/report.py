"""The generalisation study's tables, from its results directory (docs/generalisation.md).

Per agent and policy (greedy, ε-greedy): success on the training and on the held-out maps and
their paired difference (held-out − training), and the greedy path length on held-out maps,
means over runs with 95 % bootstrap intervals (:mod:`skidnav.statistics.intervals`, one generator
seeded 0,
drawn in table order); the reference policies on the same split; one row per run.
``skidnav study generalise`` prints them as text, ``skidnav report`` shows them as HTML
(:func:`report_section`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import fields
from html import escape
from pathlib import Path

import numpy as np
import pandas as pd

from skidnav.statistics.intervals import bootstrap_interval, difference_interval
from skidnav.studies.agent_grid import html_table, interval_cell, results_table, study_results
from skidnav.studies.generalisation.evaluation import (
    GeneralisationResult,
    Reference,
    Split,
    grid_split,
    references,
)
from skidnav.studies.generalisation.grid import LAYOUT, GeneralisationGrid

SUMMARY_HEADER = (
    "agent",
    "policy",
    "success, training maps",
    "success, held-out",
    "held-out − training",
    "length, held-out",
)
"""The columns of the summary table."""
_FLOAT_FIELDS = tuple(field.name for field in fields(GeneralisationResult))[4:]
"""The fields of a result after agent, seed, episodes and steps (floats)."""


def grid_references(grid: GeneralisationGrid) -> list[Reference]:
    """The reference policies on ``grid``'s split (deterministic: the split's own seeds)."""
    return references(grid_split(grid), grid.max_steps, grid.env_options)


def results_of(summaries: pd.DataFrame) -> list[GeneralisationResult]:
    """One result per run of a results directory's summaries (agent: the agent's label)."""
    return [
        GeneralisationResult(
            str(row["agent"]),
            int(row["seed"]),
            int(row["episodes"]),
            int(row["steps"]),
            *(float(row[name]) for name in _FLOAT_FIELDS),
        )
        for row in summaries.to_dict("records")
    ]


def summary_rows(results: Sequence[GeneralisationResult]) -> list[tuple[str, ...]]:
    """The summary table's rows (:data:`SUMMARY_HEADER`), agents in order of first run."""
    rng = np.random.default_rng(0)
    rows = []
    for name in dict.fromkeys(result.agent for result in results):
        mine = [result for result in results if result.agent == name]
        for policy, prefix in (("greedy", ""), ("ε-greedy", "epsilon_")):
            trained = [getattr(row, f"{prefix}success_training_maps") for row in mine]
            held_out = [getattr(row, f"{prefix}success_held_out_maps") for row in mine]
            cells = [
                interval_cell(bootstrap_interval(trained, rng)),
                interval_cell(bootstrap_interval(held_out, rng)),
                interval_cell(difference_interval(held_out, trained, rng)),
                interval_cell(bootstrap_interval([row.length_held_out_maps for row in mine], rng))
                if not prefix
                else "",
            ]
            rows.append((name, policy, *cells))
    return rows


def summary_text(results: Sequence[GeneralisationResult]) -> str:
    """The summary table as fixed-width text."""
    lines = [f"{SUMMARY_HEADER[0]:18s} {SUMMARY_HEADER[1]:>10s} "
             + " ".join(f"{name:>24s}" for name in SUMMARY_HEADER[2:])]  # fmt: skip
    for name, policy, *cells in summary_rows(results):
        lines.append(f"{name:18s} {policy:>10s} " + " ".join(f"{cell:>24s}" for cell in cells))
    return "\n".join(lines)


def run_line(result: GeneralisationResult) -> str:
    """One run's results in one line."""
    return (
        f"  {result.agent} seed {result.seed}: {result.steps} steps; success on training maps "
        f"{result.success_training_maps:.2f}, held-out {result.success_held_out_maps:.2f} "
        f"(greedy), {result.epsilon_success_training_maps:.2f}, "
        f"{result.epsilon_success_held_out_maps:.2f} (ε-greedy)"
    )


def split_line(split: Split) -> str:
    """The world seeds of both sides of the split."""
    return f"training worlds {list(split.training)}; held-out worlds {list(split.held_out)}"


def reference_line(reference: Reference) -> str:
    """A reference policy's shares in one line."""
    return (
        f"reference {reference.policy:12s} success, training maps "
        f"{reference.success_training_maps:.2f}, held-out {reference.success_held_out_maps:.2f}"
    )


def report_section(run_dir: Path) -> str:
    """The study's section of the HTML report of ``run_dir`` (UserError if it is not a
    generalisation study's results directory)."""
    grid, summaries = study_results(run_dir, LAYOUT)
    results = results_of(summaries)
    summary = [dict(zip(SUMMARY_HEADER, row, strict=True)) for row in summary_rows(results)]
    shares = [
        {"policy": ref.policy, "success, training maps": f"{ref.success_training_maps:.2f}",
         "success, held-out": f"{ref.success_held_out_maps:.2f}"}
        for ref in grid_references(grid)
    ]  # fmt: skip
    note = (
        f"{grid.training_maps} training and {grid.held_out_maps} held-out {grid.map_kind} maps "
        f"on the {grid.slip} floor (root seed {grid.root_seed}); {grid.episodes} training "
        f"episodes of at most {grid.max_steps} actions per run; {grid.rollouts} rollouts per "
        f"map, greedy and ε-greedy (ε {grid.eval_epsilon}). Means over the {len(results)} "
        "finished runs with 95 % bootstrap intervals; n/a: no rollout reached the goal. The "
        "reference policies learn nothing (measured for this report on the same maps and "
        "rollout seeds). docs/generalisation.md."
    )
    return (
        "<h2>Generalisation to maps never seen</h2>"
        f"<p class='note'>{escape(note)}</p>"
        + html_table(summary)
        + "<h3>Reference policies</h3>"
        + html_table(shares)
        + "<h3>Runs</h3>"
        + results_table(results)
    )
