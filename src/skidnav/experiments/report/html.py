"""The experiment report: ONE self-contained HTML file (tables, base64 PNG figures, the config).

Sections: setup, metric definitions (with the convergence tolerance), thesis reproduction
(speed-up, success-rate gain, final-length difference, rough vs slippery floor), aggregate
tables, per-cell figures (learning curves, per-seed metrics, final greedy trajectories and one of
them animated (:mod:`skidnav.physics.render`), value maps with preferred headings, greedy-policy
maps), provenance (config, versions, sessions with their code versions). The numbers are what
was measured.

The page shell is shared with the studies' reports (:mod:`skidnav.experiments.report.page`). An
experiment report takes extra sections from its caller (:data:`ExperimentSection`: the commands
pass the studies' sections, e.g. the discretization-gap table, :mod:`skidnav.studies.kind`), so
this module imports no study.
"""

from __future__ import annotations

import html
import logging
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from skidnav.experiments.config import ExperimentConfig, config_to_dict
from skidnav.experiments.report import plots
from skidnav.experiments.report.analysis import (
    METRICS,
    aggregate,
    budget_rows,
    cells,
    compare_surfaces,
    compare_to_baseline,
    convergence_table,
    speedup_of,
    stats_rng,
    survival_columns,
)
from skidnav.experiments.report.page import (
    config_and_provenance,
    gif_image,
    image,
    interval_text,
    page,
    report_path,
    table,
    write_page,
)
from skidnav.experiments.report.reproduction import reproduction_section
from skidnav.experiments.store import ResultStore, TrialResult
from skidnav.physics.materials import region_materials
from skidnav.physics.render import Arena, animate, describe
from skidnav.robot.floors import PRESET_FLOORS
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SlipField
from skidnav.survival import performance_profile, profile_band

logger = logging.getLogger(__name__)

ExperimentSection = Callable[[pd.DataFrame, ExperimentConfig], str]
"""An extra section of an experiment report: the summaries (one row per run) and the config in,
an HTML fragment out (empty when it has nothing to show)."""


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


def definitions(config: ExperimentConfig) -> str:
    """The metric definitions, with this experiment's tolerance, window and interval settings."""
    tol, window, rollouts, level = (
        config.convergence_tolerance, config.convergence_window, config.eval_rollouts,
        config.convergence_level,
    )  # fmt: skip
    measured, optimum = (
        ("length", "L*") if config.convergence_objective == "actions"
        else ("cost (minus the reward without the goal bonus: the objective of the agents' "
              "reward)", "the oracle's C*, the least expected cost from the start")
    )  # fmt: skip
    return f"""<ul class="note">
<li><b>Oracle</b> L*: the expected number of actions from the start under the best policy of the
true transition model of the discretized MDP, estimated from the simulator itself
({config.oracle_samples} sampled poses per state and action) and solved by value iteration.</li>
<li><b>Evaluation</b>: after every training episode the greedy policy is rolled out
<b>{rollouts}</b> times from the start, each from a reset with one of {rollouts} fixed evaluation
seeds (the same after every episode and for every agent of a world).</li>
<li><b>Pass</b>: an evaluation passes when every rollout reaches the goal with a mean
{measured} within <b>{tol:.0%}</b> above {optimum}. (The oracle's own greedy policy over cells
can loop from the exact start pose; the share of its rollouts that reached the goal is the column
<code>oracle_rollout_success</code>: L* is a reference, not a policy every world lets a cell
policy follow.)</li>
<li><b>Convergence episode</b> (converged means it stays converged): the first passing episode e
from which the share of passing evaluations stays at least <b>{level:.0%}</b> to the end of the
run (over e … k for every k from e + {window - 1} on: at least <b>{window}</b> evaluations of
evidence). A run that passed for a while and then fell apart is not converged at its first good
stretch; a run with no such episode is <b>censored</b> at episode {config.episodes} − {window} + 1.
A longer run can only reveal that a policy did not stay (its convergence episode is the same or
later). Medians are Kaplan–Meier estimates; ∞ means more than half of the runs never converged.
<b>Pass share after convergence</b>: share of passing evaluations from the convergence episode
to the end; <b>after the first good window</b>: the same from the first {window} passes in a row
(the drift a first-window rule would hide); <b>last 10 %</b>: share of passing evaluations in
the last 10 % of episodes. Speed-up: KM median of the baseline / KM median of the agent; where
more than half of one side's runs are censored, its largest censoring time stands in for its
median and the speed-up is a bound: <b>≥</b> (baseline censored; no upper end), <b>≤</b> (agent
censored), or <b>unknown</b> (both). Probability of improvement (Agarwal et al. 2021):
the chance that a run of the agent converges before a run of the baseline, censored pairs scored
by Gehan's rule. The mean and IQM of the convergence episode below count censored runs at their
censoring time (biased low); use the medians for claims.</li>
<li><b>Optimality gap</b>: mean greedy length over the last {window} evaluations (rollouts that
reached the goal) / L* − 1.</li>
<li><b>Final greedy length</b>: actions (and metres travelled) of one greedy rollout from the start
after the last episode (the trajectory drawn below); only runs where it reached the goal, and
comparisons only over seeds where both agents' rollouts did.</li>
<li><b>Success rate</b>: share of training episodes that reached the goal within
{config.max_steps or "the environment's"} actions (all episodes, and the last 10 %).</li>
<li>Intervals: {config.confidence:.0%} percentile bootstrap over seeds,
{config.bootstrap_samples} resamples, seeded. IQM: mean of the middle 50 % of seeds.
Comparisons with the baseline <b>{html.escape(config.baseline)}</b> are paired by seed (every agent
meets the same maps and floors). "No significant difference" means the interval of the difference
contains 0; its width tells how large a difference could have gone unnoticed.</li></ul>"""


def convergence_section(
    summaries: pd.DataFrame, comparisons: pd.DataFrame, config: ExperimentConfig
) -> str:
    """Per cell: converged share and KM median of every agent, and its speed-up over the
    baseline with the censoring stated; then the performance profiles."""
    table_rows = convergence_table(summaries, config)
    records = []
    for _, row in table_rows.iterrows():
        match = comparisons[
            (comparisons["map"] == row["map"]) & (comparisons["preset"] == row["preset"])
            & (comparisons["agent"] == row["agent"])
        ] if not comparisons.empty else comparisons  # fmt: skip
        speedup, improvement = "baseline", ""
        if not match.empty:
            first = match.iloc[0]
            speedup = speedup_text(first)
            improvement = interval_text(
                float(first["improvement_probability"]),
                float(first["improvement_probability_low"]),
                float(first["improvement_probability_high"]),
            )
        records.append({
            "map · preset": html.escape(f"{row['map']} · {row['preset']}"),
            "agent": html.escape(str(row["agent"])),
            "converged": f"{round(row['converged'] * row['n'])} / {row['n']}",
            "median convergence episode": interval_text(
                row["median"], row["median_low"], row["median_high"], 0
            ),
            "speed-up": speedup, "P(improvement)": improvement,
        })  # fmt: skip
    frame = pd.DataFrame.from_records(records)
    return (
        "<h2>Convergence</h2>" + frame.to_html(index=False, escape=False, border=0)
        + calibration_text(summaries)
    )  # fmt: skip


def calibration_text(summaries: pd.DataFrame) -> str:
    """One paragraph on what the best computable policies do from the exact start of the
    experiment's worlds (:mod:`skidnav.experiments.reference.start_plan`); empty for runs without
    it."""
    if "start_plan_length" not in summaries.columns:
        return ""
    worlds = summaries.drop_duplicates(["map", "preset", "seed"])
    plans = worlds[np.isfinite(worlds["start_plan_length"])]
    if plans.empty:
        return ""
    ratio = (plans["start_plan_length"] / plans["oracle_length"]).median()
    passes = int((plans["start_plan_passes"] > 0.5).sum())
    oracle_all = int((worlds["oracle_rollout_success"] >= 1.0).sum())
    return (
        f"<p class='note'>Calibration over {len(worlds)} worlds: the fewest actions from the exact"
        f" start (the start plan, no slip noise) is a median {ratio:.0%} of L*; replayed from the"
        f" evaluation seeds it passes the test in {passes} of {len(plans)} worlds where it was"
        f" found. The oracle's greedy policy over cells reaches the goal from every evaluation"
        f" seed in {oracle_all} of {len(worlds)} worlds (from one exact pose it can loop).</p>"
    )


def performance_profiles(summaries: pd.DataFrame, config: ExperimentConfig) -> str:
    """Per cell, the share of runs converged by each episode, per agent, with bootstrap bands."""
    parts = []
    horizon = config.episodes
    episodes = np.unique(np.geomspace(1, horizon, 200).round())
    for map_label, preset, rows in cells(summaries):
        profiles = {}
        for agent in config.agent_labels:
            if rows[rows["agent"] == agent].empty:
                continue
            times, seen = survival_columns(rows, agent)
            rng = stats_rng(config, map_label, preset, agent, "profile")
            low, high = profile_band(
                times, seen, episodes, rng, n_resamples=config.bootstrap_samples,
                confidence=config.confidence,
            )  # fmt: skip
            profiles[agent] = (episodes, performance_profile(times, seen, episodes), low, high)
        title = f"converged by episode e · {map_label} · {preset}"
        parts.append(image(plots.performance_profiles(profiles, horizon, title), title))
    return "".join(parts)


def budget_section(
    comparisons: pd.DataFrame, aggregates: pd.DataFrame, config: ExperimentConfig
) -> str:
    """The speed-up against the planning budget with the wall time it costs, when some
    algorithm was run at two budgets or more; else nothing."""
    rows = budget_rows(comparisons, aggregates, config) if not comparisons.empty else None
    if (
        rows is None
        or rows.empty
        or rows.groupby("algorithm")["planning_steps"].nunique().max() < 2
    ):
        return ""
    parts = ["<h2>Planning budget</h2>"]
    for (map_label, preset), part in rows.groupby(["map", "preset"], sort=False):
        parts.append(f"<h3>{html.escape(f'{map_label} · {preset}')}</h3>")
        parts.append(image(plots.speedup_vs_budget(part), f"speed-up vs budget {map_label}"))
    return "".join(parts)


def speedup_text(row: pd.Series) -> str:
    """The speed-up of a comparison row in words (:meth:`SpeedupInterval.words`), with a colour
    class: green when its interval excludes 1 from above."""
    text = speedup_of(row).words(1)
    faster = float(row["speedup_low"]) > 1.0
    return f"<span class='{'yes' if faster else 'no'}'>{html.escape(text)}</span>"


def setup(config: ExperimentConfig, metadata: dict[str, object], n_runs: int) -> str:
    """The experiment grid in a few lines."""
    agents = ", ".join(html.escape(label) for label in config.agent_labels)
    maps = ", ".join(html.escape(m.label) for m in config.maps)
    return (
        f"<p>{html.escape(config.description)}</p><ul><li>agents: {agents}</li>"
        f"<li>maps: {maps}; slip presets: {', '.join(config.presets)}; drift amplitude "
        f"{config.drift_amplitude}</li><li>{config.seeds} seeds per cell, {config.episodes} "
        f"episodes per run, action limit {config.max_steps or 'env default'}; root seed "
        f"{config.root_seed}; {n_runs} runs finished of {config.n_runs}</li>"
        f"<li>environment {html.escape(config.env_id)}; git commit "
        f"{html.escape(str(metadata.get('git_commit')))}"
        f"{' (dirty)' if metadata.get('git_dirty') else ''}</li></ul>"
    )


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
        f"{run.coordinates['seed']}, {len(poses) - 1} actions; {why}), animated by the "
        f"{describe(movie)}."
    )
    return (
        f"<figure>{gif_image(movie.gif, 'animated greedy trajectory')}"
        f"<figcaption class='note'>{html.escape(caption)}</figcaption></figure>"
    )


def figures_for_cell(
    store: ResultStore,
    config: ExperimentConfig,
    episodes: pd.DataFrame,
    summaries: pd.DataFrame,
    aggregates: pd.DataFrame,
    map_label: str,
    preset: str,
) -> str:
    """Learning curves, per-seed metrics, trajectories, value and policy maps of one cell."""
    parts = [
        image(
            plots.learning_curves(
                episodes, config, map_label, preset, float(summaries["action_limit"].max())
            ),
            "learning curves",
        ),
        image(plots.metric_strips(summaries, aggregates, config, map_label, preset), "metrics"),
    ]
    cell = summaries[(summaries["map"] == map_label) & (summaries["preset"] == preset)]
    first_seed = int(cell["seed"].min())
    run_ids = [
        str(rows.iloc[0]["run_id"])
        for agent in config.agent_labels
        if not (rows := cell[(cell["agent"] == agent) & (cell["seed"] == first_seed)]).empty
    ]
    runs = [run for run in store.iter_runs(run_ids) if "occupancy" in run.arrays]
    if not runs:  # not the skid-steer env: no arena to draw
        return "\n".join(parts)
    title = f"{map_label} · {preset}, seed {first_seed}"
    parts.append(
        image(
            plots.trajectories(runs, f"final greedy trajectories, {title} (shading: slip η)"),
            "trajectories",
        )
    )
    animated, why = animated_run(runs, config.baseline)
    parts.append(animation_figure(animated, preset, why))
    tabular = [run for run in runs if "value_map" in run.arrays]  # agents with a Q table
    if tabular:
        parts.append(
            image(
                plots.value_maps(tabular, f"state values and preferred headings, {title}"),
                "value maps",
            )
        )
    with_policy = [run for run in runs if "policy_map" in run.arrays]
    if with_policy:  # older run files have no policy map
        parts.append(
            image(
                plots.policy_maps(with_policy, f"greedy action at the start heading, {title}"),
                "policy maps",
            )
        )
    return "\n".join(parts)


def build_report(run_dir: Path | str, sections: Sequence[ExperimentSection] = ()) -> str:
    """The report of a results directory as one HTML string; ``sections`` are drawn after the
    thesis reproduction, in order (the commands pass the studies' sections)."""
    store = ResultStore(run_dir)
    config = store.config()
    episodes, summaries = store.load_tables()
    aggregates = aggregate(summaries, config)
    comparisons = compare_to_baseline(summaries, config)
    surfaces = compare_surfaces(summaries, config)
    metadata = store.metadata()
    body = [
        f"<h1>skidnav experiment: {html.escape(config.name)}</h1>",
        setup(config, metadata, len(summaries)),
        "<h2>Definitions</h2>",
        definitions(config),
        convergence_section(summaries, comparisons, config),
        performance_profiles(summaries, config),
        budget_section(comparisons, aggregates, config),
        reproduction_section(comparisons, surfaces, summaries, config),
        *(section(summaries, config) for section in sections),
    ]
    if not surfaces.empty:
        body.append(image(plots.surface_bars(surfaces), "rough vs slippery"))
    for map_label, preset, _ in cells(summaries):
        logger.info("report: cell %s / %s", map_label, preset)
        body += [
            f"<h2>Map {html.escape(map_label)} · preset {html.escape(preset)}</h2>",
            aggregate_table(aggregates, map_label, preset),
            figures_for_cell(store, config, episodes, summaries, aggregates, map_label, preset),
        ]
    body += config_and_provenance(config_to_dict(config), metadata)
    return page(f"skidnav: {config.name}", body)


def write_report(
    run_dir: Path | str,
    output: Path | str | None = None,
    sections: Sequence[ExperimentSection] = (),
) -> Path:
    """Write the report of the experiment in ``run_dir`` (:func:`build_report` with its extra
    ``sections``) to :func:`report_path`, atomically (:func:`write_page`); returns its path.

    Raises:
        UserError: the results are missing or damaged, or the report cannot be written there.
    """
    path = report_path(run_dir, output)
    return write_page(path, build_report(run_dir, sections))
