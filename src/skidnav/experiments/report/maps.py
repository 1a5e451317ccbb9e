"""Pictures of the arena in an experiment report, as PNG bytes: the final greedy trajectories, the
state values with preferred headings and the greedy actions of each run's world
(:func:`draw_cells` also draws the continuity study's trajectories,
:mod:`skidnav.studies.continuity.trajectory_plot`).

Every picture draws the start cell green and the goal cell red (:mod:`skidnav.world.colours`,
the convention of every picture of a world) and names them in its legend. The panels of one
figure share one colour scale: the slip shading of the trajectories (η from 0 to
:func:`eta_ceiling`), the values of the value maps (:func:`value_limits`, with one colour bar).
"""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch, Rectangle

from skidnav.experiments.report.plots import to_png
from skidnav.experiments.store import TrialResult
from skidnav.statistics.formatting import plural
from skidnav.world.colours import LANDMARKS, TRAIL, unit_rgb

ARENA = (0.62, 0.505)
"""Arena width and height [m] (the thesis arena, Alhawary (2020), App. A.1.1; as
:class:`~skidnav.robot.params.RobotParams`)."""


def landmark_handles() -> list[Artist]:
    """Legend entries of the start and goal cells."""
    return [Patch(color=unit_rgb(colour), label=label) for label, colour in LANDMARKS]


ETA_SHADING_CEILING = 1.7
"""The slip shading's darkest η unless a world has more (:func:`eta_ceiling`)."""


def eta_ceiling(runs: list[TrialResult]) -> float:
    """The η drawn darkest in a figure of ``runs``' worlds: :data:`ETA_SHADING_CEILING`, or the
    largest η of any of them if larger, so every panel shades alike."""
    return max([ETA_SHADING_CEILING, *(float(run.arrays["slip_eta"].max()) for run in runs)])


def draw_arena(
    axes: Axes, run: TrialResult, *, slip: bool = True, eta_max: float | None = None
) -> None:
    """Walls, slip regions (η shading from 0 to ``eta_max``, default :func:`eta_ceiling` of this
    run), start (green), goal (red) of one run's world."""
    occupancy = run.arrays["occupancy"].astype(bool)
    if slip:
        eta = run.arrays["slip_eta"]
        region_w, region_h = ARENA[0] / (eta.shape[0] - 1), ARENA[1] / (eta.shape[1] - 1)
        axes.imshow(
            eta.T,
            origin="lower",
            cmap="Oranges",
            vmin=0.0,
            vmax=eta_max if eta_max is not None else eta_ceiling([run]),
            extent=(0, eta.shape[0] * region_w, 0, eta.shape[1] * region_h),
            alpha=0.6,
        )
    draw_cells(axes, occupancy, tuple(run.arrays["start"]), tuple(run.arrays["goal"]))


def draw_cells(
    axes: Axes,
    occupancy: np.ndarray,
    start: tuple[int, int],
    goal: tuple[int, int],
    arena: tuple[float, float] = ARENA,
) -> None:
    """Walls (``occupancy`` bool (n_x, n_y), True = wall), the start (green) and goal (red)
    cells on the cells of the arena W × H = ``arena`` [m] (W / (n_x − 1) by H / (n_y − 1) [m],
    as the discretization's), equal aspect, axes in metres (the patches carry the labels
    "start" and "goal" for a legend)."""
    n_x, n_y = occupancy.shape
    cell_w, cell_h = arena[0] / (n_x - 1), arena[1] / (n_y - 1)
    walls = np.ma.masked_where(~occupancy.T, np.ones_like(occupancy.T, dtype=float))
    axes.imshow(
        walls,
        origin="lower",
        cmap="Greys",
        vmin=0,
        vmax=1.2,
        extent=(0, n_x * cell_w, 0, n_y * cell_h),
    )
    for (i, j), (label, colour) in zip((start, goal), LANDMARKS, strict=True):
        axes.add_patch(
            Rectangle((i * cell_w, j * cell_h), cell_w, cell_h, color=unit_rgb(colour), label=label)
        )
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
    eta_max = eta_ceiling(runs)
    for ax, run in zip(axes, runs, strict=True):
        draw_arena(ax, run, eta_max=eta_max)
        poses = run.arrays["greedy_poses"]
        ax.plot(poses[:, 0], poses[:, 1], color=unit_rgb(TRAIL), linewidth=1.5)
        ax.plot(poses[-1:, 0], poses[-1:, 1], "o", color=unit_rgb(TRAIL), markersize=4)
        reached = (
            "reached goal"
            if run.summary["final_length_m"] == run.summary["final_length_m"]
            else "did not reach goal"
        )
        ax.set_title(
            f"{run.coordinates['agent']} (seed {run.coordinates['seed']})\n"
            f"{plural(len(poses) - 1, 'action')}, {reached}",
            fontsize=9,
        )
    path = Line2D([], [], color=unit_rgb(TRAIL), marker="o", markevery=[-1], label="greedy path")
    _legend(figure, [*landmark_handles(), path])
    figure.suptitle(title)
    return to_png(figure)


def value_limits(runs: list[TrialResult]) -> tuple[float, float]:
    """(lowest, highest) finite state value over every run's ``value_map``: the one colour scale
    of a value-map figure, so a colour means the same value in every panel ((0, 1) when no value
    is finite; widened by ±0.5 when all are equal)."""
    values = np.concatenate([np.ravel(run.arrays["value_map"]) for run in runs] or [np.zeros(0)])
    values = values[np.isfinite(values)]
    if values.size == 0:
        return 0.0, 1.0
    low, high = float(values.min()), float(values.max())
    return (low, high) if high > low else (low - 0.5, high + 0.5)


def value_maps_figure(runs: list[TrialResult], title: str) -> Figure:
    """The figure of :func:`value_maps`, open (its panels' images share :func:`value_limits` and
    one colour bar)."""
    figure, axes = _grid(len(runs))
    low, high = value_limits(runs)
    image = None
    for ax, run in zip(axes, runs, strict=True):
        draw_arena(ax, run, slip=False)
        value = run.arrays["value_map"]
        n_x, n_y = value.shape
        cell_w, cell_h = ARENA[0] / (n_x - 1), ARENA[1] / (n_y - 1)
        image = ax.imshow(
            np.ma.masked_invalid(value).T,
            origin="lower",
            cmap="viridis",
            vmin=low,
            vmax=high,
            extent=(0, n_x * cell_w, 0, n_y * cell_h),
        )
        _heading_arrows(ax, run.arrays["heading_map"], cell_w, cell_h)
        ax.set_title(f"{run.coordinates['agent']} (seed {run.coordinates['seed']})", fontsize=9)
    if image is not None:
        figure.colorbar(image, ax=axes, fraction=0.03, label="state value (max over actions)")
    _legend(figure, landmark_handles())
    figure.suptitle(title)
    return figure


def _heading_arrows(ax: Axes, heading: np.ndarray, cell_w: float, cell_h: float) -> None:
    """The preferred heading of each cell (``heading`` (n_x, n_y) bin indices, −1: none) as a
    white arrow; cells ``cell_w`` × ``cell_h`` [m]."""
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


def value_maps(runs: list[TrialResult], title: str) -> bytes:
    """State values (max over headings and actions) and preferred headings per cell, one panel
    per run on one colour scale (:func:`value_maps_figure`)."""
    return to_png(value_maps_figure(runs, title))


ACTION_GLYPHS = (
    (0, "forward", None, "C0"),
    (1, "backward", None, "C1"),
    (2, "turn left", r"$\circlearrowleft$", "C4"),
    (3, "turn right", r"$\circlearrowright$", "C9"),
)
"""(action, name, marker, colour) of the skid-steer env's actions; forward and backward are drawn
as arrows along and against the heading; no glyph is green or red (the start's and goal's
colours)."""


GLYPH_NAMES = frozenset(name for _, name, _, _ in ACTION_GLYPHS)


def _legend(figure: Figure, handles: list[Artist]) -> None:
    """One legend below every panel of ``figure``."""
    figure.legend(handles=handles, loc="outside lower center", ncols=len(handles), fontsize=8)


def _policy_panel(ax: Axes, run: TrialResult) -> None:
    """One run's greedy action per cell at its start heading, as glyphs over the arena."""
    draw_arena(ax, run, slip=False)
    policy = run.arrays["policy_map"]
    n_x, n_y = policy.shape
    cell_w, cell_h = ARENA[0] / (n_x - 1), ARENA[1] / (n_y - 1)
    heading = float(run.arrays["start_heading"])
    for action, name, marker, color in ACTION_GLYPHS:
        ii, jj = np.nonzero(policy == action)
        x, y = (ii + 0.5) * cell_w, (jj + 0.5) * cell_h
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
    glyphs = [h for h in axes[0].get_legend_handles_labels()[0] if h.get_label() in GLYPH_NAMES]
    _legend(figure, [*landmark_handles(), *glyphs])
    figure.suptitle(title)
    return to_png(figure)
