"""The discretization-gap table (docs/discretization-gap.md): per agent and state grid, the
success rate, the convergence episode (Kaplan–Meier, censored runs as censored), the final
greedy path length [m] and its gap to the world's continuous optimum
(:mod:`skidnav.experiments.reference.optimum`), and the optimum with its convergence check.

A section of ``skidnav report`` (:func:`gap_section`, one of the experiment report's extra
sections, :func:`skidnav.studies.kind.experiment_sections`) when the runs hold optimum columns
(``[experiment] optimum_grids``); ``python -m skidnav.studies.gap RUN_DIR`` prints the same
tables as Markdown.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

import numpy as np
import pandas as pd

from skidnav.agents.catalog import entry
from skidnav.errors import UserError
from skidnav.experiments.config import ExperimentConfig
from skidnav.experiments.report.analysis import aggregate, cells, convergence_table
from skidnav.experiments.report.page import interval_text
from skidnav.experiments.store import ResultStore
from skidnav.experiments.trial import config_map
from skidnav.world.discretization import Discretization

GAP_METRICS = (
    "success_rate",
    "success_rate_last10",
    "final_length_m",
    "gap_to_optimum",
    "final_length_actions",
    "gap_in_actions",
    "oracle_length",
)
"""Summary columns of the table; two are derived per run, so paired with its own world's
optimum: ``gap_to_optimum`` = final_length_m / optimum_length_m − 1 and ``gap_in_actions`` =
final_length_actions / optimum_rollout_actions − 1."""


def has_optimum(summaries: pd.DataFrame) -> bool:
    """True if the runs measured a continuous optimum."""
    return "optimum_length_m" in summaries and bool(summaries["optimum_length_m"].notna().any())


def grid_text(config: ExperimentConfig, label: str, map_label: str) -> str:
    """The state grid agent ``label`` learns over on map ``map_label``, e.g. ``"25 × 25 × 20"``
    (its ``discretization``, else the map's cells and the env's default heading bins)."""
    agent = next(a for a in config.agents if a.label == label)
    described = entry(agent.name)
    if described.observation == "box":
        observation = described.env_observation(dict(config.env_options).get("observation"))
        return f"continuous ({observation})"
    levels = agent.discretization
    if not levels:
        spec = next(m for m in config.maps if m.label == map_label)
        shape = config_map(spec, np.random.default_rng(0)).shape
        levels = (*shape, Discretization().n_headings)
    return " × ".join(str(v) for v in levels)


def _interval(frame: pd.DataFrame, metric: str, scale: float = 1.0, digits: int = 2) -> str:
    row = frame[frame["metric"] == metric].iloc[0]
    low, high = float(row["mean_low"]), float(row["mean_high"])
    return interval_text(float(row["mean"]) * scale, low * scale, high * scale, digits)


def gap_rows(summaries: pd.DataFrame, config: ExperimentConfig) -> pd.DataFrame:
    """One row of text cells per (map, preset, agent): grid, success, convergence, final
    length [m] and its gap [%] with 95 % bootstrap intervals over seeds."""
    frame = summaries.copy()
    frame["gap_to_optimum"] = frame["final_length_m"] / frame["optimum_length_m"] - 1.0
    frame["gap_in_actions"] = frame["final_length_actions"] / frame["optimum_rollout_actions"] - 1.0
    aggregates = aggregate(frame, config, GAP_METRICS)
    convergence = convergence_table(frame, config)
    records = []
    for _, row in convergence.iterrows():
        where = ["map", "preset", "agent"]
        mine = aggregates[(aggregates[where] == row[where]).all(axis=1)]
        reached = int(mine[mine["metric"] == "final_length_m"]["n"].iloc[0])
        records.append({
            "map · preset": f"{row['map']} · {row['preset']}",
            "agent": row["agent"], "grid": grid_text(config, str(row["agent"]), str(row["map"])),
            "success rate [%]": _interval(mine, "success_rate", 100.0, 1),
            "success, last 10 % [%]": _interval(mine, "success_rate_last10", 100.0, 1),
            "converged": f"{round(row['converged'] * row['n'])} / {row['n']}",
            "median convergence episode": _median_text(row),
            "final length [m]": f"{_interval(mine, 'final_length_m', 1.0, 3)} ({reached} of "
            f"{row['n']} reached)",
            "gap to optimum [%]": _interval(mine, "gap_to_optimum", 100.0, 1),
            "final length [actions]": _interval(mine, "final_length_actions", 1.0, 1),
            "gap in actions [%]": _interval(mine, "gap_in_actions", 100.0, 1),
            "L* of its grid [actions]": _interval(mine, "oracle_length", 1.0, 2),
        })  # fmt: skip
    return pd.DataFrame.from_records(records)


def _median_text(row: pd.Series) -> str:
    """KM median [interval]; "> T (censored)" when more than half of the runs never converged."""
    if not np.isfinite(row["median"]):
        return f"> {row['censored_at']:.0f} (censored)"
    return interval_text(row["median"], row["median_low"], row["median_high"], 0)


def _grid_names(config: ExperimentConfig) -> list[str]:
    """The ``optimum_grids`` as text, e.g. ``["97 × 97 × 80", …]``."""
    return [" × ".join(str(v) for v in levels) for levels in config.optimum_grids]


def _chosen(worlds: pd.DataFrame, config: ExperimentConfig) -> str:
    """Which grid gave the best policy, and in how many worlds: ``"97 × 97 × 80 (3)"``."""
    names = _grid_names(config)
    counts = worlds["optimum_grid"].astype(int).value_counts().sort_index()
    pairs = zip(counts.index.to_numpy(int), counts.to_numpy(int), strict=True)
    return ", ".join(f"{names[index]} ({count})" for index, count in pairs)


def optimum_rows(summaries: pd.DataFrame, config: ExperimentConfig) -> pd.DataFrame:
    """Per (map, preset): the continuous optimum over its worlds (one value per world, the mean
    shown), the grids whose policy it is, the same without the finest grid, and the largest
    change between the two (:mod:`skidnav.experiments.reference.optimum`)."""
    records = []
    for map_label, preset, rows in cells(summaries):
        worlds = rows.drop_duplicates("seed")
        change_m = (worlds["optimum_length_m"] / worlds["optimum_check_length_m"] - 1).abs()
        change_a = (
            worlds["optimum_rollout_actions"] / worlds["optimum_check_rollout_actions"] - 1
        ).abs()
        records.append({
            "map · preset": f"{map_label} · {preset}", "worlds": len(worlds),
            "optimum [m]": f"{worlds['optimum_length_m'].mean():.3f}",
            "optimum [actions]": f"{worlds['optimum_rollout_actions'].mean():.2f}",
            "its rollouts reaching the goal [%]": f"{100 * worlds['optimum_success'].mean():.0f}",
            "V*(start) of its grid [actions]": f"{worlds['optimum_actions'].mean():.2f}",
            "best grid (worlds)": _chosen(worlds, config),
            "without the finest grid [m] / [actions]":
                f"{worlds['optimum_check_length_m'].mean():.3f} / "
                f"{worlds['optimum_check_rollout_actions'].mean():.2f}",
            "largest change, m / actions [%]": f"{100 * change_m.max():.1f} / "
            f"{100 * change_a.max():.1f}",
        })  # fmt: skip
    return pd.DataFrame.from_records(records)


def gap_section(summaries: pd.DataFrame, config: ExperimentConfig) -> str:
    """The report's "Discretization gap" section (empty without optimum columns)."""
    if not has_optimum(summaries):
        return ""
    return (
        "<h2>Discretization gap</h2><p class='note'>Final length: the one greedy rollout after "
        "training (the runs that reached the goal); gap: per run, final length / its world's "
        "continuous optimum − 1. The optimum is the best policy of the oracle over the fine "
        "grids below (most rollouts reaching the goal, then fewest actions), its length the "
        "mean path of its rollouts; it minimizes actions, as the agents do. Convergence: "
        "against each run's own oracle L* (its own state grid; the 25 × 25 × 20 one for "
        "continuous agents), censored runs as censored. docs/discretization-gap.md.</p>"
        + gap_rows(summaries, config).to_html(index=False, escape=True, border=0)
        + optimum_rows(summaries, config).to_html(index=False, escape=True, border=0)
    )


def markdown(frame: pd.DataFrame) -> str:
    """A Markdown table of string cells."""
    lines = ["| " + " | ".join(frame.columns) + " |", "|" + "---|" * len(frame.columns)]
    lines += ["| " + " | ".join(str(v) for v in row) + " |" for row in frame.to_numpy()]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """Print the tables of a results directory as Markdown; exit code 2 on a bad directory."""
    args = list(sys.argv[1:] if argv is None else argv)
    if len(args) != 1:
        print("usage: python -m skidnav.studies.gap RUN_DIR", file=sys.stderr)
        return 2
    try:
        store = ResultStore(args[0])
        config = store.config()
        _, summaries = store.load_tables()
    except UserError as error:
        print(f"skidnav: error: {error}", file=sys.stderr)
        return 2
    if not has_optimum(summaries):
        print(f"skidnav: error: {args[0]}: no continuous optimum in these runs", file=sys.stderr)
        return 2
    print(markdown(gap_rows(summaries, config)))
    print()
    print(markdown(optimum_rows(summaries, config)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
