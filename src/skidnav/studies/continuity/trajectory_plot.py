"""The trajectories of several policies drawn on one arena (a companion of
:mod:`skidnav.studies.continuity.traces`); PNG bytes, rendered headless (Agg).

The arena is drawn as the experiment report draws it
(:func:`~skidnav.experiments.report.maps.draw_cells`): the whole cell grid, y up; walls grey, the
start cell green, the goal cell red (:mod:`skidnav.world.colours`), both named in the legend. Each
policy is one coloured line (never green or red) through the poses of its trace from the start
pose (a dot) to its last pose: a filled circle when it reached the goal, a cross when it did not;
the legend names the policy and its time to goal.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt

from skidnav.experiments.report.maps import draw_cells
from skidnav.experiments.report.plots import DPI, to_png
from skidnav.files.atomic import write_user_file
from skidnav.statistics.formatting import plural
from skidnav.studies.continuity.traces import Trace
from skidnav.world.grid import GridMap

LINE_COLOURS = ("C0", "C1", "C4", "C5", "C6", "C7", "C8", "C9")
"""The policies' line colours: matplotlib's tab10 without its green and red (the start's and the
goal's colours)."""
FIGURE_SIZE = (6.4, 6.0)
"""Width and height of the picture [inches]; at :data:`~skidnav.experiments.report.plots.DPI`
(90 pixels per inch) 576 × 540 pixels."""


def _label(name: str, trace: Trace) -> str:
    if trace.terminated:
        return f"{name}: goal in {trace.n_actions * trace.control_period:g} s"
    return f"{name}: no goal ({plural(trace.n_actions, 'action')})"


def trajectory_picture(
    grid_map: GridMap,
    traces: Mapping[str, Trace],
    *,
    title: str | None = None,
    dpi: int = DPI,
) -> bytes:
    """PNG bytes of the arena (``grid_map`` on the default arena's cells) with one line per
    named trace (module doc), :data:`FIGURE_SIZE` inches at ``dpi`` [pixels per inch]."""
    figure, axes = plt.subplots(figsize=FIGURE_SIZE, layout="constrained")
    draw_cells(axes, grid_map.occupancy, grid_map.start, grid_map.goal)
    axes.set_xlabel("x [m]")
    axes.set_ylabel("y [m]")
    for number, (name, trace) in enumerate(traces.items()):
        colour = LINE_COLOURS[number % len(LINE_COLOURS)]
        x, y = trace.poses[:, 0], trace.poses[:, 1]
        axes.plot(x, y, color=colour, linewidth=1.8, label=_label(name, trace))
        axes.plot(x[:1], y[:1], "o", color=colour, markersize=3)
        end = "o" if trace.terminated else "x"
        axes.plot(x[-1:], y[-1:], end, color=colour, markersize=7, markeredgewidth=2)
    if traces:
        figure.legend(loc="outside lower center", ncols=2, fontsize=8, frameon=False)
    if title is not None:
        axes.set_title(title, fontsize=10)
    return to_png(figure, dpi, crop=False)


def save_trajectory_picture(
    path: Path | str,
    grid_map: GridMap,
    traces: Mapping[str, Trace],
    *,
    title: str | None = None,
    dpi: int = DPI,
) -> None:
    """Write :func:`trajectory_picture` to ``path`` all-or-nothing
    (:func:`~skidnav.files.atomic.write_user_file`: UserError when it cannot be written)."""
    png = trajectory_picture(grid_map, traces, title=title, dpi=dpi)
    write_user_file(path, png, "picture")
