"""The BARN benchmark's 300 static worlds as skidnav maps, and its navigation metric.

BARN (Benchmark Autonomous Robot Navigation; Perille, Truong, Xiao & Stone (2020),
"Benchmarking metric ground navigation", IEEE SSRR) is 300 worlds of unit cylinders (radius
0.075 m) in which a Clearpath Jackal drives from a start to a goal 10 m ahead through a 4.5 m ×
4.5 m obstacle field. The worlds, reference paths and rules come from the public repository
``Daffan/the-barn-challenge`` (MIT licence); :mod:`skidnav.world.barn_import` converts them and
the package ships the result (``skidnav/data/barn/``, see its README).

The arena frame: the benchmark's Gazebo frame shifted by :data:`ARENA_ORIGIN`, so the arena is
x ∈ [0, 4.5] m, y ∈ [0, 15] m, cut into cells of :data:`CELL` = 0.15 m (31 × 101 levels, the
last of each the zero-width border line, :mod:`skidnav.world.discretization`). The cylinders sit
on a 0.15 m lattice, each at the centre of one cell, which becomes a wall cell (the cell is the
cylinder's bounding square). Cells of row ``FIELD_ROW + b`` and column ``a`` are the obstacle
field's cell (a, b), the grid of the benchmark's reference paths.

The rules (the repository's ``run.py``): start at (−2.25, 3) m in the Gazebo frame heading 1.57
rad (+y), goal 10 m ahead; success when the robot comes within 1 m of the goal without a
collision within 100 s. The score of a run is

    success · OT / clip(AT, 2·OT, 8·OT),     OT = L / 2 m/s,

AT the run's time [s] and L the length [m] of the polyline start → reference path → goal, whose
grid points ``run.py`` maps to metres as x = 0.15·a − 4.575, y = 0.15·b + 5.075 (Gazebo frame).
That mapping puts each point 0.15 m left of and 0.10 m below the centre of the cell (a, b) it
names; :func:`path_point` keeps it and its arithmetic, so OT is the benchmark's to the last digit.
"""

from __future__ import annotations

import math
import zipfile
from importlib import resources
from typing import NamedTuple

import numpy as np

from skidnav.world.discretization import Discretization
from skidnav.world.mapfile import MapFile, MapFileError, parse_map_file

N_WORLDS = 300
"""Static BARN worlds, numbered 0 … 299."""
CELL = 0.15
"""Side of a cell [m]: the cylinders' lattice pitch (twice their radius)."""
CYLINDER_RADIUS = 0.075
"""Radius of every BARN cylinder [m]."""
SHAPE = (31, 101)
"""(n_x, n_y) levels of a converted map: 30 columns of cylinders, 100 rows up to y = 15 m, and
the zero-width border line of each axis."""
ARENA_ORIGIN = (-4.5, 0.0)
"""The arena's (0, 0) in the benchmark's Gazebo frame [m]: arena = Gazebo − origin."""
FIELD_ROW = 34
"""Map row of the obstacle field's first row (the reference paths' b = 0)."""
FIELD_SIZE = 30
"""Cells per side of the obstacle field (the reference paths' grid)."""
START_GAZEBO = (-2.25, 3.0, 1.57)
"""Start pose in the Gazebo frame (x [m], y [m], heading [rad]), as ``run.py``."""
GOAL_OFFSET = (0.0, 10.0)
"""Goal relative to the start position [m]."""
GOAL_RADIUS = 1.0
"""Distance to the goal [m] within which a run succeeds."""
TIME_LIMIT = 100.0
"""A run that has not succeeded after this long [s] failed."""
REFERENCE_SPEED = 2.0
"""Speed [m/s] the optimal time OT assumes (the Jackal's top speed)."""
DATA_DIR = ("data", "barn")
"""The shipped worlds inside the ``skidnav`` package."""
WORLDS_ZIP = "worlds.zip"
"""Archive of ``world_N.txt`` map files (format version 2) in :data:`DATA_DIR`."""


class BarnWorld(NamedTuple):
    """One BARN world in the arena frame (SI units).

    Attributes:
        number: the world's number, 0 … 299.
        map: the map file: grid, cell size, start pose, goal point and radius, reference cells.
        discretization: the map's cells and arena (20 heading bins, 7 × 7 slip regions).
        start_pose: (x [m], y [m], heading [rad]).
        goal: (x [m], y [m]). goal_radius: success distance [m].
        reference_path: float64 (k + 2, 2) [m], arena frame: the start, the k reference
            points mapped as ``run.py`` maps them, the goal.
        optimal_time: OT [s], the reference path's length over :data:`REFERENCE_SPEED`.
    """

    number: int
    map: MapFile
    discretization: Discretization
    start_pose: tuple[float, float, float]
    goal: tuple[float, float]
    goal_radius: float
    reference_path: np.ndarray
    optimal_time: float


def to_arena(x: float, y: float) -> tuple[float, float]:
    """A Gazebo-frame point [m] in the arena frame [m]."""
    return x - ARENA_ORIGIN[0], y - ARENA_ORIGIN[1]


def start_pose() -> tuple[float, float, float]:
    """The start pose in the arena frame (x [m], y [m], heading [rad])."""
    return (*to_arena(*START_GAZEBO[:2]), START_GAZEBO[2])


def goal_point() -> tuple[float, float]:
    """The goal in the arena frame [m]."""
    return to_arena(START_GAZEBO[0] + GOAL_OFFSET[0], START_GAZEBO[1] + GOAL_OFFSET[1])


def field_cell(a: int, b: int) -> tuple[int, int]:
    """The map cell (i, j) of the obstacle field's cell (a, b) (a reference path's grid point)."""
    return a, FIELD_ROW + b


def path_point(a: int, b: int) -> tuple[float, float]:
    """A reference path's grid point (a, b) in metres, Gazebo frame, with ``run.py``'s
    arithmetic (see the module docstring: not the centre of the cell it names)."""
    x_shift = -CYLINDER_RADIUS - (FIELD_SIZE * CYLINDER_RADIUS * 2)
    y_shift = CYLINDER_RADIUS + 5
    return a * (CYLINDER_RADIUS * 2) + x_shift, b * (CYLINDER_RADIUS * 2) + y_shift


def gazebo_reference_path(cells: tuple[tuple[int, int], ...]) -> np.ndarray:
    """float64 (k + 2, 2) [m], Gazebo frame: the start, the points of the reference path given
    as map cells (:func:`field_cell`), the goal."""
    start = START_GAZEBO[:2]
    goal = (start[0] + GOAL_OFFSET[0], start[1] + GOAL_OFFSET[1])
    points = [path_point(i, j - FIELD_ROW) for i, j in cells]
    return np.array([start, *points, goal], dtype=np.float64)


def optimal_time(path: np.ndarray) -> float:
    """OT [s]: the length of the polyline ``path`` (k, 2) [m] over :data:`REFERENCE_SPEED`,
    summed segment by segment in order as ``run.py`` sums it."""
    length = 0.0
    for (x0, y0), (x1, y1) in zip(path[:-1].tolist(), path[1:].tolist(), strict=True):
        length += ((x0 - x1) ** 2 + (y0 - y1) ** 2) ** 0.5
    return length / REFERENCE_SPEED


def barn_score(success: bool, actual_time: float, optimal_time: float) -> float:
    """The BARN score of one run: success · OT / clip(AT, 2·OT, 8·OT) (``run.py``).

    Args:
        success: the run reached the goal (within :data:`GOAL_RADIUS`) without a collision
            before :data:`TIME_LIMIT`.
        actual_time: AT, the run's time [s] (``run.py`` starts it when the robot has left the
            start by 0.1 m).
        optimal_time: OT [s] > 0 (:func:`optimal_time`).

    A success scores between 1/8 (AT ≥ 8·OT) and 1/2 (AT ≤ 2·OT); a failure scores 0.

    >>> barn_score(True, 10.0, 4.0), barn_score(True, 5.0, 4.0), barn_score(False, 10.0, 4.0)
    (0.4, 0.5, 0.0)
    """
    if not (math.isfinite(optimal_time) and optimal_time > 0):
        raise ValueError(f"expected optimal_time > 0 s, got {optimal_time}")
    if not (math.isfinite(actual_time) and actual_time >= 0):
        raise ValueError(f"expected actual_time >= 0 s, got {actual_time}")
    if not success:
        return 0.0
    return optimal_time / min(max(actual_time, 2 * optimal_time), 8 * optimal_time)


def world_name(index: int) -> str:
    """The map file name of world ``index`` in the shipped archive."""
    return f"world_{index}.txt"


def load_barn_world(index: int) -> BarnWorld:
    """BARN world ``index`` (0 … 299) from the package's shipped maps; ValueError for another
    index."""
    if not (isinstance(index, int) and 0 <= index < N_WORLDS):
        raise ValueError(f"expected a BARN world index in [0, {N_WORLDS - 1}], got {index!r}")
    archive = resources.files("skidnav").joinpath(*DATA_DIR, WORLDS_ZIP)
    with archive.open("rb") as stream, zipfile.ZipFile(stream) as worlds:
        text = worlds.read(world_name(index)).decode("utf-8")
    return barn_world(
        index, parse_map_file(text, f"skidnav/data/barn/{WORLDS_ZIP}:{world_name(index)}")
    )


def barn_world(index: int, document: MapFile) -> BarnWorld:
    """The :class:`BarnWorld` of a converted map; MapFileError if it lacks a start pose, a goal
    or a reference path."""
    if document.start_pose is None or document.goal is None or not document.path:
        raise MapFileError(f"BARN world {index}: expected a map with start, goal and path")
    path = gazebo_reference_path(document.path)
    return BarnWorld(
        number=index,
        map=document,
        discretization=document.discretization(),
        start_pose=document.start_pose,
        goal=document.goal[:2],
        goal_radius=document.goal[2],
        reference_path=path - np.array(ARENA_ORIGIN),
        optimal_time=optimal_time(path),
    )
