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
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from skidnav.errors import UserError, excerpt
from skidnav.files.atomic import write_atomic
from skidnav.files.user import read_limited
from skidnav.world.grid import MAX_SIZE, MIN_SIZE, GridMap, on_far_edge

MAGIC = "skidnav-map 1"
MAX_MAP_BYTES = 4 * 2**20
"""Longest map file read [bytes] (a 1000 × 1000 map takes about 1 MB)."""
WALL_CHARS = "#@"
FREE_CHARS = ".SG"


class MapFileError(UserError):
    """A map file that cannot be read; the message is ``path:line:column: problem``."""


def _fail(path: Path | str, line: int, message: str, column: int | None = None) -> MapFileError:
    where = f"{path}:{line}" + (f":{column}" if column is not None else "")
    return MapFileError(f"{where}: {message}")


def _read_header(path: Path | str, lines: list[str]) -> tuple[int, int, int]:
    """Parse the header; returns (width, height, index of the first grid line)."""
    if not lines or lines[0].strip() != MAGIC:
        first = lines[0].strip() if lines else ""
        raise _fail(path, 1, f"expected first line {MAGIC!r}, got {excerpt(first)}")
    sizes: dict[str, int] = {}
    given_on: dict[str, int] = {}
    for number, raw in enumerate(lines[1:], start=2):
        text = raw.strip()
        if not text or text.startswith("# "):
            continue
        if text == "map":
            missing = [k for k in ("width", "height") if k not in sizes]
            if missing:
                raise _fail(path, number, f"missing {' and '.join(missing)} before 'map'")
            return sizes["width"], sizes["height"], number
        key, _, value = text.partition(" ")
        if key not in ("width", "height"):
            raise _fail(
                path, number, f"expected 'width N', 'height N' or 'map', got {excerpt(text)}"
            )
        if key in given_on:
            raise _fail(path, number, f"repeated {key} (first given on line {given_on[key]})")
        given_on[key] = number
        try:
            sizes[key] = int(value)
        except ValueError:
            raise _fail(
                path, number, f"expected an integer {key}, got {excerpt(value.strip())}"
            ) from None
        if not MIN_SIZE <= sizes[key] <= MAX_SIZE:
            raise _fail(
                path, number, f"expected {key} between {MIN_SIZE} and {MAX_SIZE}, got {sizes[key]}"
            )
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


def parse_map(text: str, path: Path | str = "<string>") -> GridMap:
    """Parse map text; raises :class:`MapFileError` naming line and column of the first problem."""
    lines = text.splitlines()
    width, height, grid_start = _read_header(path, lines)
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
    return grid


def format_map(grid: GridMap) -> str:
    """The text of a map in format version 1 (ends with a newline)."""
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
    return "\n".join([MAGIC, f"width {width}", f"height {height}", "map", *rows]) + "\n"


def load_map(path: Path | str) -> GridMap:
    """Read a map file; a missing, undecodable, too long (more than :data:`MAX_MAP_BYTES`) or
    malformed file raises :class:`MapFileError`."""
    try:
        text = read_limited(path, MAX_MAP_BYTES, "map file", MapFileError).decode("utf-8")
    except UnicodeDecodeError as error:
        raise MapFileError(f"{path}: cannot read map file ({error.__class__.__name__})") from None
    return parse_map(text, path)


def save_map(grid: GridMap, path: Path | str) -> None:
    """Write a map file (format version 1) atomically."""
    write_atomic(Path(path), format_map(grid).encode("utf-8"))
