"""The plain-text map format: load, save, and one-line errors naming file, line and column.

Format (version 1)::

    skidnav-map 1
    # comment lines start with '#' followed by a space, or are blank; only before 'map'
    width 25
    height 25
    map
    #########################
    #.......................#
    ...

After the line ``map`` come exactly ``height`` rows of exactly ``width`` characters. The first row
is the top of the arena (j = height − 1), the last row the bottom (j = 0); column c is i = c.
Characters: ``#`` or ``@`` wall, ``.`` free, ``S`` start (free), ``G`` goal (free); exactly one S
and one G, and the goal must be reachable from the start (4-neighbour). Each of ``width`` and
``height`` (3 to :data:`MAX_SIZE`) is given once. S and G may not lie in the last column nor in the
top row: those are zero-width cells on the arena's far edge (see :mod:`skidnav.world.grid`).
A file is at most :data:`MAX_MAP_BYTES` long; errors quote at most a short excerpt of it.

Version 2 (first line ``skidnav-map 2``) adds optional header lines, each given at most once,
for maps of a real arena (the BARN worlds, :mod:`skidnav.world.barn`):

- ``cell SIZE``: the side of a cell [m], so the arena is SIZE·(width − 1) by SIZE·(height − 1)
  metres (cell index i = ⌊x / SIZE⌋, :mod:`skidnav.world.discretization`);
- ``start X Y HEADING``: the start pose [m, m, rad], inside the S cell (needs ``cell``);
- ``goal X Y RADIUS``: the goal point [m] inside the G cell, and the distance [m] > 0 from it
  within which the goal counts as reached (needs ``cell``);
- ``path I,J I,J …``: a reference path as free cells, in order.

A version-1 file is a version-2 file without these lines; :func:`format_map_file` writes version 1
whenever none of them is set.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from skidnav.errors import UserError, excerpt
from skidnav.files.atomic import write_atomic
from skidnav.files.user import read_limited
from skidnav.world.discretization import Discretization
from skidnav.world.grid import MAX_SIZE, MIN_SIZE, GridMap, on_far_edge

MAGIC = "skidnav-map 1"
MAGIC_PREFIX = "skidnav-map "
VERSIONS = (1, 2)
"""Format versions read; a file is written in the lowest that holds it."""
MAX_MAP_BYTES = 4 * 2**20
"""Longest map file read [bytes] (a 1000 × 1000 map takes about 1 MB)."""
MAX_PATH_CELLS = 100_000
"""Most cells of a ``path`` line."""
WALL_CHARS = "#@"
FREE_CHARS = ".SG"
_ARITY = {"width": 1, "height": 1, "cell": 1, "start": 3, "goal": 3}
_SYNTAX = {
    "width": "'width N'",
    "height": "'height N'",
    "cell": "'cell SIZE'",
    "start": "'start X Y HEADING'",
    "goal": "'goal X Y RADIUS'",
    "path": "'path I,J …'",
}


class MapFileError(UserError):
    """A map file that cannot be read; the message is ``path:line:column: problem``."""


@dataclass(frozen=True)
class MapFile:
    """A map with the optional metric facts of format version 2 (SI units).

    Attributes:
        grid: the occupancy grid with its start and goal cells.
        cell_size: side of a cell [m], or None (the arena then comes from the robot).
        start_pose: (x [m], y [m], heading [rad]) inside the start cell, or None (its centre,
            heading 0).
        goal: (x [m], y [m], radius [m]) inside the goal cell, or None (the goal cell itself).
        path: a reference path as cells (i, j), in order; empty if none.
    """

    grid: GridMap
    cell_size: float | None = None
    start_pose: tuple[float, float, float] | None = None
    goal: tuple[float, float, float] | None = None
    path: tuple[tuple[int, int], ...] = ()

    @property
    def version(self) -> int:
        """The lowest format version that holds this map."""
        extras = (self.cell_size, self.start_pose, self.goal)
        return 2 if self.path or any(v is not None for v in extras) else 1

    def discretization(self, **levels: int) -> Discretization:
        """The discretization of this map's cells and arena (``cell_size`` needed); ``levels``
        sets the other levels (``n_headings``, ``regions_x``, ``regions_y``)."""
        if self.cell_size is None:
            raise ValueError("expected a map with a cell size, got none")
        n_x, n_y = self.grid.shape
        return Discretization(
            n_x=n_x,
            n_y=n_y,
            arena_width=self.cell_size * (n_x - 1),
            arena_height=self.cell_size * (n_y - 1),
            **levels,
        )


def _fail(path: Path | str, line: int, message: str, column: int | None = None) -> MapFileError:
    where = f"{path}:{line}" + (f":{column}" if column is not None else "")
    return MapFileError(f"{where}: {message}")


def _read_version(path: Path | str, lines: list[str]) -> int:
    first = lines[0].strip() if lines else ""
    number = first[len(MAGIC_PREFIX) :]
    if not first.startswith(MAGIC_PREFIX) or number not in {str(v) for v in VERSIONS}:
        raise _fail(path, 1, f"expected first line {MAGIC!r}, got {excerpt(first)}")
    return int(number)


def _header_value(path: Path | str, number: int, key: str, value: str) -> object:
    """The value of header line ``key value``: an int size, a tuple of floats, or path cells."""
    if not value.isascii():  # int() and float() also read other scripts' digits, e.g. "６"
        raise _fail(path, number, f"expected ASCII numbers after {key}, got {excerpt(value)}")
    if key == "path":
        return _path_cells(path, number, value)
    words = value.split()
    if len(words) != _ARITY[key]:
        raise _fail(
            path, number, f"expected {_ARITY[key]} number(s) after {key}, got {excerpt(value)}"
        )
    if key in ("width", "height"):
        if not words[0].isdigit():  # ASCII here: no sign, no "_" (int() would take "1_0")
            raise _fail(path, number, f"expected an integer {key}, got {excerpt(words[0])}")
        size = int(words[0])
        if not MIN_SIZE <= size <= MAX_SIZE:
            raise _fail(
                path, number, f"expected {key} between {MIN_SIZE} and {MAX_SIZE}, got {size}"
            )
        return size
    try:
        numbers = tuple(float(word) for word in words)
    except ValueError:
        raise _fail(path, number, f"expected numbers after {key}, got {excerpt(value)}") from None
    if not all(math.isfinite(v) for v in numbers):
        raise _fail(path, number, f"expected finite numbers after {key}, got {excerpt(value)}")
    if (key == "cell" and not numbers[0] > 0) or (key == "goal" and not numbers[2] > 0):
        raise _fail(path, number, f"expected a {key} size > 0 m, got {excerpt(value)}")
    return numbers


def _path_cells(path: Path | str, number: int, value: str) -> tuple[tuple[int, int], ...]:
    words = value.split()
    if not 1 <= len(words) <= MAX_PATH_CELLS:
        raise _fail(path, number, f"expected 1 to {MAX_PATH_CELLS} cells 'I,J' after path")
    cells = []
    for word in words:
        i, comma, j = word.partition(",")
        if not (comma and i.isdigit() and j.isdigit()):
            raise _fail(path, number, f"expected path cells 'I,J', got {excerpt(word)}")
        cells.append((int(i), int(j)))
    return tuple(cells)


def _read_header(
    path: Path | str, lines: list[str]
) -> tuple[dict[str, object], dict[str, int], int]:
    """Parse the header; returns (values by key, line of each key, index of the first grid line)."""
    version = _read_version(path, lines)
    keys = (
        ("width", "height")
        if version == 1
        else ("width", "height", "cell", "start", "goal", "path")
    )
    values: dict[str, object] = {}
    given_on: dict[str, int] = {}
    for number, raw in enumerate(lines[1:], start=2):
        text = raw.strip()
        if not text or text.startswith("# "):
            continue
        if text == "map":
            missing = [k for k in ("width", "height") if k not in values]
            if missing:
                raise _fail(path, number, f"missing {' and '.join(missing)} before 'map'")
            return values, given_on, number
        key, _, value = text.partition(" ")
        if key not in keys:
            expected = ", ".join(_SYNTAX[k] for k in keys)
            raise _fail(path, number, f"expected {expected} or 'map', got {excerpt(text)}")
        if key in given_on:
            raise _fail(path, number, f"repeated {key} (first given on line {given_on[key]})")
        given_on[key] = number
        values[key] = _header_value(path, number, key, value)
    raise _fail(path, len(lines), "missing the 'map' line")


Marks = dict[str, list[tuple[int, int, int, int]]]


def _read_rows(
    path: Path | str, rows: list[str], width: int, grid_start: int
) -> tuple[np.ndarray, Marks]:
    """Occupancy (width, height) and the (i, j, line, column) of every S and G in the rows."""
    height = len(rows)
    occupancy = np.zeros((width, height), dtype=np.bool_)
    marks: Marks = {"S": [], "G": []}
    for row_index, row in enumerate(rows):
        line_number = grid_start + row_index + 1
        if len(row) != width:
            raise _fail(path, line_number, f"expected {width} characters, got {len(row)}")
        j = height - 1 - row_index
        for i, char in enumerate(row):
            if char in WALL_CHARS:
                occupancy[i, j] = True
            elif char in marks:
                marks[char].append((i, j, line_number, i + 1))
            elif char not in FREE_CHARS:
                raise _fail(path, line_number, f"unknown map character {char!r}", i + 1)
    return occupancy, marks


def _check_marks(path: Path | str, marks: Marks, shape: tuple[int, ...], grid_start: int) -> None:
    """Exactly one S and one G, neither on the far edge (last column, top row)."""
    for char, name in (("S", "start"), ("G", "goal")):
        if not marks[char]:
            raise _fail(path, grid_start, f"no {name} '{char}' in the map")
        if len(marks[char]) > 1:
            _, _, line, column = marks[char][1]
            raise _fail(path, line, f"a second {name} '{char}' (expected exactly one)", column)
        i, j, line, column = marks[char][0]
        if on_far_edge((i, j), shape):
            raise _fail(
                path,
                line,
                f"{name} '{char}' in the last column or the top row (zero-width cells on the "
                "arena's far edge; move it one cell inwards)",
                column,
            )


def _check_extras(path: Path | str, lines: dict[str, int], document: MapFile) -> None:
    """Start pose and goal point inside their cells (with a cell size), path cells free."""
    grid = document.grid
    for key in ("start", "goal"):
        if key in lines and document.cell_size is None:
            raise _fail(path, lines[key], f"expected a 'cell' size before {key} can be in metres")
    if document.cell_size is not None:
        arena = document.discretization()
        for key, point, cell in (
            ("start", document.start_pose, grid.start),
            ("goal", document.goal, grid.goal),
        ):
            if point is not None and arena.cell(point[0], point[1]) != cell:
                raise _fail(
                    path,
                    lines[key],
                    f"{key} ({point[0]:g}, {point[1]:g}) m lies in cell "
                    f"{arena.cell(point[0], point[1])}, not in the map's {key} cell {cell}",
                )
    for cell in document.path:
        if not (cell[0] < grid.shape[0] and cell[1] < grid.shape[1]) or grid.occupancy[cell]:
            raise _fail(path, lines["path"], f"path cell {cell} is not a free cell of the map")


def parse_map_file(text: str, path: Path | str = "<string>") -> MapFile:
    """Parse map text of either version; raises :class:`MapFileError` naming line and column of
    the first problem."""
    lines = text.splitlines()
    values, given_on, grid_start = _read_header(path, lines)
    width, height = int(values["width"]), int(values["height"])  # type: ignore[call-overload]
    rows = lines[grid_start : grid_start + height]
    if len(rows) < height:
        raise _fail(path, len(lines), f"expected {height} map rows, got {len(rows)}")
    extra = [k for k, row in enumerate(lines[grid_start + height :]) if row.strip()]
    if extra:
        raise _fail(path, grid_start + height + extra[0] + 1, "unexpected text after the map rows")
    occupancy, marks = _read_rows(path, rows, width, grid_start)
    _check_marks(path, marks, occupancy.shape, grid_start)
    (si, sj, _, _), (gi, gj, g_line, g_col) = marks["S"][0], marks["G"][0]
    grid = GridMap(occupancy=occupancy, start=(si, sj), goal=(gi, gj))
    if not grid.connected():
        raise _fail(path, g_line, "goal unreachable from the start", g_col)
    cell = values.get("cell")
    document = MapFile(
        grid,
        cell_size=None if cell is None else float(cell[0]),  # type: ignore[index]
        start_pose=values.get("start"),  # type: ignore[arg-type]
        goal=values.get("goal"),  # type: ignore[arg-type]
        path=values.get("path", ()),  # type: ignore[arg-type]
    )
    _check_extras(path, given_on, document)
    return document


def parse_map(text: str, path: Path | str = "<string>") -> GridMap:
    """Parse map text; raises :class:`MapFileError` naming line and column of the first problem."""
    return parse_map_file(text, path).grid


def _grid_rows(grid: GridMap) -> list[str]:
    width, height = grid.shape
    rows = []
    for j in range(height - 1, -1, -1):
        chars = []
        for i in range(width):
            if (i, j) == grid.start:
                chars.append("S")
            elif (i, j) == grid.goal:
                chars.append("G")
            else:
                chars.append("#" if grid.occupancy[i, j] else ".")
        rows.append("".join(chars))
    return rows


def format_map(grid: GridMap) -> str:
    """The text of a map in format version 1 (ends with a newline)."""
    return format_map_file(MapFile(grid))


def format_map_file(document: MapFile, comments: tuple[str, ...] = ()) -> str:
    """The text of a map in the lowest format version that holds it (ends with a newline);
    ``comments`` become ``# `` lines after the first."""
    width, height = document.grid.shape
    header = [f"skidnav-map {document.version}", *(f"# {c}" for c in comments)]
    header += [f"width {width}", f"height {height}"]
    if document.cell_size is not None:
        header.append(f"cell {document.cell_size!r}")
    if document.start_pose is not None:
        header.append("start " + " ".join(repr(float(v)) for v in document.start_pose))
    if document.goal is not None:
        header.append("goal " + " ".join(repr(float(v)) for v in document.goal))
    if document.path:
        header.append("path " + " ".join(f"{i},{j}" for i, j in document.path))
    return "\n".join([*header, "map", *_grid_rows(document.grid)]) + "\n"


def read_map_text(path: Path | str) -> str:
    """The text of a map file; a missing, undecodable or too long (more than
    :data:`MAX_MAP_BYTES`) file raises :class:`MapFileError`."""
    try:
        return read_limited(path, MAX_MAP_BYTES, "map file", MapFileError).decode("utf-8")
    except UnicodeDecodeError as error:
        raise MapFileError(f"{path}: cannot read map file ({error.__class__.__name__})") from None


def load_map(path: Path | str) -> GridMap:
    """Read a map file; a missing, undecodable, too long (more than :data:`MAX_MAP_BYTES`) or
    malformed file raises :class:`MapFileError`."""
    return parse_map(read_map_text(path), path)


def load_map_file(path: Path | str) -> MapFile:
    """Read a map file with its version-2 facts (:class:`MapFile`); errors as :func:`load_map`."""
    return parse_map_file(read_map_text(path), path)


def save_map(grid: GridMap | MapFile, path: Path | str) -> None:
    """Write a map file atomically, in the lowest format version that holds it."""
    document = grid if isinstance(grid, MapFile) else MapFile(grid)
    write_atomic(Path(path), format_map_file(document).encode("utf-8"))
