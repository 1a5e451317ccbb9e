"""A picture of a few BARN worlds with each agent's scored trajectory, as PNG bytes (Agg).

Each panel is one world as every picture of a world draws it
(:func:`~skidnav.experiments.report.maps.draw_cells`: walls grey, start cell green, goal cell
red), with the goal's 1-m disc outlined, the arena cut to the rows the runs use, and one
coloured line per agent (never green or red) through the poses of its scored run: a filled
circle at the end of a success, a cross at the end of a failure.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Circle

from skidnav.experiments.report.maps import draw_cells, landmark_handles
from skidnav.experiments.report.plots import to_png
from skidnav.studies.continuity.trajectory_plot import LINE_COLOURS
from skidnav.world.barn import load_barn_world

Y_LIMITS = (1.5, 14.5)
"""The rows drawn [m]: from below the start (y = 3 m) to beyond the goal (y = 13 m)."""


def worlds_picture(
    trajectories: Mapping[int, Sequence[tuple[str, np.ndarray, bool]]], title: str
) -> bytes:
    """One panel per world of ``trajectories`` (world → (agent label, poses float (T + 1, 3)
    [m, m, rad], success) per agent), left to right in world order."""
    worlds = sorted(trajectories)
    figure, axes = plt.subplots(
        1, len(worlds), figsize=(2.6 * len(worlds) + 0.6, 6.4), squeeze=False,
        layout="constrained",
    )  # fmt: skip
    labels = sorted({label for runs in trajectories.values() for label, _, _ in runs})
    colours = dict(zip(labels, LINE_COLOURS * (len(labels) // len(LINE_COLOURS) + 1), strict=False))
    for ax, number in zip(axes[0], worlds, strict=True):
        world = load_barn_world(number)
        grid = world.map.grid
        arena = (world.discretization.arena_width, world.discretization.arena_height)
        draw_cells(ax, grid.occupancy, grid.start, grid.goal, arena)
        ax.add_patch(Circle(world.goal, world.goal_radius, fill=False, color="0.4", ls="--"))
        for label, poses, success in trajectories[number]:
            colour = colours[label]
            ax.plot(poses[:, 0], poses[:, 1], color=colour, linewidth=1.3, label=label)
            marker = "o" if success else "x"
            ax.plot(poses[-1, 0], poses[-1, 1], marker, color=colour, markersize=6)
        ax.set_ylim(*Y_LIMITS)
        ax.set_title(f"world {number}", fontsize=9)
    handles = landmark_handles() + [
        Line2D([], [], color=colours[label], label=label) for label in labels
    ]
    figure.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), 4))
    figure.suptitle(title, fontsize=10)
    return to_png(figure)
