"""How fast the arms of a hardware-in-the-loop study learn on the robot: the markdown tables of
robot episodes and seconds of driving to the first success and to sustained success
(docs/realtime.md, "From simulation to the robot in a study").

Per run, from its summary (:func:`skidnav.studies.hardware.trial.run_summary`): the episode of
the first goal and the last episode of the first 10 consecutive robot episodes with at least 9
goals (:func:`~skidnav.experiments.metrics.window_success_episode`), and the seconds of driving
up to them (actions × the action's duration, homing not counted). A run that never got there is
*censored* at its last episode (its whole driving time). Per arm and preset: the Kaplan–Meier
median with its percentile-bootstrap interval over seeds
(:func:`~skidnav.statistics.survival.median_interval`; ∞ when more than half of the runs are
censored). Each arm against its reference (:meth:`~skidnav.studies.hardware.grid.StudyGrid.
references`: a pre-trained arm against the same agent from scratch), paired by (preset, seed),
both having met the same world: the speed-up, the reference's KM median over the arm's
(:func:`~skidnav.statistics.survival.speedup_interval`, a bound when a side's median is
censored), and the difference of the restricted means (each time capped at its run's end, where
a censored run stands; :func:`~skidnav.experiments.report.analysis.paired_difference`). Every
interval draws from its own generator keyed by the root seed and the cell's labels
(:func:`~skidnav.experiments.report.analysis.stats_rng`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from skidnav.experiments.report.analysis import aggregate, paired_difference, stats_rng
from skidnav.statistics.formatting import interval, readable
from skidnav.statistics.survival import median_interval, speedup_interval
from skidnav.studies.hardware.grid import StudyGrid

TARGETS = (("first_success", "first success"), ("success90", "≥ 90 %"))
"""(column suffix, words) of the two learning times."""
UNITS = (("episodes", "episodes", "episodes"), ("seconds", "driving_seconds", "driving [s]"))
"""(column prefix, censoring column, words) of the two units."""


def _runs(summaries: pd.DataFrame, agent: str, preset: str) -> pd.DataFrame:
    """``agent``'s runs of ``preset``, by seed."""
    rows = summaries[(summaries["agent"] == agent) & (summaries["preset"] == preset)]
    return rows.sort_values("seed")


def censored(rows: pd.DataFrame, column: str, limit: str) -> tuple[np.ndarray, np.ndarray]:
    """(times, observed) of ``rows``: ``column`` where reached (observed 1), else the run's
    ``limit`` (its last episode, or its whole driving time: observed 0)."""
    values = rows[column].to_numpy(np.float64)
    observed = np.isfinite(values)
    times = np.where(observed, values, rows[limit].to_numpy(np.float64))
    return times, observed.astype(np.float64)


def _median(rows: pd.DataFrame, column: str, limit: str, grid: StudyGrid, *keys: str) -> str:
    """KM median of ``column`` (censored at ``limit``) with its interval, whole numbers."""
    median = median_interval(
        *censored(rows, column, limit), stats_rng(grid, *keys),
        n_resamples=grid.bootstrap_samples, confidence=grid.confidence,
    )  # fmt: skip
    return interval(*median, digits=0)


def _arm_table(summaries: pd.DataFrame, grid: StudyGrid) -> str:
    header = " | ".join(f"{words} to {target}" for _, target in TARGETS for _, _, words in UNITS)
    lines = [
        f"| arm | preset | runs | reached first success | reached ≥ 90 % | {header} "
        "| collisions / episode |",
        "|---|---|---:|---:|---:|" + "---:|" * (len(TARGETS) * len(UNITS) + 1),
    ]
    collisions = aggregate(summaries, grid, ("collisions_per_episode",))
    for agent in grid.agent_labels:
        for preset in grid.presets:
            rows = _runs(summaries, agent, preset)
            if rows.empty:
                continue
            reached = [
                f"{int(np.isfinite(rows[f'episodes_to_{key}']).sum())}/{len(rows)}"
                for key, _ in TARGETS
            ]
            cells = [
                _median(rows, f"{unit}_to_{key}", limit, grid, preset, agent, unit, key)
                for key, _ in TARGETS
                for unit, limit, _ in UNITS
            ]
            cell = collisions[(collisions["agent"] == agent) & (collisions["preset"] == preset)]
            mean = cell.iloc[0]
            hits = interval(mean["mean"], mean["mean_low"], mean["mean_high"], seeds=len(rows))
            lines.append(
                f"| {agent} | {preset} | {len(rows)} | {' | '.join(reached)} "
                f"| {' | '.join(cells)} | {hits} |"
            )
    return "\n".join(lines)


def _restricted(rows: pd.DataFrame) -> pd.DataFrame:
    """``rows`` with each learning time capped at its run's end (censored runs there), as
    ``…_restricted`` columns."""
    capped = rows.copy()
    for key, _ in TARGETS:
        for unit, limit, _ in UNITS:
            times, _ = censored(rows, f"{unit}_to_{key}", limit)
            capped[f"{unit}_to_{key}_restricted"] = times
    return capped


def _comparison_cells(
    rows: pd.DataFrame, agent: str, reference: str, grid: StudyGrid, preset: str
) -> tuple[list[str], int]:
    """(cells, pairs) of ``agent`` against ``reference`` on ``preset``'s rows."""
    mine, theirs = _runs(rows, agent, preset), _runs(rows, reference, preset)
    paired = list(mine["seed"]) == list(theirs["seed"])
    capped = _restricted(rows)
    cells = []
    for key, _ in TARGETS:
        ratio = speedup_interval(
            *censored(theirs, f"episodes_to_{key}", "episodes"),
            *censored(mine, f"episodes_to_{key}", "episodes"),
            stats_rng(grid, preset, agent, reference, key, "speedup"), paired=paired,
            n_resamples=grid.bootstrap_samples, confidence=grid.confidence,
        )  # fmt: skip
        cells.append(ratio.words(1))
        for unit, _, _ in UNITS:
            column = f"{unit}_to_{key}_restricted"
            keys = (preset, agent, reference, column)
            difference, pairs, _ = paired_difference(capped, agent, reference, column, grid, *keys)
            cells.append(interval(*difference, digits=0, seeds=pairs))
    return cells, min(len(mine), len(theirs))


def _comparison_table(summaries: pd.DataFrame, grid: StudyGrid) -> str:
    columns = " | ".join(
        f"speed-up to {target} | Δ episodes to {target} | Δ driving to {target} [s]"
        for _, target in TARGETS
    )
    lines = [
        f"| arm | minus | preset | pairs | {columns} |",
        "|---|---|---|---:|" + "---:|" * (3 * len(TARGETS)),
    ]
    for agent, reference in grid.references().items():
        for preset in grid.presets:
            rows = summaries[summaries["preset"] == preset]
            if _runs(rows, agent, preset).empty or _runs(rows, reference, preset).empty:
                continue
            cells, pairs = _comparison_cells(rows, agent, reference, grid, preset)
            lines.append(f"| {agent} | {reference} | {preset} | {pairs} | {' | '.join(cells)} |")
    return "\n".join(lines) if len(lines) > 2 else "(no arm to compare)"


def _pretraining_table(summaries: pd.DataFrame, grid: StudyGrid) -> str:
    lines = [
        "| arm | preset | runs | simulator episodes | success, last 10 [%] | reached ≥ 90 % "
        "| its episode (median) | greedy success, last 10 evaluations [%] | robot episode 1 "
        "at the goal |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for agent in grid.agent_labels:
        episodes = grid.pretraining(agent)
        for preset in grid.presets:
            rows = _runs(summaries, agent, preset)
            if episodes == 0 or rows.empty or "sim_success_last10" not in rows:
                continue
            reached = rows["sim_episodes_to_success90"].dropna()
            cells = [
                readable(100 * rows["sim_success_last10"].mean(), 1),
                f"{len(reached)}/{len(rows)}",
                readable(reached.median() if len(reached) else None, 0),
                readable(100 * rows["sim_greedy_success"].mean(), 1),
                f"{int((rows['episodes_to_first_success'] == 1).sum())}/{len(rows)}",
            ]
            lines.append(f"| {agent} | {preset} | {len(rows)} | {episodes} | {' | '.join(cells)} |")
    return "\n".join(lines)


def speed_report(summaries: pd.DataFrame, grid: StudyGrid) -> str:
    """The markdown of the module doc (empty for results recorded before these columns)."""
    if "episodes_to_success90" not in summaries.columns:
        return ""
    level = round(100 * grid.confidence)
    parts = [
        "\n## Robot episodes to success\n",
        "≥ 90 %: the last episode of the first 10 consecutive robot episodes with at least 9 "
        f"goals. Kaplan–Meier medians over seeds with {level} % bootstrap intervals; a run "
        "that never got there is censored at its end (∞: more than half were). Driving: "
        "actions × their duration [s of robot time], homing not counted.\n",
        _arm_table(summaries, grid),
    ]
    if any(grid.sim_episodes):
        parts += [
            "\n## Pre-training in the simulator\n",
            "Mean over runs; ≥ 90 %: 9 goals in 10 consecutive simulator episodes, as on the "
            "robot; greedy: 5 rollouts after each simulator episode.\n",
            _pretraining_table(summaries, grid),
        ]
    if grid.references():
        parts += [
            "\n## Against the reference (paired by preset and seed)\n",
            "Speed-up: the reference's Kaplan–Meier median episodes over the arm's (> 1: the "
            "arm learns in fewer robot episodes; ≥ or ≤ when a median is censored). Δ: the arm "
            "minus the reference, each time capped at its run's end (restricted means).\n",
            _comparison_table(summaries, grid),
        ]
    return "\n".join(parts) + "\n"
