"""Converting the BARN benchmark's files to skidnav maps (``skidnav world barn import``).

Inputs, as the repository ``Daffan/the-barn-challenge`` lays them out in
``jackal_helper/worlds/BARN/``: ``world_N.world``, a Gazebo SDF world whose models are a ground
plane and static cylinders (each model's ``<pose>`` places it, its collision geometry gives the
radius), and ``path_files/path_N.npy``, a NumPy int array (k, 2) of the reference path's grid
points (a, b) on the 30 × 30 obstacle field.

Each cylinder becomes wall: every cell whose square the cylinder's disc overlaps by more than a
touch (:data:`TOUCH` m), which for BARN's cylinders (radius 0.075 m at the centres of 0.15 m
cells) is exactly the one cell under each. The start and goal of the rules become the map's S and
G cells and its metric start pose and goal point, the arena's zero-width far edges (x = 4.5 m,
y = 15 m) walls (:mod:`skidnav.world.barn`); the reference path
becomes the map's ``path`` cells. The ``.npy`` files are read without pickle. Every problem is
one line naming the file.
"""

from __future__ import annotations

import io
import math
import xml.etree.ElementTree as ElementTree
import zipfile
from pathlib import Path

import numpy as np

from skidnav.errors import UserError, excerpt
from skidnav.files.atomic import write_atomic
from skidnav.files.user import read_limited
from skidnav.world import barn
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap
from skidnav.world.mapfile import MapFile, format_map_file

MAX_WORLD_BYTES = 16 * 2**20
"""Longest ``.world`` file read [bytes] (BARN's are under 1 MB)."""
MAX_PATH_BYTES = 2**20
"""Longest ``.npy`` file read [bytes]."""
TOUCH = 1e-9
"""Overlap [m] below which a disc only touches a cell (a cylinder tangent to a cell's side)."""


class BarnImportError(UserError):
    """A BARN file that cannot be converted; the message names the file and the problem."""


def arena() -> Discretization:
    """The discretization of every converted world (:data:`skidnav.world.barn.SHAPE`)."""
    n_x, n_y = barn.SHAPE
    return Discretization(
        n_x=n_x, n_y=n_y, arena_width=barn.CELL * (n_x - 1), arena_height=barn.CELL * (n_y - 1)
    )


def _numbers(path: Path, text: str | None, count: int, what: str) -> list[float]:
    words = (text or "").split()
    try:
        values = [float(word) for word in words]
    except ValueError:
        values = []
    if len(values) < count or not all(math.isfinite(v) for v in values):
        raise BarnImportError(
            f"{path}: expected {count} numbers in {what}, got {excerpt(text or '')}"
        )
    return values


def read_cylinders(path: Path) -> np.ndarray:
    """float64 (n, 3): x [m], y [m] (Gazebo frame) and radius [m] of each cylinder model of a
    ``.world`` file; models without collision geometry and planes are skipped, any other shape
    is an error."""
    data = read_limited(path, MAX_WORLD_BYTES, "world file", BarnImportError)
    try:
        root = ElementTree.fromstring(data)
    except ElementTree.ParseError as error:
        raise BarnImportError(f"{path}: not an SDF world ({error})") from None
    world = root.find("world")
    if root.tag != "sdf" or world is None:
        raise BarnImportError(f"{path}: expected an <sdf> document with a <world>")
    cylinders = []
    for model in world.findall("model"):
        name = excerpt(model.get("name", "?"))
        shapes = model.findall("link/collision/geometry/*")
        if not shapes or all(shape.tag == "plane" for shape in shapes):
            continue
        if len(shapes) != 1 or shapes[0].tag != "cylinder":
            kinds = ", ".join(sorted({shape.tag for shape in shapes}))
            raise BarnImportError(
                f"{path}: model {name} collides as {kinds}, expected one cylinder"
            )
        x, y = _numbers(path, model.findtext("pose"), 6, f"the pose of model {name}")[:2]
        (radius,) = _numbers(path, shapes[0].findtext("radius"), 1, f"the radius of model {name}")[
            :1
        ]
        if not radius > 0:
            raise BarnImportError(f"{path}: model {name} has radius {radius}, expected > 0")
        cylinders.append((x, y, radius))
    if not cylinders:
        raise BarnImportError(f"{path}: no cylinder models")
    return np.array(cylinders, dtype=np.float64)


def read_path(path: Path) -> np.ndarray:
    """int64 (k, 2): a ``path_N.npy`` reference path's grid points (a, b), each in [0, 30),
    read without pickle."""
    data = read_limited(path, MAX_PATH_BYTES, "path file", BarnImportError)
    try:
        points = np.load(io.BytesIO(data), allow_pickle=False)
    except (ValueError, OSError, EOFError) as error:
        raise BarnImportError(f"{path}: not a NumPy array file ({excerpt(str(error))})") from None
    if not isinstance(points, np.ndarray) or points.dtype.kind not in "iu":
        raise BarnImportError(
            f"{path}: expected an integer array, got {getattr(points, 'dtype', type(points))}"
        )
    if points.ndim != 2 or points.shape[1] != 2 or len(points) == 0:
        raise BarnImportError(f"{path}: expected an array of shape (k, 2), got {points.shape}")
    if points.min() < 0 or points.max() >= barn.FIELD_SIZE:
        raise BarnImportError(
            f"{path}: expected grid points in [0, {barn.FIELD_SIZE - 1}], got "
            f"[{points.min()}, {points.max()}]"
        )
    return points.astype(np.int64)


def wall_cells(cylinders: np.ndarray, grid: Discretization) -> np.ndarray:
    """bool (n_x, n_y): cells each cylinder (x, y, radius in the arena frame [m]) overlaps by
    more than :data:`TOUCH`; ValueError for a cylinder not wholly inside the arena."""
    occupancy = np.zeros((grid.n_x, grid.n_y), dtype=np.bool_)
    width, height = grid.cell_width, grid.cell_height
    for x, y, radius in cylinders:
        if not (
            radius <= x <= grid.arena_width - radius and radius <= y <= grid.arena_height - radius
        ):
            raise ValueError(
                f"a cylinder at ({x:g}, {y:g}) m, radius {radius:g} m, is not inside the arena"
            )
        for i in range(math.floor((x - radius) / width), math.floor((x + radius) / width) + 1):
            for j in range(
                math.floor((y - radius) / height), math.floor((y + radius) / height) + 1
            ):
                near_x = min(max(x, i * width), (i + 1) * width)
                near_y = min(max(y, j * height), (j + 1) * height)
                if math.hypot(x - near_x, y - near_y) < radius - TOUCH:
                    occupancy[min(i, grid.n_x - 1), min(j, grid.n_y - 1)] = True
    return occupancy


def convert_world(world_file: Path, path_file: Path) -> MapFile:
    """The map of one BARN world: cylinders as walls, the rules' start and goal, the reference
    path's cells; BarnImportError naming the file for any problem."""
    grid = arena()
    cylinders = read_cylinders(world_file)
    cylinders[:, :2] -= np.array(barn.ARENA_ORIGIN)
    points = read_path(path_file)
    try:
        occupancy = wall_cells(cylinders, grid)
    except ValueError as error:
        raise BarnImportError(f"{world_file}: {error}") from None
    # the zero-width far edges x = W, y = H are the arena's boundary: walls, as in every map,
    # so that no path of cells runs along them around the obstacle field
    occupancy[-1, :] = occupancy[:, -1] = True
    start, goal = barn.start_pose(), barn.goal_point()
    try:
        grid_map = GridMap(occupancy, start=grid.cell(*start[:2]), goal=grid.cell(*goal))
    except ValueError as error:
        raise BarnImportError(f"{world_file}: {error}") from None
    if not grid_map.connected():
        raise BarnImportError(f"{world_file}: the goal cell is unreachable from the start cell")
    cells = tuple(barn.field_cell(int(a), int(b)) for a, b in points)
    blocked = [cell for cell in cells if occupancy[cell]]
    if blocked:
        raise BarnImportError(f"{path_file}: reference path point {blocked[0]} is on a cylinder")
    return MapFile(
        grid_map,
        cell_size=barn.CELL,
        start_pose=start,
        goal=(*goal, barn.GOAL_RADIUS),
        path=cells,
    )


def world_files(source: Path, index: int) -> tuple[Path, Path]:
    """(``world_N.world``, ``path_files/path_N.npy``) of world ``index`` in ``source`` (the
    ``BARN`` directory, or a checkout of the repository)."""
    nested = source / "jackal_helper" / "worlds" / "BARN"
    base = nested if nested.is_dir() else source
    return base / f"world_{index}.world", base / "path_files" / f"path_{index}.npy"


def map_text(index: int, document: MapFile) -> str:
    """The map file text of converted world ``index``, with a comment naming its source."""
    comments = (
        f"BARN world {index} (Perille, Truong, Xiao & Stone 2020), converted from",
        "github.com/Daffan/the-barn-challenge (MIT licence); arena frame = Gazebo + (4.5, 0) m",
    )
    return format_map_file(document, comments)


def import_worlds(source: Path, out: Path, indices: range | list[int]) -> int:
    """Convert worlds ``indices`` of ``source`` (:func:`world_files`) and write them to ``out``:
    a ``.zip`` archive of ``world_N.txt`` files (stored with a fixed date, so the same worlds
    give the same bytes), or else a directory (created if needed) of them. Returns the number
    of worlds written; BarnImportError for the first problem, before anything is written."""
    texts = {
        barn.world_name(index): map_text(index, convert_world(*world_files(source, index)))
        for index in indices
    }
    if out.suffix == ".zip":
        buffer = io.BytesIO()
        with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED, compresslevel=9) as archive:
            for name, text in texts.items():
                info = zipfile.ZipInfo(name, date_time=(2020, 1, 1, 0, 0, 0))
                info.compress_type = zipfile.ZIP_DEFLATED
                archive.writestr(info, text.encode("utf-8"))
        write_atomic(out, buffer.getvalue())
    else:
        out.mkdir(parents=True, exist_ok=True)
        for name, text in texts.items():
            write_atomic(out / name, text.encode("utf-8"))
    return len(texts)
