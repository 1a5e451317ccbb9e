"""Discretization of continuous poses into tabular states and coarse slip regions.

Thesis convention (Alhawary (2020), App. A.1.1): with arena width W [m] and ``n_x`` levels, the cell
index is ``i = floor(x / W · (n_x − 1))``, so the default 25 levels give cells of W/24 and the
boundary x = W falls in the last cell (a border wall in every shipped map). y likewise with H and
``n_y``. The heading bin is ``floor((atan2(sin ψ, cos ψ) + π) / 2π · n_headings) mod n_headings``;
for 20 bins it equals the thesis's k + 10 with k = floor(atan2(sin ψ, cos ψ)/2π · 20) ∈ −10..9.

Flat state index: ``state = (i · n_y + j) · n_headings + heading_bin``.
Flat region index: ``region = region_i · regions_y + region_j`` with region_i computed like i
with ``regions_x`` levels (7 by default: the thesis's floor(x/0.62·6)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from skidnav._jit import jit
from skidnav.robot.kinematics import wrap_angle


class GridShape(NamedTuple):
    """The integers the compiled kernels need to discretize a pose."""

    n_x: int
    n_y: int
    n_headings: int
    regions_x: int
    regions_y: int
    arena_width: float
    arena_height: float


@jit
def level_index(value: float, extent: float, levels: int) -> int:
    """``floor(value / extent · (levels − 1))`` clipped to [0, levels − 1]."""
    index = math.floor(value / extent * (levels - 1))
    if index < 0:
        return 0
    if index > levels - 1:
        return levels - 1
    return index


@jit
def heading_bin(heading: float, n_headings: int) -> int:
    """Bin of a heading [rad] among ``n_headings`` equal sectors starting at −π."""
    wrapped = wrap_angle(heading)
    return math.floor((wrapped + math.pi) / (2.0 * math.pi) * n_headings) % n_headings


@jit
def cell_of(x: float, y: float, grid: GridShape) -> tuple[int, int]:
    """Cell (i, j) of a position [m]."""
    return (
        level_index(x, grid.arena_width, grid.n_x),
        level_index(y, grid.arena_height, grid.n_y),
    )


@jit
def squeezes_between_walls(
    walls: np.ndarray, from_i: int, from_j: int, to_i: int, to_j: int
) -> bool:
    """Whether a move from cell (``from_i``, ``from_j``) into cell (``to_i``, ``to_j``) changes
    both indices between two walls meeting at a corner: both cells beside the move, (``from_i``,
    ``to_j``) and (``to_i``, ``from_j``), are set in ``walls`` bool (n_x, n_y). Only a point
    passes such a gap, of no width."""
    if from_i == to_i or from_j == to_j:
        return False
    return bool(walls[from_i, to_j] and walls[to_i, from_j])


@jit
def state_of(x: float, y: float, heading: float, grid: GridShape) -> int:
    """Flat state index of a pose (x [m], y [m], heading [rad])."""
    i, j = cell_of(x, y, grid)
    return (i * grid.n_y + j) * grid.n_headings + heading_bin(heading, grid.n_headings)


@jit
def region_of(x: float, y: float, grid: GridShape) -> int:
    """Flat coarse slip-region index of a position [m]."""
    region_i = level_index(x, grid.arena_width, grid.regions_x)
    region_j = level_index(y, grid.arena_height, grid.regions_y)
    return region_i * grid.regions_y + region_j


@dataclass(frozen=True)
class Discretization:
    """Quantization levels of the tabular state, validated on construction.

    Attributes:
        n_x, n_y: position levels along x and y (cells are W/(n_x − 1) by H/(n_y − 1)).
        n_headings: heading bins over a full turn.
        regions_x, regions_y: coarse slip-region levels.
        arena_width, arena_height: arena extent [m].

    >>> d = Discretization()
    >>> d.n_states, d.cell_width
    (12500, 0.025833333333333333)
    >>> d.state(0.30, 0.20, 0.0)  # i = ⌊0.30/0.62·24⌋ = 11, j = ⌊0.20/0.505·24⌋ = 9, bin 10
    5690
    >>> d.unflatten(5690)
    (11, 9, 10)
    """

    n_x: int = 25
    n_y: int = 25
    n_headings: int = 20
    regions_x: int = 7
    regions_y: int = 7
    arena_width: float = 0.62
    arena_height: float = 0.505

    def __post_init__(self) -> None:
        for name in ("n_x", "n_y", "regions_x", "regions_y"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 2):
                raise ValueError(f"expected {name} to be an integer >= 2, got {value!r}")
        if not (isinstance(self.n_headings, int) and self.n_headings >= 1):
            raise ValueError(f"expected n_headings to be an integer >= 1, got {self.n_headings!r}")
        for name in ("arena_width", "arena_height"):
            if not getattr(self, name) > 0:
                raise ValueError(f"expected {name} > 0 m, got {getattr(self, name)}")

    @property
    def n_states(self) -> int:
        """n_x · n_y · n_headings."""
        return self.n_x * self.n_y * self.n_headings

    @property
    def n_regions(self) -> int:
        """regions_x · regions_y."""
        return self.regions_x * self.regions_y

    @property
    def cell_width(self) -> float:
        """Cell extent along x [m]."""
        return self.arena_width / (self.n_x - 1)

    @property
    def cell_height(self) -> float:
        """Cell extent along y [m]."""
        return self.arena_height / (self.n_y - 1)

    def grid_shape(self) -> GridShape:
        """The levels as the named tuple the kernels take."""
        return GridShape(
            self.n_x,
            self.n_y,
            self.n_headings,
            self.regions_x,
            self.regions_y,
            float(self.arena_width),
            float(self.arena_height),
        )

    def state(self, x: float, y: float, heading: float) -> int:
        """Flat state index of a pose."""
        return int(state_of(float(x), float(y), float(heading), self.grid_shape()))

    def cell(self, x: float, y: float) -> tuple[int, int]:
        """Cell (i, j) of a position [m]."""
        i, j = cell_of(float(x), float(y), self.grid_shape())
        return int(i), int(j)

    def region(self, x: float, y: float) -> int:
        """Flat slip-region index of a position [m]."""
        return int(region_of(float(x), float(y), self.grid_shape()))

    def unflatten(self, state: int) -> tuple[int, int, int]:
        """(i, j, heading_bin) of a flat state index."""
        cell, heading = divmod(int(state), self.n_headings)
        i, j = divmod(cell, self.n_y)
        return i, j, heading

    def cell_centre(self, i: int, j: int) -> tuple[float, float]:
        """Centre of cell (i, j) [m], clipped to the arena.

        The last level (i = n_x − 1, j = n_y − 1) is a zero-width cell, the boundary line x = W
        or y = H, so its "centre" is that line: the point returned always lies in cell (i, j) and
        in the arena. (Maps never put the start or goal there; see :mod:`skidnav.world.grid`.)

        >>> d = Discretization()
        >>> d.cell_centre(23, 0) == (23.5 * d.cell_width, 0.5 * d.cell_height)
        True
        >>> d.cell_centre(24, 24), d.cell(*d.cell_centre(24, 24))
        ((0.62, 0.505), (24, 24))
        """
        x = min((i + 0.5) * self.cell_width, self.arena_width)
        y = min((j + 0.5) * self.cell_height, self.arena_height)
        return x, y

    def heading_centre(self, heading_index: int) -> float:
        """Centre angle of a heading bin [rad], in [−π, π)."""
        return -math.pi + (heading_index + 0.5) * 2.0 * math.pi / self.n_headings

    def state_cells(self) -> np.ndarray:
        """(i, j) of every flat state, shape (n_states, 2)."""
        states = np.arange(self.n_states)
        cells = states // self.n_headings
        return np.stack([cells // self.n_y, cells % self.n_y], axis=1)
