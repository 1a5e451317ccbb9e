"""The experiment report: ONE self-contained HTML file (tables, base64 PNG figures, the config).

It leads with its point: the one-line verdict (``id="verdict"``, the headline speed-up with its
interval, :mod:`skidnav.experiments.report.verdict`), a caveat when the seeds are too few for
intervals, the convergence table with every agent's speed-up, the setup, then the metric
definitions folded (:mod:`skidnav.experiments.report.definitions`). Then performance profiles, the
planning budget, thesis reproduction (speed-up, success-rate gain, final-length difference, rough
vs slippery floor), the value of learning the kinematic model where agents were run with several
(:mod:`skidnav.experiments.report.learning_value`), aggregate tables, per-cell figures (greedy path
lengths against the oracle, learning curves, per-seed metrics, final greedy trajectories and one of
them animated (:mod:`skidnav.physics.render`), value maps with preferred headings, greedy-policy
maps), provenance (config, versions, sessions with their code versions). The numbers are what was
measured, rounded for people (:mod:`skidnav.statistics.formatting`). Building it shows a progress
bar on stderr when asked (``skidnav report``).

The page shell is shared with the studies' reports (:mod:`skidnav.experiments.report.page`). An
experiment report takes extra sections from its caller (:data:`ExperimentSection`: the commands
pass the studies' sections, e.g. the discretization-gap table, :mod:`skidnav.studies.kind`), so
this module imports no study.
"""

from __future__ import annotations

import html
import logging
import sys
from collections.abc import Callable, Sequence
from functools import partial
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pandas as pd
from tqdm import tqdm

from skidnav.experiments.config import ExperimentConfig, config_to_dict
from skidnav.experiments.report import plots
from skidnav.experiments.report.analysis import (
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
from skidnav.experiments.report.cells import Part, cell_parts, figure
from skidnav.experiments.report.colours import agent_colours
from skidnav.experiments.report.definitions import definitions
from skidnav.experiments.report.learning_value import learning_value_section
from skidnav.experiments.report.page import (
    config_and_provenance,
    image,
    interval_text,
    page,
    report_path,
    table,
    write_page,
)
from skidnav.experiments.report.reproduction import reproduction_section
from skidnav.experiments.report.verdict import verdict_html, verdict_text
from skidnav.experiments.store import ResultStore
from skidnav.statistics.formatting import MIN_INTERVAL_SEEDS, plural
from skidnav.statistics.survival import performance_profile, profile_band

logger = logging.getLogger(__name__)

ExperimentSection = Callable[[pd.DataFrame, ExperimentConfig], str]
"""An extra section of an experiment report: the summaries (one row per run) and the config in,
an HTML fragment out (empty when it has nothing to show)."""


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
        "<h2>Convergence</h2>" + table(frame, labels=2, escape=False)
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
    for map_label, preset, _ in cells(summaries):
        title = f"converged by episode e · {map_label} · {preset}"
        parts.append(image(profile_figure(summaries, config, (map_label, preset)), title))
    return "".join(parts)


def profile_figure(
    summaries: pd.DataFrame, config: ExperimentConfig, cell: tuple[str, str]
) -> bytes:
    """PNG bytes of one cell's performance profiles (:func:`plots.performance_profiles`): per
    agent the share of its runs converged by each episode, with its bootstrap band (also drawn
    for the docs by ``docs/tools/convergence_figure.py``)."""
    map_label, preset = cell
    rows = summaries[(summaries["map"] == map_label) & (summaries["preset"] == preset)]
    episodes = np.unique(np.geomspace(1, config.episodes, 200).round())
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
    colours = agent_colours(config.agent_labels)
    return plots.performance_profiles(profiles, config.episodes, title, colours)


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
        f"{config.drift_amplitude}</li><li>{plural(config.seeds, 'seed')} per cell, "
        f"{plural(config.episodes, 'episode')} per run, action limit "
        f"{config.max_steps or 'env default'}; root seed {config.root_seed}; {n_runs} of "
        f"{plural(config.n_runs, 'run')} finished</li>"
        f"<li>environment {html.escape(config.env_id)}; git commit "
        f"{html.escape(str(metadata.get('git_commit') or 'unknown (not run from a checkout)'))}"
        f"{' (dirty)' if metadata.get('git_dirty') else ''}</li></ul>"
    )


class Tables(NamedTuple):
    """What an experiment report is computed from: the results' tables and their statistics."""

    config: ExperimentConfig
    episodes: pd.DataFrame
    summaries: pd.DataFrame
    aggregates: pd.DataFrame
    comparisons: pd.DataFrame
    surfaces: pd.DataFrame
    metadata: dict[str, object]


def load_tables(store: ResultStore) -> Tables:
    """The tables of ``store`` and the statistics every section reads."""
    config = store.config()
    episodes, summaries = store.load_tables()
    return Tables(
        config, episodes, summaries, aggregate(summaries, config),
        compare_to_baseline(summaries, config), compare_surfaces(summaries, config),
        store.metadata(),
    )  # fmt: skip


def seeds_caveat_html(summaries: pd.DataFrame, config: ExperimentConfig) -> str:
    """A warning when a cell has fewer seeds than an interval needs; else nothing."""
    seeds = int(summaries.groupby(["map", "preset", "agent"])["seed"].nunique().min())
    if seeds >= MIN_INTERVAL_SEEDS:
        return ""
    return (
        f"<p class='no'>Only {plural(seeds, 'seed')} per cell: the {config.confidence:.0%} "
        "intervals in this report are not meaningful (a bootstrap over so few seeds only "
        f"returns their own values); run at least {MIN_INTERVAL_SEEDS} seeds (the thesis's "
        "claims need ≥ 30).</p>"
    )


def headline(tables: Tables) -> str:
    """The top of the report: title, verdict, seeds caveat, convergence table, setup, the
    definitions folded."""
    config, summaries = tables.config, tables.summaries
    return "".join((
        f"<h1>skidnav experiment: {html.escape(config.name)}</h1>",
        verdict_html(verdict_text(tables.comparisons, summaries, config)),
        seeds_caveat_html(summaries, config),
        convergence_section(summaries, tables.comparisons, config),
        setup(config, tables.metadata, len(summaries)),
        definitions(config),
    ))  # fmt: skip


def report_parts(
    store: ResultStore, tables: Tables, sections: Sequence[ExperimentSection]
) -> list[Part]:
    """Every step of the report after the statistics, in page order."""
    config, summaries, comparisons = tables.config, tables.summaries, tables.comparisons
    parts: list[Part] = [
        ("headline", partial(headline, tables)),
        ("performance profiles", partial(performance_profiles, summaries, config)),
        ("planning budget", partial(budget_section, comparisons, tables.aggregates, config)),
        (
            "thesis reproduction",
            partial(reproduction_section, comparisons, tables.surfaces, summaries, config),
        ),
        ("value of learning", partial(learning_value_section, summaries, config)),
    ]
    parts += [
        (f"study section {number}", partial(section, summaries, config))
        for number, section in enumerate(sections, start=1)
    ]
    if not tables.surfaces.empty:
        floors = partial(plots.surface_bars, tables.surfaces)
        parts.append(("rough vs slippery", partial(figure, floors, "rough vs slippery")))
    for map_label, preset, _ in cells(summaries):
        cell_tables = (tables.episodes, summaries, tables.aggregates)
        parts += cell_parts(store, config, cell_tables, (map_label, preset))
    provenance = partial(config_and_provenance, config_to_dict(config), tables.metadata)
    parts.append(("provenance", lambda: "".join(provenance())))
    return parts


class WrittenReport(NamedTuple):
    """A report written: where, and its verdict line (:func:`verdict_text`)."""

    path: Path
    verdict: str


def render_report(
    run_dir: Path | str, sections: Sequence[ExperimentSection] = (), *, progress: bool = False
) -> tuple[str, str]:
    """(the report of a results directory as one HTML string, its verdict line); ``sections``
    are drawn after the thesis reproduction, in order (the commands pass the studies'
    sections); ``progress``: a progress bar of its steps on stderr."""
    store = ResultStore(run_dir)
    with tqdm(
        total=1, desc="report", unit="step", file=sys.stderr, disable=not progress,
        dynamic_ncols=True, leave=False,
    ) as bar:  # fmt: skip
        bar.set_postfix_str("statistics")
        tables = load_tables(store)
        parts = report_parts(store, tables, sections)
        bar.total = len(parts) + 1
        bar.update(1)
        body = []
        for name, draw in parts:
            bar.set_postfix_str(name)
            logger.info("report: %s", name)
            body.append(draw())
            bar.update(1)
    verdict = verdict_text(tables.comparisons, tables.summaries, tables.config)
    return page(f"skidnav: {tables.config.name}", body), verdict


def build_report(run_dir: Path | str, sections: Sequence[ExperimentSection] = ()) -> str:
    """The report of a results directory as one HTML string (:func:`render_report`)."""
    return render_report(run_dir, sections)[0]


def write_report(
    run_dir: Path | str,
    output: Path | str | None = None,
    sections: Sequence[ExperimentSection] = (),
    *,
    progress: bool = False,
) -> WrittenReport:
    """Write the report of the experiment in ``run_dir`` (:func:`render_report` with its extra
    ``sections`` and ``progress``) to :func:`report_path`, atomically (:func:`write_page`);
    returns its path and verdict line.

    Raises:
        UserError: the results are missing or damaged, or the report cannot be written there.
    """
    path = report_path(run_dir, output)
    text, verdict = render_report(run_dir, sections, progress=progress)
    return WrittenReport(write_page(path, text), verdict)
