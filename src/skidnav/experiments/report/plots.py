"""Figures of an experiment, as PNG bytes (with :mod:`skidnav.studies.continuity.trajectory_plot`,
the only modules of skidnav that import matplotlib).

Every figure function takes the tidy tables (or run arrays) and returns PNG bytes, so the report
embeds them without touching matplotlib. The Agg backend is forced: no display is needed.
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
from matplotlib.patches import Rectangle

from skidnav.experiments.config import ExperimentConfig
from skidnav.experiments.metrics import moving_average
from skidnav.experiments.store import TrialResult
from skidnav.stats import curve_band

ARENA = (0.62, 0.505)
"""Arena width and height [m] (the thesis arena, Alhawary (2020), App. A.1.1; as
:class:`~skidnav.robot.params.RobotParams`)."""
DPI = 90


def to_png(figure: Figure, dpi: int = DPI) -> bytes:
    """Render ``figure`` in memory at ``dpi`` [pixels per inch] and close it (also when rendering
    fails); returns the PNG bytes. Nothing here writes a file: callers write the bytes with
    :func:`~skidnav.atomicfile.write_atomic` (the report embeds them)."""
    buffer = io.BytesIO()
    try:
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
    for label, values in curves.items():
        if isinstance(values, tuple):
            axes.plot(*values, label=label, marker="o", markersize=3)
        else:
            axes.plot(np.arange(x0, x0 + len(values)), values, label=label)
    axes.set_xlabel(xlabel)
    axes.set_ylabel(ylabel)
    axes.legend()
    figure.tight_layout()
    return to_png(figure, dpi=100)


def _colors(labels: list[str]) -> dict[str, tuple[float, ...]]:
    cmap = plt.get_cmap("tab10")
    return {label: tuple(cmap(n % 10)) for n, label in enumerate(labels)}


def _band(
    axes: Axes,
    curves: np.ndarray,
    rng: np.random.Generator,
    label: str,
    color: tuple[float, ...],
    confidence: float,
) -> None:
    mean, low, high = curve_band(curves, rng, confidence=confidence)
    episodes = np.arange(1, curves.shape[1] + 1)
    axes.plot(episodes, mean, color=color, label=label, linewidth=1.4)
    axes.fill_between(episodes, low, high, color=color, alpha=0.2, linewidth=0)


def learning_curves(
    episodes: pd.DataFrame, config: ExperimentConfig, map_label: str, preset: str, limit: float
) -> bytes:
    """Greedy trajectory length, return and success rate per episode, mean over seeds with a
    bootstrap band, one line per agent (one map × preset cell). A greedy evaluation that did not
    reach the goal is drawn at the action limit ``limit``."""
    cell = episodes[(episodes["map"] == map_label) & (episodes["preset"] == preset)]
    panels = (
        ("greedy_length", f"greedy trajectory length [actions] (failed = {limit:.0f})"),
        ("return", "episode return"),
        ("success", f"success (moving average, {max(1, round(config.episodes / 20))} ep.)"),
    )
    figure, axes = plt.subplots(1, 3, figsize=(15, 4), layout="constrained")
    colors = _colors(config.agent_labels)
    rng = np.random.default_rng([config.root_seed, 0xC0])
    for agent in config.agent_labels:
        rows = cell[cell["agent"] == agent]
        if rows.empty:
            continue
        for ax, (column, title) in zip(axes, panels, strict=True):
            table = rows.pivot(index="seed", columns="episode", values=column).to_numpy(float)
            table = np.nan_to_num(table, nan=limit)
            if column == "success":
                window = max(1, round(config.episodes / 20))
                table = np.array([moving_average(row, window) for row in table])
            _band(ax, table, rng, agent, colors[agent], config.confidence)
            ax.set_title(title, fontsize=10)
            ax.set_xlabel("episode")
    axes[0].set_yscale("log")
    axes[0].legend(fontsize=8)
    figure.suptitle(
        f"{map_label} · {preset}: mean over seeds, {config.confidence:.0%} bootstrap band"
    )
    return to_png(figure)


def _strip(
    axes: Axes,
    summaries: pd.DataFrame,
    column: str,
    labels: list[str],
    aggregates: pd.DataFrame,
    title: str,
) -> None:
    rng = np.random.default_rng(0)  # jitter only
    for position, agent in enumerate(labels):
        values = summaries[summaries["agent"] == agent][column].to_numpy(float)
        jitter = rng.uniform(-0.15, 0.15, size=values.size)
        axes.scatter(position + jitter, values, s=10, alpha=0.5, color="grey")
        row = aggregates[(aggregates["agent"] == agent) & (aggregates["metric"] == column)]
        if not row.empty:
            r = row.iloc[0]
            axes.errorbar(
                position + 0.3,
                r["mean"],
                yerr=[[r["mean"] - r["mean_low"]], [r["mean_high"] - r["mean"]]],
                fmt="o",
                color="C3",
                capsize=3,
            )
            axes.errorbar(
                position + 0.4,
                r["iqm"],
                yerr=[[r["iqm"] - r["iqm_low"]], [r["iqm_high"] - r["iqm"]]],
                fmt="s",
                color="C0",
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
    """Per-seed convergence episodes, success rates and final lengths per agent, with the mean
    (red circle) and IQM (blue square) and their bootstrap intervals."""
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
        f"{map_label} · {preset}: seeds (grey), mean ● and IQM ■ with "
        f"{config.confidence:.0%} intervals"
    )
    return to_png(figure)


def draw_arena(axes: Axes, run: TrialResult, *, slip: bool = True) -> None:
    """Walls, slip regions (η shading), start (green), goal (red) of one run's world."""
    occupancy = run.arrays["occupancy"].astype(bool)
    if slip:
        eta = run.arrays["slip_eta"]
        region_w, region_h = ARENA[0] / (eta.shape[0] - 1), ARENA[1] / (eta.shape[1] - 1)
        axes.imshow(
            eta.T,
            origin="lower",
            cmap="Oranges",
            vmin=0.0,
            vmax=max(1.7, eta.max()),
            extent=(0, eta.shape[0] * region_w, 0, eta.shape[1] * region_h),
            alpha=0.6,
        )
    draw_cells(axes, occupancy, tuple(run.arrays["start"]), tuple(run.arrays["goal"]))


def draw_cells(
    axes: Axes, occupancy: np.ndarray, start: tuple[int, int], goal: tuple[int, int]
) -> None:
    """Walls (``occupancy`` bool (n_x, n_y), True = wall), the start (green) and goal (red)
    cells on the arena's cells (W / (n_x − 1) by H / (n_y − 1) [m], as the discretization's),
    equal aspect."""
    n_x, n_y = occupancy.shape
    cell_w, cell_h = ARENA[0] / (n_x - 1), ARENA[1] / (n_y - 1)
    walls = np.ma.masked_where(~occupancy.T, np.ones_like(occupancy.T, dtype=float))
    axes.imshow(
        walls,
        origin="lower",
        cmap="Greys",
        vmin=0,
        vmax=1.2,
        extent=(0, n_x * cell_w, 0, n_y * cell_h),
    )
    for (i, j), color in ((start, "green"), (goal, "red")):
        axes.add_patch(Rectangle((i * cell_w, j * cell_h), cell_w, cell_h, color=color, alpha=0.8))
    axes.set_xlim(0, n_x * cell_w)
    axes.set_ylim(0, n_y * cell_h)
    axes.set_aspect("equal")
    axes.tick_params(labelsize=7)


def _grid(count: int) -> tuple[Figure, list[Axes]]:
    columns = min(4, count)
    rows = math.ceil(count / columns)
    figure, axes = plt.subplots(
        rows, columns, figsize=(4.2 * columns, 3.8 * rows), squeeze=False, layout="constrained"
    )
    flat = list(axes.ravel())
    for extra in flat[count:]:
        extra.axis("off")
    return figure, flat[:count]


def trajectories(runs: list[TrialResult], title: str) -> bytes:
    """The final greedy trajectory of each run (one panel per run) on its arena."""
    figure, axes = _grid(len(runs))
    for ax, run in zip(axes, runs, strict=True):
        draw_arena(ax, run)
        poses = run.arrays["greedy_poses"]
        ax.plot(poses[:, 0], poses[:, 1], color="C0", linewidth=1.5)
        ax.plot(poses[-1:, 0], poses[-1:, 1], "o", color="C0", markersize=4)
        reached = (
            "reached goal"
            if run.summary["final_length_m"] == run.summary["final_length_m"]
            else "did not reach goal"
        )
        ax.set_title(
            f"{run.coordinates['agent']} (seed {run.coordinates['seed']})\n"
            f"{len(poses) - 1} actions, {reached}",
            fontsize=9,
        )
    figure.suptitle(title)
    return to_png(figure)


def value_maps(runs: list[TrialResult], title: str) -> bytes:
    """State values (max over headings and actions) and preferred headings per cell."""
    figure, axes = _grid(len(runs))
    for ax, run in zip(axes, runs, strict=True):
        draw_arena(ax, run, slip=False)
        value = run.arrays["value_map"]
        n_x, n_y = value.shape
        cell_w, cell_h = ARENA[0] / (n_x - 1), ARENA[1] / (n_y - 1)
        image = ax.imshow(
            np.ma.masked_invalid(value).T,
            origin="lower",
            cmap="viridis",
            extent=(0, n_x * cell_w, 0, n_y * cell_h),
        )
        heading = run.arrays["heading_map"]
        n_headings = max(int(heading.max()) + 1, 20)
        angle = -math.pi + (heading + 0.5) * 2 * math.pi / n_headings
        ii, jj = np.nonzero(heading >= 0)
        ax.quiver(
            (ii + 0.5) * cell_w,
            (jj + 0.5) * cell_h,
            np.cos(angle[ii, jj]),
            np.sin(angle[ii, jj]),
            scale=40,
            width=0.003,
            color="white",
        )
        figure.colorbar(image, ax=ax, fraction=0.04)
        ax.set_title(f"{run.coordinates['agent']} (seed {run.coordinates['seed']})", fontsize=9)
    figure.suptitle(title)
    return to_png(figure)


ACTION_GLYPHS = (
    (0, "forward", None),
    (1, "backward", None),
    (2, "turn left", r"$\circlearrowleft$"),
    (3, "turn right", r"$\circlearrowright$"),
)
"""(action, name, marker) of the skid-steer env's actions; forward and backward are drawn as
arrows along and against the heading."""


def _policy_panel(ax: Axes, run: TrialResult) -> None:
    """One run's greedy action per cell at its start heading, as glyphs over the arena."""
    draw_arena(ax, run, slip=False)
    policy = run.arrays["policy_map"]
    n_x, n_y = policy.shape
    cell_w, cell_h = ARENA[0] / (n_x - 1), ARENA[1] / (n_y - 1)
    heading = float(run.arrays["start_heading"])
    for action, name, marker in ACTION_GLYPHS:
        ii, jj = np.nonzero(policy == action)
        x, y = (ii + 0.5) * cell_w, (jj + 0.5) * cell_h
        color = f"C{action}"
        if marker is None:
            sign = 1.0 if action == 0 else -1.0
            u, v = (
                np.full(ii.size, sign * math.cos(heading)),
                np.full(ii.size, sign * math.sin(heading)),
            )
            ax.quiver(x, y, u, v, color=color, scale=45, width=0.004, pivot="middle", label=name)
        else:
            ax.scatter(x, y, s=22, marker=marker, color=color, linewidths=0.4, label=name)
    ax.set_title(f"{run.coordinates['agent']} (seed {run.coordinates['seed']})", fontsize=9)


def policy_maps(runs: list[TrialResult], title: str) -> bytes:
    """The greedy action per cell with the robot at its start heading (``policy_map``): arrows
    for forward (along the heading) and backward, circular arrows for the turns; no glyph on walls
    and on cells whose Q values at that heading were never updated."""
    figure, axes = _grid(len(runs))
    for ax, run in zip(axes, runs, strict=True):
        _policy_panel(ax, run)
    handles, labels = axes[0].get_legend_handles_labels()
    figure.legend(handles, labels, loc="outside lower center", ncols=4, fontsize=8)
    figure.suptitle(title)
    return to_png(figure)


def surface_bars(surfaces: pd.DataFrame) -> bytes:
    """Rough / slippery success-rate ratio per agent with its interval (1 = no effect)."""
    rows = surfaces[surfaces["metric"] == "success_rate"]
    figure, axes = plt.subplots(figsize=(max(5.0, 1.2 * len(rows)), 3.6), layout="constrained")
    positions = np.arange(len(rows))
    labels = [f"{r.agent}\n{r.map}" for r in rows.itertuples()]
    error = np.vstack([rows["ratio"] - rows["ratio_low"], rows["ratio_high"] - rows["ratio"]])
    axes.bar(positions, rows["ratio"], yerr=error, capsize=4, color="C2", alpha=0.8)
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
) -> bytes:
    """Share of runs converged by each episode (Agarwal et al. (2021) performance profiles over
    convergence episodes), one step curve with its bootstrap band per agent.

    Args:
        profiles: agent label → (episodes, share, low, high), shape (k,) each, e.g. from
            :func:`skidnav.survival.performance_profile` and :func:`~skidnav.survival.profile_band`.
        horizon: the last episode of the runs (the dashed line; censored runs stop there).
        title: figure title.
    """
    figure, axes = plt.subplots(figsize=(6.4, 4.2), layout="constrained")
    colors = _colors(list(profiles))
    for label, (episodes, share, low, high) in profiles.items():
        color = colors[label]
        axes.step(episodes, share, where="post", color=color, label=label, linewidth=1.4)
        axes.fill_between(episodes, low, high, step="post", color=color, alpha=0.2, linewidth=0)
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


def _speedup_panel(axes: Axes, rows: pd.DataFrame, color: tuple[float, ...], label: str) -> None:
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
    colors = _colors(labels)
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
