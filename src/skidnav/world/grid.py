"""Occupancy-grid maps of the arena: walls, a start cell and a goal cell, and their generators.

A map's cells match the state grid (25 × 25 by default): ``occupancy[i, j]`` is True where cell
(i, j) is a wall, i along x and j along y. Map kinds (docs/simulator.md, "Maps"; ``free`` is the
thesis's default grid, Alhawary (2020), App. A.1.2): ``free`` (a wall border only), ``obstacles``
(the border plus 3–6 random rectangles, redrawn until start and goal are connected), ``maze``
(corridors three cells wide carved by a randomized depth-first search, so that the robot, which
moves ≈1.5 cells per action and slides ≈1.2 cells sideways per turn, can pass). Connectivity is
4-neighbour over free cells. Every draw comes from the Generator passed in.

Start and goal never lie on the far edge, the last column (i = n_x − 1) or the top row
(j = n_y − 1): with the cell index i = ⌊x/W·(n_x − 1)⌋ of :mod:`skidnav.world.discretization`
those cells have zero width, the lines x = W and y = H, the arena's boundary, where the robot
cannot stand and which it reaches only by being clipped against the boundary.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

MAP_KINDS = ("free", "obstacles", "maze")
MAZE_CORRIDOR = 3
"""Width of maze corridors [cells]."""
MIN_SIZE = 3
MAX_SIZE = 1000
"""Least and greatest map side [cells] (map files and generated maps)."""
MAX_TRIES = 10_000
"""Most layouts :func:`generate_map` may be asked to draw before giving up."""


@dataclass(frozen=True, eq=False)
class GridMap:
    """An occupancy grid with start and goal cells, validated on construction.

    Attributes:
        occupancy: bool array, shape (n_x, n_y); True = wall.
        start: start cell (i, j); the robot starts at its centre, heading 0 (+x).
        goal: goal cell (i, j); reaching it (any heading) ends the episode.

    Start and goal must be free, differ, and lie off the far edge (see :func:`on_far_edge`).
    """

    occupancy: np.ndarray
    start: tuple[int, int]
    goal: tuple[int, int]

    def __post_init__(self) -> None:
        occupancy = np.ascontiguousarray(self.occupancy, dtype=np.bool_)
        if occupancy.ndim != 2 or min(occupancy.shape) < 3:
            raise ValueError(
                f"expected a 2-D occupancy grid of at least 3 × 3, got {occupancy.shape}"
            )
        object.__setattr__(self, "occupancy", occupancy)
        for name in ("start", "goal"):
            cell = tuple(int(v) for v in getattr(self, name))
            if len(cell) != 2 or not all(
                0 <= v < n for v, n in zip(cell, occupancy.shape, strict=False)
            ):
                raise ValueError(f"expected {name} inside the {occupancy.shape} grid, got {cell}")
            if occupancy[cell]:
                raise ValueError(f"expected {name} on a free cell, got wall at {cell}")
            if on_far_edge(cell, occupancy.shape):
                raise ValueError(
                    f"expected {name} off the last column and the top row (zero-width cells at "
                    f"the arena's far edge), got {cell} in a {occupancy.shape} grid"
                )
            object.__setattr__(self, name, cell)
        if self.start == self.goal:
            raise ValueError(f"expected start and goal to differ, both are {self.start}")

    @property
    def shape(self) -> tuple[int, int]:
        """(n_x, n_y)."""
        return (int(self.occupancy.shape[0]), int(self.occupancy.shape[1]))

    def connected(self) -> bool:
        """True if the goal is reachable from the start through free cells (4-neighbour)."""
        return bool(reachable_cells(self.occupancy, self.start)[self.goal])

    def shortest_cell_distance(self) -> int:
        """Cells on the shortest 4-neighbour start→goal path (−1 if none)."""
        return int(cell_distances(self.occupancy, self.start)[self.goal])

    def as_uint8(self) -> np.ndarray:
        """Occupancy as uint8 (1 = wall), shape (n_x, n_y), for the compiled kernels."""
        return self.occupancy.astype(np.uint8)


def on_far_edge(cell: tuple[int, ...], shape: tuple[int, ...]) -> bool:
    """True if ``cell`` is in the last column (i = n_x − 1) or the top row (j = n_y − 1) of a
    grid of ``shape`` (n_x, n_y): a zero-width cell on the arena's boundary x = W or y = H.

    >>> [on_far_edge(cell, (25, 25)) for cell in ((24, 3), (3, 24), (0, 0), (23, 23))]
    [True, True, False, False]
    """
    return cell[0] == shape[0] - 1 or cell[1] == shape[1] - 1


def cell_distances(occupancy: np.ndarray, origin: tuple[int, int]) -> np.ndarray:
    """Breadth-first 4-neighbour distance [cells] from ``origin``; −1 where unreachable.

    Returns an int64 array of the grid's shape.
    """
    distance = np.full(occupancy.shape, -1, dtype=np.int64)
    distance[origin] = 0
    frontier = deque([origin])
    n_x, n_y = occupancy.shape
    while frontier:
        i, j = frontier.popleft()
        for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            ni, nj = i + di, j + dj
            if 0 <= ni < n_x and 0 <= nj < n_y and not occupancy[ni, nj] and distance[ni, nj] < 0:
                distance[ni, nj] = distance[i, j] + 1
                frontier.append((ni, nj))
    return distance


def reachable_cells(occupancy: np.ndarray, origin: tuple[int, int]) -> np.ndarray:
    """Bool mask of the free cells 4-connected to ``origin``."""
    return cell_distances(occupancy, origin) >= 0


def border_walls(shape: tuple[int, int]) -> np.ndarray:
    """An empty grid with a one-cell wall border."""
    occupancy = np.zeros(shape, dtype=np.bool_)
    occupancy[0, :] = occupancy[-1, :] = True
    occupancy[:, 0] = occupancy[:, -1] = True
    return occupancy


def open_cells(occupancy: np.ndarray) -> np.ndarray:
    """(k, 2) cells whose 3 × 3 neighbourhood is free: room for the robot to turn."""
    blocked = occupancy.copy()
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            blocked |= np.roll(np.roll(occupancy, di, axis=0), dj, axis=1)
    return np.argwhere(~blocked)


def place_start_goal(
    occupancy: np.ndarray, rng: np.random.Generator, min_distance: int
) -> tuple[tuple[int, int], tuple[int, int]] | None:
    """Draw a start and a goal among open cells, connected and at least ``min_distance`` cells
    apart along free paths; None if no such pair was found in 50 draws."""
    candidates = open_cells(occupancy)
    if len(candidates) < 2:
        return None
    for _ in range(50):
        start = tuple(int(v) for v in candidates[int(rng.random() * len(candidates))])
        distance = cell_distances(occupancy, start)  # type: ignore[arg-type]
        ok = distance[candidates[:, 0], candidates[:, 1]] >= min_distance
        if ok.any():
            far = candidates[ok]
            goal = tuple(int(v) for v in far[int(rng.random() * len(far))])
            return start, goal  # type: ignore[return-value]
    return None


def _add_rectangles(occupancy: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Border plus 3–6 random rectangles of 2–6 cells per side."""
    grid = occupancy.copy()
    n_x, n_y = grid.shape
    for _ in range(int(rng.integers(3, 7))):
        width = int(rng.integers(2, max(3, min(7, n_x // 3))))
        height = int(rng.integers(2, max(3, min(7, n_y // 3))))
        i = int(rng.integers(1, max(2, n_x - width - 1)))
        j = int(rng.integers(1, max(2, n_y - height - 1)))
        grid[i : i + width, j : j + height] = True
    return grid


def _carve_maze(shape: tuple[int, int], rng: np.random.Generator) -> np.ndarray:
    """Randomized depth-first maze with corridors MAZE_CORRIDOR cells wide and 1-cell walls."""
    pitch = MAZE_CORRIDOR + 1
    rooms_x, rooms_y = (shape[0] - 1) // pitch, (shape[1] - 1) // pitch
    if rooms_x < 1 or rooms_y < 1:
        raise ValueError(f"expected a grid of at least {pitch + 1} cells per side for a maze")
    grid = np.ones(shape, dtype=np.bool_)
    visited = np.zeros((rooms_x, rooms_y), dtype=np.bool_)
    stack = [(int(rng.integers(rooms_x)), int(rng.integers(rooms_y)))]
    visited[stack[0]] = True
    while stack:
        rx, ry = stack[-1]
        i, j = 1 + rx * pitch, 1 + ry * pitch
        grid[i : i + MAZE_CORRIDOR, j : j + MAZE_CORRIDOR] = False
        options = [
            (dx, dy)
            for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1))
            if 0 <= rx + dx < rooms_x and 0 <= ry + dy < rooms_y and not visited[rx + dx, ry + dy]
        ]
        if not options:
            stack.pop()
            continue
        dx, dy = options[int(rng.integers(len(options)))]
        # open the one-cell wall between the two rooms
        wi = i + MAZE_CORRIDOR if dx == 1 else i - 1 if dx == -1 else i
        wj = j + MAZE_CORRIDOR if dy == 1 else j - 1 if dy == -1 else j
        span_i = MAZE_CORRIDOR if dx == 0 else 1
        span_j = MAZE_CORRIDOR if dy == 0 else 1
        grid[wi : wi + span_i, wj : wj + span_j] = False
        visited[rx + dx, ry + dy] = True
        stack.append((rx + dx, ry + dy))
    return grid


def generate_map(
    kind: str,
    rng: np.random.Generator,
    shape: tuple[int, int] = (25, 25),
    *,
    min_distance: int | None = None,
    max_tries: int = 200,
) -> GridMap:
    """Generate a seeded map of the given kind with a connected start and goal.

    Args:
        kind: one of :data:`MAP_KINDS`.
        rng: the only source of randomness.
        shape: (n_x, n_y) cells.
        min_distance: least start→goal path length [cells], at least 1; default half the
            larger side.
        max_tries: layouts to draw before giving up, 1 to :data:`MAX_TRIES`.

    Raises:
        ValueError: an unknown kind, or an option out of range (a side outside
            [:data:`MIN_SIZE`, :data:`MAX_SIZE`], a count that is not an integer).

    >>> m = generate_map("obstacles", np.random.default_rng(0))
    >>> m.shape, m.connected()
    ((25, 25), True)
    >>> generate_map("free", np.random.default_rng(0), max_tries=10**12)
    Traceback (most recent call last):
    ...
    ValueError: expected max_tries to be an integer in [1, 10,000], got 1000000000000
    """
    if kind not in MAP_KINDS:
        raise ValueError(f"expected map kind one of {', '.join(MAP_KINDS)}, got {kind!r}")
    shape = _check_shape(shape)
    if min_distance is None:
        min_distance = max(shape) // 2
    _check_integer("min_distance", min_distance, 1, shape[0] * shape[1])
    _check_integer("max_tries", max_tries, 1, MAX_TRIES)
    for _ in range(max_tries):
        if kind == "free":
            occupancy = border_walls(shape)
        elif kind == "obstacles":
            occupancy = _add_rectangles(border_walls(shape), rng)
        else:
            occupancy = _carve_maze(shape, rng)
        placed = place_start_goal(occupancy, rng, min_distance)
        if placed is not None:
            return GridMap(occupancy=occupancy, start=placed[0], goal=placed[1])
    raise ValueError(f"could not place a connected start and goal on a {kind} map of {shape}")


def refinement_factor(coarse: int, fine: int, axis: str) -> int:
    """The integer f ≥ 1 with ``fine − 1 = f · (coarse − 1)`` levels along ``axis``; ValueError
    otherwise. Only such a refinement nests every fine cell inside one coarse cell (cells are
    W/(n − 1) wide, :mod:`skidnav.world.discretization`).

    >>> refinement_factor(25, 49, "x")
    2
    >>> refinement_factor(25, 50, "x")
    Traceback (most recent call last):
    ...
    ValueError: expected n_x − 1 to be a multiple of 24 (the map's 25 levels), got 50
    """
    factor, rest = divmod(fine - 1, coarse - 1)
    if rest or factor < 1:
        raise ValueError(
            f"expected n_{axis} − 1 to be a multiple of {coarse - 1} (the map's {coarse} "
            f"levels), got {fine}"
        )
    return factor


def refine_map(grid_map: GridMap, shape: tuple[int, int]) -> GridMap:
    """The same arena on a finer grid of ``shape`` (n_x′, n_y′) cells, each side a refinement
    f of the map's (:func:`refinement_factor`).

    Fine cell (i′, j′) covers part of coarse cell (i′ // f_x, j′ // f_y) and inherits its wall, so
    the walls occupy the same metres (the zero-width last level maps to the last level). Start and
    goal become the fine cells holding the centres of the coarse ones (for an even f the centre lies
    on that cell's lower edge). The goal of the refined map is one fine cell, 1/(f_x · f_y) of the
    coarse goal's area, as the MDP defines a goal (:mod:`skidnav.sim.navigation`): users that keep
    the world's task take the coarse goal cell instead
    (:func:`skidnav.experiments.reference.finegrid.goal_states`).

    >>> walls = border_walls((5, 5))
    >>> fine = refine_map(GridMap(walls, start=(1, 1), goal=(2, 3)), (13, 13))
    >>> fine.shape, fine.start, fine.goal, bool(fine.occupancy[2, 5]), bool(fine.occupancy[3, 3])
    ((13, 13), (4, 4), (7, 10), True, False)
    """
    factors = [
        refinement_factor(coarse, int(fine), axis)
        for coarse, fine, axis in zip(grid_map.shape, _check_shape(shape), "xy", strict=True)
    ]
    rows = np.arange(shape[0]) // factors[0]
    columns = np.arange(shape[1]) // factors[1]
    occupancy = grid_map.occupancy[np.ix_(rows, columns)]

    def centred(cell: tuple[int, int]) -> tuple[int, int]:
        return (cell[0] * factors[0] + factors[0] // 2, cell[1] * factors[1] + factors[1] // 2)

    return GridMap(occupancy, start=centred(grid_map.start), goal=centred(grid_map.goal))


def _check_integer(name: str, value: object, low: int, high: int) -> None:
    if not (isinstance(value, int) and not isinstance(value, bool) and low <= value <= high):
        raise ValueError(f"expected {name} to be an integer in [{low}, {high:,}], got {value!r}")


def _check_shape(shape: object) -> tuple[int, int]:
    """``shape`` as (n_x, n_y) if it is two integer sides in [MIN_SIZE, MAX_SIZE]."""
    if not (isinstance(shape, tuple | list) and len(shape) == 2):
        raise ValueError(f"expected shape to be two integers [n_x, n_y], got {shape!r}")
    for side in shape:
        _check_integer("each side of shape", side, MIN_SIZE, MAX_SIZE)
    return (int(shape[0]), int(shape[1]))
