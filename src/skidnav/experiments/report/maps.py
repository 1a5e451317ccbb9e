"""Pictures of the arena in an experiment report, as PNG bytes: the final greedy trajectories, the
state values with preferred headings and the greedy actions of each run's world
(:func:`draw_cells` also draws the continuity study's trajectories,
:mod:`skidnav.studies.continuity.trajectory_plot`).

Every picture draws the start cell green and the goal cell red (:mod:`skidnav.world.colours`,
the convention of every picture of a world) and names them in its legend.
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
    for ax, run in zip(axes, runs, strict=True):
        draw_arena(ax, run)
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
    _legend(figure, landmark_handles())
    figure.suptitle(title)
    return to_png(figure)


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
