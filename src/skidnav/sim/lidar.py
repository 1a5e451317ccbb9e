"""A simulated 2-D lidar: range readings along rays cast over the occupancy grid.

A ray starts at the robot's position (x, y) [m] and runs along the angle θ [rad] until it first
reaches a wall cell or the arena's border; its reading is the distance travelled [m], clipped at
the maximum range. The cells are the MDP's (:func:`skidnav.world.discretization.cell_of`): in
grid units u = x / W · (n_x − 1) and v = y / H · (n_y − 1) the cell (i, j) is (⌊u⌋, ⌊v⌋), so a
ray stops exactly where a sub-step of the robot would start to collide
(:mod:`skidnav.sim.navigation`, step 4). The last column and the top row are the zero-width
lines x = W and y = H; reaching them, or x = 0 or y = 0, is reaching the border, which stops a
ray like a wall.

The traversal is Amanatides & Woo (1987), "A fast voxel traversal algorithm for ray tracing"
(Eurographics '87), in two dimensions: from the starting cell, step to whichever neighbour
(along x or along y) the ray enters first, keeping for each axis the distance at which the ray
crosses its next cell boundary (``t_next``) and the distance between two such crossings
(``t_delta``). Each step costs a comparison and an addition, and the ray visits exactly the cells
it passes through. Where the ray passes through a cell corner (both crossings at the same
distance) it steps along both axes at once, into the cell diagonally beyond, which is the one
``cell_of`` gives the points just past the corner.

>>> import numpy as np
>>> walls = np.zeros((11, 11), dtype=np.uint8)  # 1 m × 1 m, cells of 0.1 m
>>> walls[7, :] = 1  # a wall column, x in [0.7, 0.8) m
>>> ranges = np.empty(4)
>>> lidar_ranges(walls, 1.0, 1.0, 0.25, 0.6, 0.0, 2.0, ranges)
>>> [round(float(r), 12) for r in ranges]  # ahead, left, behind, right
[0.45, 0.4, 0.25, 0.6]

A laser with a field of view narrower than a full turn (a Hokuyo UST-10 sees 270°) spreads its
rays over that sector, both ends included: :class:`LaserSpec` and :func:`lidar_scan`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from skidnav._jit import inline_jit, jit
from skidnav.world.discretization import level_index

FULL_TURN = 2.0 * math.pi
"""A field of view of a full turn [rad]: a laser that sees all around."""


@inline_jit
def _axis_start(position: float, rate: float, cell: int, levels: int) -> tuple[float, float, int]:
    """The traversal's start along one axis.

    Args:
        position: the ray's origin in grid units (u or v). rate: d(position)/dt, grid units per
            metre travelled (cos θ · (n_x − 1) / W, or the same with sin θ, n_y and H).
        cell: the origin's cell index along this axis. levels: n_x or n_y.

    Returns:
        (t_next: distance [m] to the first cell boundary crossed, t_delta: distance [m] between
        successive crossings, step: +1, −1, or 0 when the ray runs parallel to the other axis).
        The last level is the zero-width border line, so its far boundary is itself.
    """
    if rate > 0.0:
        boundary = min(cell + 1, levels - 1)
        return (boundary - position) / rate, 1.0 / rate, 1
    if rate < 0.0:
        return (position - cell) / -rate, -1.0 / rate, -1
    return math.inf, math.inf, 0


@inline_jit
def cast_ray(
    occupancy: np.ndarray,
    arena_width: float,
    arena_height: float,
    x: float,
    y: float,
    angle: float,
    max_range: float,
) -> float:
    """Distance [m] from (x, y) [m] along ``angle`` [rad] to the first wall cell or the arena's
    border, at most ``max_range`` [m] (see the module doc for the traversal).

    Args:
        occupancy: uint8 (n_x, n_y), nonzero = wall. arena_width, arena_height: W, H [m].
        x, y: the ray's origin [m], clipped to the arena first (as the MDP clips poses).
        angle: the ray's direction [rad], counter-clockwise from +x.
        max_range: the greatest reading [m], > 0.

    Returns:
        The reading in [0, max_range] [m]; 0 if the origin lies in a wall cell or on the border
        facing out.
    """
    n_x, n_y = occupancy.shape
    x = min(max(x, 0.0), arena_width)
    y = min(max(y, 0.0), arena_height)
    i = level_index(x, arena_width, n_x)
    j = level_index(y, arena_height, n_y)
    if occupancy[i, j] != 0:
        return 0.0
    u = x / arena_width * (n_x - 1)  # the expressions of level_index, so ⌊u⌋ = i
    v = y / arena_height * (n_y - 1)
    t_x, delta_x, step_i = _axis_start(u, math.cos(angle) * (n_x - 1) / arena_width, i, n_x)
    t_y, delta_y, step_j = _axis_start(v, math.sin(angle) * (n_y - 1) / arena_height, j, n_y)
    while True:
        t = min(t_x, t_y)
        if t >= max_range:
            return max_range
        if t_x == t:
            i += step_i
            t_x += delta_x
            if i < 0 or i >= n_x - 1:  # reached the border x = 0 or x = W
                return t
        if t_y == t:
            j += step_j
            t_y += delta_y
            if j < 0 or j >= n_y - 1:
                return t
        if occupancy[i, j] != 0:
            return t


@jit
def lidar_ranges(
    occupancy: np.ndarray,
    arena_width: float,
    arena_height: float,
    x: float,
    y: float,
    heading: float,
    max_range: float,
    out: np.ndarray,
) -> None:
    """Fill ``out`` with the readings [m] of ``len(out)`` rays from (x, y) [m] spread evenly over
    a full turn, ray 0 along ``heading`` [rad] and the others counter-clockwise: ray k along
    heading + 2π·k / len(out). ``occupancy`` uint8 (n_x, n_y), nonzero = wall; W, H [m];
    ``max_range`` [m]; ``out`` float64 (n_rays,). See :func:`cast_ray`."""
    n_rays = out.shape[0]
    for k in range(n_rays):
        angle = heading + 2.0 * math.pi * k / n_rays
        out[k] = cast_ray(occupancy, arena_width, arena_height, x, y, angle, max_range)


@jit
def lidar_scan(
    occupancy: np.ndarray,
    arena_width: float,
    arena_height: float,
    x: float,
    y: float,
    heading: float,
    max_range: float,
    field_of_view: float,
    out: np.ndarray,
) -> None:
    """Fill ``out`` with the readings [m] of ``len(out)`` rays from (x, y) [m] over a sector of
    ``field_of_view`` [rad] centred on ``heading`` [rad]: ray k along
    heading − fov/2 + fov·k / (n − 1), clockwise edge first, both edges included (one ray:
    along ``heading``). A field of view of 2π or more is a full turn, rays as
    :func:`lidar_ranges` casts them. Other arguments as :func:`lidar_ranges`."""
    n_rays = out.shape[0]
    if field_of_view >= 2.0 * math.pi:
        lidar_ranges(occupancy, arena_width, arena_height, x, y, heading, max_range, out)
        return
    for k in range(n_rays):
        offset = 0.0 if n_rays == 1 else field_of_view * (k / (n_rays - 1) - 0.5)
        angle = heading + offset
        out[k] = cast_ray(occupancy, arena_width, arena_height, x, y, angle, max_range)


@dataclass(frozen=True)
class LaserSpec:
    """A 2-D laser scanner, validated on construction.

    Attributes:
        rays: readings per scan, ≥ 1.
        max_range: the greatest reading [m], > 0.
        field_of_view: the swept sector [rad], in (0, 2π] (2π: a full turn).
    """

    rays: int
    max_range: float
    field_of_view: float = FULL_TURN

    def __post_init__(self) -> None:
        if not (isinstance(self.rays, int) and self.rays >= 1):
            raise ValueError(f"expected rays to be an integer >= 1, got {self.rays!r}")
        if not (math.isfinite(self.max_range) and self.max_range > 0):
            raise ValueError(f"expected max_range > 0 m, got {self.max_range}")
        if not 0 < self.field_of_view <= 2.0 * math.pi:
            raise ValueError(f"expected field_of_view in (0, 2π] rad, got {self.field_of_view}")

    def angles(self, heading: float = 0.0) -> np.ndarray:
        """float64 (rays,): each ray's direction [rad], as :func:`lidar_scan` casts them."""
        k = np.arange(self.rays)
        if self.field_of_view >= 2.0 * math.pi:
            return heading + 2.0 * math.pi * k / self.rays
        if self.rays == 1:
            return np.array([heading])
        return heading + self.field_of_view * (k / (self.rays - 1) - 0.5)

    def scan(
        self,
        occupancy: np.ndarray,
        arena: tuple[float, float],
        pose: tuple[float, float, float],
    ) -> np.ndarray:
        """float64 (rays,) readings [m] from ``pose`` (x [m], y [m], heading [rad]) over the
        uint8 wall grid ``occupancy`` (n_x, n_y) of an arena (W, H) [m]."""
        out = np.empty(self.rays)
        lidar_scan(
            np.ascontiguousarray(occupancy, dtype=np.uint8),
            float(arena[0]),
            float(arena[1]),
            float(pose[0]),
            float(pose[1]),
            float(pose[2]),
            float(self.max_range),
            float(self.field_of_view),
            out,
        )
        return out


HOKUYO_UST10 = LaserSpec(rays=1081, max_range=10.0, field_of_view=math.radians(270.0))
"""The BARN Jackal's laser, a Hokuyo UST-10LX (Hokuyo's specifications): 270° field of view,
10 m range, 0.25° steps (1081 rays)."""
