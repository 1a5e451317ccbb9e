"""Figures of an experiment, as PNG bytes (with :mod:`skidnav.experiments.report.maps`,
:mod:`skidnav.experiments.report.colours` and :mod:`skidnav.studies.continuity.trajectory_plot`,
the only modules of skidnav that import matplotlib).

Every figure function takes the tidy tables (or run arrays) and returns PNG bytes, so the report
embeds them without touching matplotlib. The Agg backend is forced: no display is needed. Every
figure is cropped to what it draws (:func:`to_png`), so no tick label or legend is cut off.
An agent has one colour in every figure (:func:`~skidnav.experiments.report.colours.agent_colour`),
and an interval band is a light fill with its edges drawn
(:func:`~skidnav.experiments.report.colours.draw_band`).
"""

from __future__ import annotations

import io
import math
from collections.abc import Mapping

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from skidnav.experiments.config import ExperimentConfig
from skidnav.experiments.metrics import moving_average
from skidnav.experiments.report.colours import Colour, agent_colours, draw_band
from skidnav.statistics.intervals import curve_band

DPI = 90


def to_png(figure: Figure, dpi: int = DPI, *, crop: bool = True) -> bytes:
    """Render ``figure`` in memory at ``dpi`` [pixels per inch], cropped to its drawn artists
    with a small margin (no label cut off; ``crop=False``: at the figure's own size, for a
    picture of a promised size drawn with a constrained layout), and close it (also when
    rendering fails); returns the PNG bytes. Nothing here writes a file: callers write the bytes
    with :func:`~skidnav.files.atomic.write_atomic` (the report embeds them)."""
    buffer = io.BytesIO()
    try:
        if crop:
            figure.savefig(buffer, format="png", dpi=dpi, bbox_inches="tight", pad_inches=0.08)
        else:
            figure.savefig(buffer, format="png", dpi=dpi)
    finally:
        plt.close(figure)
    return buffer.getvalue()


def line_plot(
    curves: Mapping[str, np.ndarray | tuple[np.ndarray, np.ndarray]],
    xlabel: str,
    ylabel: str,
    x0: int = 1,
) -> bytes:
    """PNG bytes of one line per named curve, with a legend: float (n,) values at x = x0,
    x0 + 1, … (the figures of ``skidnav study reproduce``), or (x (n,), y (n,)) points, marked
    (a policy search's evaluations, :mod:`skidnav.studies.policy_search.report`)."""
    figure, axes = plt.subplots(figsize=(6, 4))
    colours = agent_colours(curves)
    for label, values in curves.items():
        if isinstance(values, tuple):
            axes.plot(*values, label=label, marker="o", markersize=3, color=colours[label])
        else:
            x = np.arange(x0, x0 + len(values))
            axes.plot(x, values, label=label, color=colours[label])
    axes.set_xlabel(xlabel)
    axes.set_ylabel(ylabel)
    axes.legend()
    figure.tight_layout()
    return to_png(figure, dpi=100)


def _band(
    axes: Axes,
    curves: np.ndarray,
    rng: np.random.Generator,
    label: str,
    colour: Colour,
    confidence: float,
) -> None:
    mean, low, high = curve_band(curves, rng, confidence=confidence)
    episodes = np.arange(1, curves.shape[1] + 1)
    axes.plot(episodes, mean, color=colour, label=label, linewidth=1.6)
    draw_band(axes, episodes, low, high, colour)


def learning_curves(
    episodes: pd.DataFrame, config: ExperimentConfig, map_label: str, preset: str
) -> bytes:
    """Return and success rate per episode, mean over seeds with a bootstrap band, one line per
    agent (one map × preset cell); the greedy lengths are :func:`greedy_lengths`."""
    cell = episodes[(episodes["map"] == map_label) & (episodes["preset"] == preset)]
    window = max(1, round(config.episodes / 20))
    panels = (("return", "episode return"), ("success", f"success (moving average, {window} ep.)"))
    figure, axes = plt.subplots(1, 2, figsize=(11, 3.8), layout="constrained")
    colors = agent_colours(config.agent_labels)
    rng = np.random.default_rng([config.root_seed, 0xC0])
    for agent in config.agent_labels:
        rows = cell[cell["agent"] == agent]
        if rows.empty:
            continue
        for ax, (column, title) in zip(axes, panels, strict=True):
            table = rows.pivot(index="seed", columns="episode", values=column).to_numpy(float)
            if column == "success":
                table = np.array([moving_average(row, window) for row in np.nan_to_num(table)])
            _band(ax, table, rng, agent, colors[agent], config.confidence)
            ax.set_title(title, fontsize=10)
            ax.set_xlabel("episode")
    axes[0].legend(fontsize=8)
    figure.suptitle(
        f"{map_label} · {preset}: mean over seeds, {config.confidence:.0%} bootstrap band"
    )
    return to_png(figure)


GREEDY_CAP = 4.0
"""The greedy-length figure's ceiling, a multiple of L*: longer greedy rollouts, and
evaluations where none reached the goal, are drawn at it."""
GREEDY_BINS = 60
"""Logarithmic episode bins of the greedy-length figure (fewer where episodes are few)."""


def _quartiles_by_bin(
    episode: np.ndarray, values: np.ndarray, edges: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(bin centres (k,), quartiles (3, k): 25th, 50th, 75th percentile) of ``values`` over
    the episodes in each bin [edges[b], edges[b + 1]) that holds any."""
    index = np.searchsorted(edges, episode, side="right") - 1
    kept = [b for b in range(len(edges) - 1) if np.any(index == b)]
    centres = np.array([math.sqrt(edges[b] * (edges[b + 1] - 1)) for b in kept])
    quartiles = np.array([np.percentile(values[index == b], (25, 50, 75)) for b in kept]).T
    return centres, quartiles.reshape(3, len(kept))


def greedy_lengths(
    episodes: pd.DataFrame, summaries: pd.DataFrame, config: ExperimentConfig, cell: tuple[str, str]
) -> bytes:
    """The greedy rollouts' length after each episode relative to the oracle's L* of the run's
    world (1 = as short as the oracle's expected path), per agent the median over seeds and over
    the episodes of logarithmic bins with its interquartile band, the episode axis logarithmic;
    capped at :data:`GREEDY_CAP` × L* (failed evaluations drawn there), the pass threshold
    dashed. Without an oracle (an env of its own) the lengths in actions, capped at the limit."""
    map_label, preset = cell
    rows = episodes[(episodes["map"] == map_label) & (episodes["preset"] == preset)]
    values, relative, cap = _capped_lengths(rows, summaries)
    edges = np.unique(np.geomspace(1, config.episodes + 1, GREEDY_BINS).round())
    figure, axes = plt.subplots(figsize=(7.5, 4.2), layout="constrained")
    colors = agent_colours(config.agent_labels)
    for agent in config.agent_labels:
        mine = (rows["agent"] == agent).to_numpy()
        if mine.any():
            x, (low, median, high) = _quartiles_by_bin(
                rows["episode"].to_numpy()[mine], values[mine], edges
            )
            axes.plot(x, median, color=colors[agent], linewidth=1.6, label=f"{agent}: median")
            draw_band(axes, x, low, high, colors[agent])
    _greedy_axes(axes, config, relative, cap)
    unit = "× L*" if relative else "actions"
    axes.set_title(
        f"greedy path length · {map_label} · {preset}\nmedian over seeds (band: 25–75 %); "
        f"failed, or ≥ {cap:g} {unit}: drawn at {cap:g}",
        fontsize=10,
    )
    return to_png(figure)


def _capped_lengths(rows: pd.DataFrame, summaries: pd.DataFrame) -> tuple[np.ndarray, bool, float]:
    """(the greedy length of each episode row over its run's L*, capped at :data:`GREEDY_CAP`,
    NaN (failed) at the cap; True; the cap), or without an oracle for every run (the lengths in
    actions capped at the action limit; False; the limit)."""
    oracle = (
        summaries.set_index("run_id")["oracle_length"] if "oracle_length" in summaries else None
    )
    reference = rows["run_id"].map(oracle) if oracle is not None else pd.Series(np.nan, rows.index)
    relative = bool(np.isfinite(reference.to_numpy(float)).all())
    cap = GREEDY_CAP if relative else float(summaries["action_limit"].max())
    values = (rows["greedy_length"] / (reference if relative else 1.0)).to_numpy(float)
    return np.minimum(np.nan_to_num(values, nan=cap), cap), relative, cap


def _greedy_axes(axes: Axes, config: ExperimentConfig, relative: bool, cap: float) -> None:
    """Axes, reference lines and legend of :func:`greedy_lengths`."""
    if relative:
        axes.axhline(1.0, color="black", linewidth=1, label="L*: the oracle's expected length")
        if config.convergence_objective == "actions":
            threshold = 1.0 + config.convergence_tolerance
            axes.axhline(threshold, color="grey", linestyle="--", linewidth=1,
                         label=f"pass threshold ({threshold:g} × L*)")  # fmt: skip
        axes.set_ylabel("greedy path length / L*")
    else:
        axes.set_ylabel("greedy path length [actions]")
    axes.set_xscale("log")
    axes.set_xlim(1, config.episodes)
    axes.set_ylim(0, cap * 1.04)
    axes.set_xlabel("episode (log scale)")
    axes.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncols=3)


def _strip(
    axes: Axes,
    summaries: pd.DataFrame,
    column: str,
    labels: list[str],
    aggregates: pd.DataFrame,
    title: str,
) -> None:
    rng = np.random.default_rng(0)  # jitter only
    colours = agent_colours(labels)
    for position, agent in enumerate(labels):
        values = summaries[summaries["agent"] == agent][column].to_numpy(float)
        jitter = rng.uniform(-0.15, 0.15, size=values.size)
        axes.scatter(position + jitter, values, s=10, alpha=0.6, color=colours[agent])
        row = aggregates[(aggregates["agent"] == agent) & (aggregates["metric"] == column)]
        if not row.empty:
            r = row.iloc[0]
            axes.errorbar(
                position + 0.3,
                r["mean"],
                yerr=[[r["mean"] - r["mean_low"]], [r["mean_high"] - r["mean"]]],
                fmt="o",
                color="black",
                capsize=3,
            )
            axes.errorbar(
                position + 0.4,
                r["iqm"],
                yerr=[[r["iqm"] - r["iqm_low"]], [r["iqm_high"] - r["iqm"]]],
                fmt="s",
                mfc="white",
                color="black",
                capsize=3,
            )
    axes.set_xticks(range(len(labels)), labels, rotation=30, ha="right", fontsize=8)
    axes.set_title(title, fontsize=10)


def metric_strips(
    summaries: pd.DataFrame,
    aggregates: pd.DataFrame,
    config: ExperimentConfig,
    map_label: str,
    preset: str,
) -> bytes:
    """Per-seed convergence episodes, success rates and final lengths per agent (dots in the
    agent's colour), with the mean (black circle) and IQM (open square) and their bootstrap
    intervals."""
    cell = summaries[(summaries["map"] == map_label) & (summaries["preset"] == preset)]
    aggs = aggregates[(aggregates["map"] == map_label) & (aggregates["preset"] == preset)]
    panels = (
        ("convergence_episode", "convergence episode (censored: at censoring time)"),
        ("optimality_gap", "optimality gap, last evaluations"),
        ("success_rate", "success rate, all episodes"),
        ("success_rate_last10", "success rate, last 10 %"),
        ("final_length_actions", "final greedy length [actions]"),
    )
    figure, axes = plt.subplots(1, len(panels), figsize=(19, 4.4), layout="constrained")
    for ax, (column, title) in zip(axes, panels, strict=True):
        _strip(ax, cell, column, config.agent_labels, aggs, title)
    figure.suptitle(
        f"{map_label} · {preset}: seeds (dots), mean ● and IQM □ with "
        f"{config.confidence:.0%} intervals"
    )
    return to_png(figure)


def surface_bars(surfaces: pd.DataFrame) -> bytes:
    """Rough / slippery success-rate ratio per agent with its interval (1 = no effect)."""
    rows = surfaces[surfaces["metric"] == "success_rate"]
    figure, axes = plt.subplots(figsize=(max(5.0, 1.2 * len(rows)), 3.6), layout="constrained")
    positions = np.arange(len(rows))
    labels = [f"{r.agent}\n{r.map}" for r in rows.itertuples()]
    error = np.vstack([rows["ratio"] - rows["ratio_low"], rows["ratio_high"] - rows["ratio"]])
    by_agent = agent_colours(rows["agent"])
    colours = [by_agent[agent] for agent in rows["agent"]]
    axes.bar(positions, rows["ratio"], yerr=error, capsize=4, color=colours, alpha=0.8)
    axes.axhline(1.0, color="grey", linewidth=1)
    axes.axhline(2.0, color="C3", linewidth=1, linestyle="--", label="thesis: ≈ 2×")
    axes.set_xticks(positions, labels, fontsize=8)
    axes.set_ylabel("success rate rough / slippery")
    axes.legend(fontsize=8)
    return to_png(figure)


def performance_profiles(
    profiles: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]],
    horizon: int,
    title: str,
    colours: Mapping[str, Colour] | None = None,
) -> bytes:
    """Share of runs converged by each episode (Agarwal et al. (2021) performance profiles over
    convergence episodes), one step curve with its bootstrap band per agent.

    Args:
        profiles: agent label → (episodes, share, low, high), shape (k,) each, e.g. from
            :func:`skidnav.statistics.survival.performance_profile` and
            :func:`~skidnav.statistics.survival.profile_band`.
        horizon: the last episode of the runs (the dashed line; censored runs stop there).
        title: figure title.
        colours: agent label → colour, by default
            :func:`~skidnav.experiments.report.colours.agent_colours` of the profiles' labels
            (a report passes its agents' colours, so an agent missing from one cell does not
            change another's colour).
    """
    figure, axes = plt.subplots(figsize=(6.4, 4.2), layout="constrained")
    colors = colours if colours is not None else agent_colours(profiles)
    for label, (episodes, share, low, high) in profiles.items():
        color = colors[label]
        axes.step(episodes, share, where="post", color=color, label=label, linewidth=1.6)
        draw_band(axes, episodes, low, high, color, step="post")
    axes.axvline(horizon, color="grey", linewidth=1, linestyle="--", label="horizon")
    axes.set_xscale("log")
    axes.set_xlim(1, horizon * 1.05)
    axes.set_ylim(-0.02, 1.02)
    axes.set_xlabel("episode")
    axes.set_ylabel("share of runs converged")
    axes.legend(fontsize=8, loc="upper left")
    axes.set_title(title, fontsize=10)
    return to_png(figure)


def _error(center: pd.Series, low: pd.Series, high: pd.Series) -> np.ndarray:
    """Asymmetric error bars, shape (2, n), never negative (NaN bounds draw no bar)."""
    below = (center - low).to_numpy(float)
    above = (high - center).to_numpy(float)
    bars: np.ndarray = np.clip(np.vstack([below, above]), 0.0, None)
    return bars


def _speedup_panel(axes: Axes, rows: pd.DataFrame, color: Colour, label: str) -> None:
    axes.errorbar(
        rows["planning_steps"],
        rows["speedup"],
        yerr=_error(rows["speedup"], rows["speedup_low"], rows["speedup_high"]),
        color=color,
        label=label,
        capsize=3,
        marker="",
    )
    bounds = rows["bound"].to_numpy(str)
    for bound, marker, size in (("", "o", 5), ("lower", "^", 9), ("upper", "v", 9)):
        marks = bounds == bound
        axes.plot(
            rows["planning_steps"][marks], rows["speedup"][marks], marker, color=color, ms=size
        )


def speedup_vs_budget(rows: pd.DataFrame) -> bytes:
    """Speed-up over the baseline (left) and mean wall time per run (right) against planning steps
    per real step, one line per algorithm.

    Args:
        rows: one row per algorithm × planning steps, columns ``algorithm``, ``planning_steps``,
            ``speedup``, ``speedup_low``, ``speedup_high``, ``bound`` (a lower bound is drawn
            ▲, an upper bound ▼, an unknown one not at all), ``wall_time``,
            ``wall_time_low``, ``wall_time_high`` [s].

    The x axes are symmetric-log so that 0 planning steps (model-free) shows at 0.
    """
    figure, (left, right) = plt.subplots(1, 2, figsize=(12, 4.2), layout="constrained")
    labels = list(dict.fromkeys(rows["algorithm"]))
    colors = agent_colours(labels)
    for label in labels:
        part = rows[rows["algorithm"] == label].sort_values("planning_steps")
        _speedup_panel(left, part, colors[label], label)
        right.errorbar(
            part["planning_steps"],
            part["wall_time"],
            yerr=_error(part["wall_time"], part["wall_time_low"], part["wall_time_high"]),
            color=colors[label],
            label=label,
            capsize=3,
            marker="o",
            ms=4,
        )
    left.axhline(1.0, color="grey", linewidth=1)
    left.set_ylabel("speed-up over the baseline")
    left.set_title("KM-median convergence episode, baseline / agent (▲ lower bound)", fontsize=10)
    right.set_ylabel("mean wall time per run [s]")
    right.set_title("wall time per run", fontsize=10)
    for axes in (left, right):
        axes.set_yscale("log")
        axes.set_xscale("symlog", linthresh=1.0)
        axes.set_xlim(-0.5, max(1.0, float(rows["planning_steps"].max())) * 1.6)
        axes.set_xlabel("planning steps per real step")
    left.legend(fontsize=8)
    return to_png(figure)
