"""The continuity study's results read back from its results directory: the runs, every
learner's rollouts, the comparison table with bootstrap intervals, its markdown and the
trajectory picture (docs/continuity.md, "Measured comparison").

Everything here comes from the run files (:mod:`skidnav.studies.continuity.runfile`), so the
tables of a study run by ``skidnav run`` on any backend, resumed or not, are those of the same
config run in one go. The goal tracker learns nothing: its runs are alike, and the tables count
its first. Written by ``skidnav study continuity`` (:func:`write_outputs`: ``runs.csv``,
``table.csv``, ``table.md``, ``trajectories.png``) and drawn in the study's report
(:func:`report_section`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any, NamedTuple

import gymnasium
import numpy as np
import pandas as pd

from skidnav.envs.registration import ENV_ID
from skidnav.errors import UserError
from skidnav.experiments.report.page import image, markdown_html, table
from skidnav.experiments.store import ResultStore
from skidnav.files.atomic import write_user_file
from skidnav.studies.continuity.comparison import REFERENCE, ComparisonConfig
from skidnav.studies.continuity.runfile import CONTINUITY_LAYOUT, traces_of
from skidnav.studies.continuity.traces import Trace, comparison_table
from skidnav.studies.continuity.trajectory_plot import trajectory_picture

SHOWN = ("success", "time_to_goal", "path_length", "wheel_change", "reversals_per_metre", "energy")
"""The metrics of the markdown table, in order."""
RUN_COLUMNS = ("episodes_used", "episodes_to_learn", "wall_time", "success", "run_seed")
"""The summary columns of the runs table (after learner and seed index)."""


class ComparisonResults(NamedTuple):
    """A comparison as its results directory holds it.

    Attributes:
        config: the comparison.
        runs: one row per learner run: ``learner``, ``seed`` (index), :data:`RUN_COLUMNS`.
        traces: learner → every rollout of its runs, in config order.
        table: :func:`~skidnav.studies.continuity.traces.comparison_table` of ``traces``, its
            resamples drawn from ``default_rng(root_seed)``.
    """

    config: ComparisonConfig
    runs: pd.DataFrame
    traces: dict[str, list[Trace]]
    table: pd.DataFrame


def read_results(run_dir: Path | str) -> ComparisonResults:
    """The comparison of the finished runs in ``run_dir``.

    Raises:
        UserError: not a continuity results directory, or no finished run.
        CorruptFileError: a damaged file, named.
    """
    store = ResultStore(run_dir, CONTINUITY_LAYOUT)
    config: ComparisonConfig = store.config()
    rows: list[dict[str, Any]] = []
    traces: dict[str, list[Trace]] = {}
    for result in store.iter_runs():  # in id order: learner by learner, seed by seed
        learner = str(result.coordinates["agent"])
        if learner == REFERENCE and learner in traces:
            continue
        traces.setdefault(learner, []).extend(traces_of(result))
        summary = {key: result.summary[key] for key in RUN_COLUMNS}
        rows.append({"learner": learner, "seed": result.coordinates["seed"], **summary})
    if not rows:
        raise UserError(f"{run_dir}: no finished runs")
    ordered = {learner: traces[learner] for learner in config.learners if learner in traces}
    comparison = comparison_table(ordered, np.random.default_rng(config.root_seed))
    return ComparisonResults(config, pd.DataFrame(rows), ordered, comparison)


def _cell(row: Mapping[Any, Any]) -> str:
    if not math.isfinite(row["mean"]):
        return "–"
    scale = 100.0 if row["metric"] == "success" else 1.0
    if math.isnan(row["low"]):
        return f"{scale * row['mean']:.2f}"
    return f"{scale * row['mean']:.2f} [{scale * row['low']:.2f}, {scale * row['high']:.2f}]"


def markdown(results: ComparisonResults) -> str:
    """The comparison as one markdown table: a row per learner."""
    config, runs = results.config, results.runs
    header = ["learner", "runs", "episodes used", "episodes to learn (runs that did)"]
    header += [
        "success [%]", "time to goal [s]", "path [m]", "wheel change Δω [rad/s]",
        "reversals [1/m]", "energy [rad²/s]",
    ]  # fmt: skip
    lines = [
        f"{config.map_kind} world {config.world_seed}, slip {config.slip}, {config.max_steps} "
        f"actions of {config.control_period:g} s, {config.rollouts} rollouts per run on shared "
        "seeds; means with 95 % bootstrap intervals over every rollout.\n",
        "| " + " | ".join(header) + " |",
        "|" + "---|" * len(header),
    ]
    for learner, cells in results.table.groupby("policy", sort=False):
        learner_runs = runs[runs["learner"] == learner]
        learned = learner_runs["episodes_to_learn"].dropna()
        to_learn = f"{learned.median():g} ({len(learned)})" if len(learned) else "– (0)"
        by_metric = {row["metric"]: row for row in cells.to_dict("records")}
        values = [_cell(by_metric[name]) for name in SHOWN]
        lines.append(
            f"| {learner} | {len(learner_runs)} | {int(learner_runs['episodes_used'].median())} "
            f"| {to_learn} | {' | '.join(values)} |"
        )
    return "\n".join(lines) + "\n"


def picture(results: ComparisonResults) -> bytes:
    """PNG of each learner's first rollout of its first run on the arena."""
    config = results.config
    env = gymnasium.make(ENV_ID, **config.env_kwargs(False))
    grid_map = env.unwrapped.grid_map  # type: ignore[attr-defined]
    env.close()
    firsts = {name: traces[0] for name, traces in results.traces.items()}
    title = f"{config.map_kind} world {config.world_seed}, {config.slip}"
    return trajectory_picture(grid_map, firsts, title=title)


def write_outputs(out: Path, results: ComparisonResults) -> None:
    """``runs.csv``, ``table.csv``, ``table.md`` and ``trajectories.png`` in ``out``, each
    written all-or-nothing."""
    write_user_file(out / "runs.csv", results.runs.to_csv(index=False).encode(), "runs")
    write_user_file(out / "table.csv", results.table.to_csv(index=False).encode(), "table")
    write_user_file(out / "table.md", markdown(results).encode(), "table")
    write_user_file(out / "trajectories.png", picture(results), "picture")


def report_section(run_dir: Path | str) -> str:
    """The study's section of the report of ``run_dir``: the comparison table, the picture and
    the runs (an HTML fragment)."""
    results = read_results(run_dir)
    return (
        "<h2>What continuity buys</h2>"
        + markdown_html(markdown(results))
        + image(picture(results), "each learner's first rollout on the arena")
        + "<h3>Runs</h3>"
        + table(results.runs)
    )
