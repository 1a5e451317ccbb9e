"""The continuity comparison over many worlds: the results directories of several continuity
studies (one world each, e.g. ``--world-seed 0`` … ``9``), pooled learner by learner
(docs/continuity.md, "Ten obstacle worlds").

A learner is told apart by its name and its training budget (real episodes used), so the same
learner given different budgets in different studies stays two rows. Per learner:

* **worlds**, **runs**: how many of each hold its runs (the goal tracker's runs of a world are
  alike: one counts);
* **success** [%]: the share of its final policy's rollouts that reached the goal, the mean over
  the worlds of each world's share, with a 95 % percentile-bootstrap interval over the worlds
  (:func:`skidnav.statistics.intervals.bootstrap_interval`; the worlds are the units, the rollouts
  of one world
  share its walls);
* **worlds ≥ 90 %**: the worlds where its rollouts reached the goal in at least 90 %;
* **real episodes to learn**: the runs whose checks all reached the goal within the budget, and
  the median and largest episode after which they first did.

``python -m skidnav.studies.continuity.worlds DIR …`` prints both tables as Markdown: one row per
world and learner, then the pooled rows.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from skidnav.statistics.intervals import bootstrap_interval
from skidnav.studies.continuity.results import read_results

GOOD_WORLD = 0.9
"""The share of rollouts at the goal that makes a world one a learner masters."""


def world_rows(run_dirs: Sequence[Path | str]) -> pd.DataFrame:
    """One row per (world, learner, budget) of the studies in ``run_dirs``: ``world`` (the world
    seed), ``map``, ``learner``, ``episodes_used``, ``runs``, ``success`` (share of the rollouts
    at the goal), ``learned`` (runs that learned), ``to_learn_median`` and ``to_learn_max``
    [episodes] (of those runs; NaN if none) and ``to_learn`` (their episodes, a list),
    ``time_to_goal`` [s] (mean over the successes)."""
    rows = []
    for run_dir in run_dirs:
        results = read_results(run_dir)
        config = results.config
        for learner, traces in results.traces.items():
            runs = results.runs[results.runs["learner"] == learner]
            learned = runs["episodes_to_learn"].dropna()
            times = [trace.n_actions * trace.control_period for trace in traces if trace.terminated]
            rows.append({
                "world": config.world_seed, "map": config.map_kind, "learner": learner,
                "episodes_used": int(runs["episodes_used"].median()), "runs": len(runs),
                "success": float(np.mean([trace.terminated for trace in traces])),
                "learned": len(learned),
                "to_learn_median": float(learned.median()) if len(learned) else math.nan,
                "to_learn_max": float(learned.max()) if len(learned) else math.nan,
                "to_learn": [float(value) for value in learned],
                "time_to_goal": float(np.mean(times)) if times else math.nan,
            })  # fmt: skip
    return pd.DataFrame(rows).sort_values(["learner", "episodes_used", "world"], kind="stable")


def pooled(rows: pd.DataFrame, rng: np.random.Generator) -> pd.DataFrame:
    """The rows of :func:`world_rows` pooled per (learner, budget) (module doc), the bootstrap
    resamples drawn from ``rng``."""
    pooled_rows = []
    for (learner, used), group in rows.groupby(["learner", "episodes_used"], sort=False):
        success = bootstrap_interval(group["success"].to_numpy(), rng)
        learned = [value for values in group["to_learn"] for value in values]
        pooled_rows.append({
            "learner": learner, "episodes_used": used, "worlds": len(group),
            "runs": int(group["runs"].sum()), "success": success.estimate,
            "success_low": success.low, "success_high": success.high,
            "worlds_good": int((group["success"] >= GOOD_WORLD).sum()),
            "learned": int(group["learned"].sum()),
            "to_learn_median": float(np.median(learned)) if learned else math.nan,
            "to_learn_max": max(learned) if learned else math.nan,
        })  # fmt: skip
    return pd.DataFrame(pooled_rows)


def _number(value: float, digits: int = 0) -> str:
    return "–" if not math.isfinite(value) else f"{value:.{digits}f}"


def markdown(rows: pd.DataFrame, table: pd.DataFrame) -> str:
    """The per-world rows and the pooled table as Markdown."""
    lines = [
        "| world | learner | episodes used | success [%] | runs that learned | episodes to learn "
        "(median, max) | time to goal [s] |",
        "|---|---|---|---|---|---|---|",
    ]
    for row in rows.sort_values(["world", "learner"], kind="stable").to_dict("records"):
        lines.append(
            f"| {row['world']} | {row['learner']} | {row['episodes_used']} "
            f"| {100 * row['success']:.0f} | {row['learned']} of {row['runs']} "
            f"| {_number(row['to_learn_median'])}, {_number(row['to_learn_max'])} "
            f"| {_number(row['time_to_goal'], 1)} |"
        )
    lines += [
        "",
        "| learner | episodes used | worlds | runs | success [%] | worlds ≥ 90 % "
        "| runs that learned | episodes to learn (median, max) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for row in table.to_dict("records"):
        interval = (
            f" [{100 * row['success_low']:.0f}, {100 * row['success_high']:.0f}]"
            if math.isfinite(row["success_low"])
            else ""
        )
        lines.append(
            f"| {row['learner']} | {row['episodes_used']} | {row['worlds']} | {row['runs']} "
            f"| {100 * row['success']:.0f}{interval} | {row['worlds_good']} of {row['worlds']} "
            f"| {row['learned']} of {row['runs']} "
            f"| {_number(row['to_learn_median'])}, {_number(row['to_learn_max'])} |"
        )
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str]) -> int:
    """Print the tables of the results directories ``argv``."""
    if not argv:
        print("usage: python -m skidnav.studies.continuity.worlds RUN_DIR ...", file=sys.stderr)
        return 2
    rows = world_rows(argv)
    print(markdown(rows, pooled(rows, np.random.default_rng(0))), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
