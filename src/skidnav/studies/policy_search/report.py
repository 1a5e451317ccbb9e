"""The report section of a policy-search study: per slip preset the learning curves (the mean
policy's evaluation return per generation, one line per seed) and the final scores of every
search, with their means over seeds and 95 % percentile-bootstrap intervals
(:func:`skidnav.statistics.intervals.bootstrap_interval`, from one generator seeded 0)."""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np
import pandas as pd

from skidnav.experiments.report.page import image, interval_text
from skidnav.experiments.store import ResultStore
from skidnav.statistics.intervals import bootstrap_interval
from skidnav.studies.policy_search.grid import LAYOUT, PolicySearchGrid

FINAL_COLUMNS = {
    "seed": "seed",
    "generations": "generations",
    "episodes": "episodes",
    "final_return": "final return",
    "final_success": "final success",
    "peak_return": "peak return",
    "peak_success": "peak success",
    "wall_time": "wall time [s]",
}
"""Summary column → its title in the table of final scores."""
MEANS = ("final_return", "final_success", "peak_success")
"""The scores given as means over seeds."""


def describe(grid: PolicySearchGrid) -> str:
    """One line: the world, the policy, the budget of each search."""
    search = grid.search
    return (
        f"{grid.seeds} search(es) per slip preset on the {search.map_kind} map of world seed "
        f"{search.world_seed}: tanh policy with {search.hidden} hidden units and "
        f"{search.lidar_rays} lidar rays ({search.n_parameters} parameters); λ = "
        f"{search.population}, σ₀ = {search.sigma0:g}, {search.generations} generations of "
        f"{search.episodes_per_generation} episodes of at most {search.max_episode_steps} "
        f"actions; the mean policy evaluated on {search.eval_episodes} fixed episodes every "
        f"{search.eval_every} generation(s) and after the last"
    )


def final_table(runs: pd.DataFrame) -> str:
    """The final scores of the runs of one preset (HTML table), one row per seed."""
    frame = runs.sort_values("seed")[list(FINAL_COLUMNS)].rename(columns=FINAL_COLUMNS)
    return frame.to_html(index=False, border=0, float_format=lambda value: f"{value:.3g}")


def means_text(runs: pd.DataFrame, rng: np.random.Generator) -> str:
    """The means over seeds of :data:`MEANS` with their intervals, as one sentence."""
    parts = []
    for column in MEANS:
        values = runs.sort_values("seed")[column].to_numpy(float)
        parts.append(f"{FINAL_COLUMNS[column]} {interval_text(*bootstrap_interval(values, rng))}")
    return "Means over seeds [95 % bootstrap interval]: " + "; ".join(parts) + "."


def curve_figure(curves: pd.DataFrame, preset: str) -> str:
    """The mean policy's evaluation return per generation of each run of ``preset`` (the
    generations it was evaluated at), as an embedded PNG."""
    from skidnav.experiments.report.plots import line_plot

    lines = {}
    for seed, rows in curves.groupby("seed"):
        evaluated = rows[rows["mean_return"].notna()]
        x, y = evaluated["generation"].to_numpy(float), evaluated["mean_return"].to_numpy(float)
        lines[f"seed {seed}"] = (x, y)
    png = line_plot(lines, "generation", "mean policy's return (evaluation)")
    return image(png, f"learning curves, {preset}")


def report_section(run_dir: Path) -> str:
    """The study's section of the HTML report of ``run_dir`` (module doc).

    Raises:
        UserError: ``run_dir`` holds no policy-search results, or none finished.
    """
    store = ResultStore(run_dir, LAYOUT)
    grid = store.config()
    curves, summaries = store.load_tables()
    rng = np.random.default_rng(0)
    parts = [
        "<h2>CMA-ES policy search</h2>",
        f"<p>{html.escape(describe(grid))}; {len(summaries)} of {grid.n_runs} runs finished. "
        "Return: undiscounted, per episode; success: share of the evaluation episodes that "
        "reached the goal; peak: the best evaluation of the mean during the search "
        "(docs/agents/cmaes.md).</p>",
    ]
    for preset in grid.presets:
        runs = summaries[summaries["preset"] == preset]
        if runs.empty:
            continue
        parts += [
            f"<h3>Slip preset {html.escape(preset)}</h3>",
            curve_figure(curves[curves["preset"] == preset], preset),
            final_table(runs),
            f"<p>{html.escape(means_text(runs, rng))}</p>",
        ]
    return "".join(parts)
