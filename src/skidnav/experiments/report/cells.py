"""The per-cell part of an experiment report (one map × preset cell): its aggregate table, the
greedy path lengths against the oracle, learning curves, per-seed metrics, and the pictures of
its first seed's worlds (final greedy trajectories, one animated, value and policy maps), each a
:data:`Part` drawn when the report gets to it (:func:`skidnav.experiments.report.html.build_report`
shows them in its progress bar).
"""

from __future__ import annotations

import html
from collections.abc import Callable
from functools import partial

import numpy as np
import pandas as pd

from skidnav.experiments.config import ExperimentConfig
from skidnav.experiments.report import maps, plots
from skidnav.experiments.report.analysis import METRICS
from skidnav.experiments.report.page import gif_image, image, interval_text, table
from skidnav.experiments.store import ResultStore, TrialResult
from skidnav.physics.materials import region_materials
from skidnav.physics.render import Arena, animate, describe
from skidnav.robot.floors import PRESET_FLOORS
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SlipField
from skidnav.statistics.formatting import plural

Part = tuple[str, Callable[[], str]]
"""A step of the report: (what it draws, the function drawing its HTML)."""

ANIMATION_FRAMES = 90
"""Frames of the report's animations (about 16 ms each for MuJoCo on a CPU renderer)."""


def aggregate_table(aggregates: pd.DataFrame, map_label: str, preset: str) -> str:
    """Mean [CI] and IQM [CI] of every metric per agent for one cell."""
    rows = aggregates[(aggregates["map"] == map_label) & (aggregates["preset"] == preset)]
    records = []
    for metric, title in METRICS.items():
        record = {"metric": title}
        for _, r in rows[rows["metric"] == metric].iterrows():
            for kind, label in (("mean", "mean"), ("iqm", "IQM")):
                record[f"{r['agent']} {label}"] = interval_text(
                    float(r[kind]), float(r[f"{kind}_low"]), float(r[f"{kind}_high"])
                )
        records.append(record)
    return table(pd.DataFrame.from_records(records))


def animated_run(runs: list[TrialResult], baseline: str) -> tuple[TrialResult, str]:
    """The run to animate, and why: the non-baseline agent whose final greedy rollout reached
    the goal in the fewest actions, else the first run."""
    reached = [
        run
        for run in runs
        if run.coordinates["agent"] != baseline
        and run.summary["final_length_m"] == run.summary["final_length_m"]  # not NaN
    ]
    if not reached:
        return runs[0], "the first agent; no other agent's greedy rollout reached the goal"
    best = min(reached, key=lambda run: len(run.arrays["greedy_poses"]))
    return best, "the shortest final greedy path of the agents other than the baseline"


def animation_figure(run: TrialResult, preset: str, why: str) -> str:
    """The animated final greedy trajectory of ``run`` with its caption."""
    robot = RobotParams()
    eta = np.asarray(run.arrays["slip_eta"], dtype=np.float64)
    start, goal = run.arrays["start"], run.arrays["goal"]
    materials = None
    if preset in PRESET_FLOORS:
        field = SlipField(eta, np.zeros_like(eta), drift_phase=np.zeros_like(eta))
        materials = region_materials(preset, field, robot)
    arena = Arena(
        run.arrays["occupancy"],
        (int(start[0]), int(start[1])),
        (int(goal[0]), int(goal[1])),
        slip_eta=eta,
        materials=materials,
        robot=robot,
    )
    poses = np.asarray(run.arrays["greedy_poses"], dtype=np.float64)
    movie = animate(arena, poses, frames_per_action=3, max_frames=ANIMATION_FRAMES)
    caption = (
        f"Final greedy trajectory of {run.coordinates['agent']} (seed "
        f"{run.coordinates['seed']}, {plural(len(poses) - 1, 'action')}; {why}), animated by the "
        f"{describe(movie)}. Start: green cell, goal: red cell, path so far: blue."
    )
    return (
        f"<figure>{gif_image(movie.gif, 'animated greedy trajectory')}"
        f"<figcaption class='note'>{html.escape(caption)}</figcaption></figure>"
    )


def figure(draw: Callable[[], bytes], alt: str, before: str = "") -> str:
    """``before``, then the <img> of the PNG ``draw`` returns."""
    return before + image(draw(), alt)


def cell_parts(
    store: ResultStore,
    config: ExperimentConfig,
    tables: tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame],
    cell: tuple[str, str],
) -> list[Part]:
    """The steps of one cell's section: its heading and aggregate table with the greedy
    lengths, learning curves, per-seed metrics, then the pictures of its first seed's worlds
    (:func:`world_parts`). ``tables``: (episodes, summaries, aggregates)."""
    episodes, summaries, aggregates = tables
    map_label, preset = cell
    name = f"{map_label} · {preset}"
    heading = f"<h2>Map {html.escape(map_label)} · preset {html.escape(preset)}</h2>"
    heading += aggregate_table(aggregates, map_label, preset)
    greedy = partial(plots.greedy_lengths, episodes, summaries, config, cell)
    curves = partial(plots.learning_curves, episodes, config, map_label, preset)
    strips = partial(plots.metric_strips, summaries, aggregates, config, map_label, preset)
    parts: list[Part] = [
        (f"{name}: greedy lengths", partial(figure, greedy, "greedy lengths", heading)),
        (f"{name}: learning curves", partial(figure, curves, "learning curves")),
        (f"{name}: metrics", partial(figure, strips, "metrics")),
    ]
    return parts + world_parts(first_seed_runs(store, summaries, config, cell), config, cell)


def first_seed_runs(
    store: ResultStore, summaries: pd.DataFrame, config: ExperimentConfig, cell: tuple[str, str]
) -> list[TrialResult]:
    """Every agent's run of the cell's first seed that recorded its arena (none for an env of
    its own)."""
    rows = summaries[(summaries["map"] == cell[0]) & (summaries["preset"] == cell[1])]
    first_seed = int(rows["seed"].min())
    run_ids = [
        str(mine.iloc[0]["run_id"])
        for agent in config.agent_labels
        if not (mine := rows[(rows["agent"] == agent) & (rows["seed"] == first_seed)]).empty
    ]
    return [run for run in store.iter_runs(run_ids) if "occupancy" in run.arrays]


def world_parts(
    runs: list[TrialResult], config: ExperimentConfig, cell: tuple[str, str]
) -> list[Part]:
    """The steps drawing the worlds of ``runs`` (one seed of a cell): final greedy trajectories,
    one of them animated, value maps and greedy-policy maps (of the runs that recorded them)."""
    if not runs:
        return []
    name = f"{cell[0]} · {cell[1]}"
    title = f"{name}, seed {runs[0].coordinates['seed']}"
    paths = partial(
        maps.trajectories, runs, f"final greedy trajectories, {title} (shading: slip η)"
    )
    animated, why = animated_run(runs, config.baseline)
    parts: list[Part] = [
        (f"{name}: trajectories", partial(figure, paths, "trajectories")),
        (f"{name}: animation", partial(animation_figure, animated, cell[1], why)),
    ]
    tabular = [run for run in runs if "value_map" in run.arrays]  # agents with a Q table
    if tabular:
        values = partial(maps.value_maps, tabular, f"state values and preferred headings, {title}")
        parts.append((f"{name}: value maps", partial(figure, values, "value maps")))
    with_policy = [run for run in runs if "policy_map" in run.arrays]  # older files have none
    if with_policy:
        actions = partial(
            maps.policy_maps, with_policy, f"greedy action at the start heading, {title}"
        )
        parts.append((f"{name}: policy maps", partial(figure, actions, "policy maps")))
    return parts
