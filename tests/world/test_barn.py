"""The BARN worlds: conversion from the benchmark's files, the shipped maps, the metric."""

from __future__ import annotations

import itertools
import zipfile
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from skidnav.cli import main
from skidnav.world import barn
from skidnav.world.barn_import import BarnImportError, convert_world, import_worlds, world_files
from skidnav.world.mapfile import parse_map_file

FIXTURES = Path(__file__).parent.parent / "data" / "barn"
"""Worlds 0 and 299 of the benchmark (tests/data/barn/README.md)."""

CYLINDER = (
    "<model name='unit_cylinder_{k}'><static>1</static><pose frame=''>{x} {y} 0 0 0 0</pose>"
    "<link name='link'><collision name='collision'><geometry><cylinder><radius>{r}</radius>"
    "<length>1</length></cylinder></geometry></collision></link></model>"
)


def world_text(cylinders: list[tuple[float, float]], radius: float = 0.075) -> str:
    """A small SDF world with a ground plane and these cylinders (Gazebo frame [m])."""
    models = "".join(CYLINDER.format(k=k, x=x, y=y, r=radius) for k, (x, y) in enumerate(cylinders))
    plane = (
        "<model name='ground_plane'><link name='link'><collision name='c'><geometry><plane>"
        "<normal>0 0 1</normal></plane></geometry></collision></link></model>"
    )
    return f"<sdf version='1.6'><world name='default'>{plane}{models}</world></sdf>"


def tiny_world(tmp_path: Path, cylinders=None, path=None) -> tuple[Path, Path]:
    """world_7 of a made-up BARN directory: three cylinders, a four-point reference path."""
    (tmp_path / "path_files").mkdir(exist_ok=True)
    world, path_file = world_files(tmp_path, 7)
    default = [(-0.075, 0.075), (-4.425, 9.525), (-2.175, 6.975)]
    world.write_text(world_text(default if cylinders is None else cylinders))
    np.save(path_file, np.array([[15, 0], [14, 1], [14, 2], [15, 29]]) if path is None else path)
    return world, path_file


def test_a_tiny_world_converts_to_the_cells_under_its_cylinders(tmp_path):
    document = convert_world(*tiny_world(tmp_path))
    grid = document.grid
    assert grid.shape == (31, 101)
    # Gazebo x + 4.5 m over 0.15 m cells: x = -0.075 -> column 29, -4.425 -> 0, -2.175 -> 15
    walls = grid.occupancy.copy()
    assert walls[-1, :].all() and walls[:, -1].all()  # the far edges x = 4.5 m, y = 15 m
    walls[-1, :] = walls[:, -1] = False
    assert sorted(map(tuple, np.argwhere(walls).tolist())) == [(0, 63), (15, 46), (29, 0)]
    assert grid.start == (15, 20) and grid.goal == (15, 86)
    assert document.start_pose == (2.25, 3.0, 1.57) and document.goal == (2.25, 13.0, 1.0)
    assert document.path == ((15, 34), (14, 35), (14, 36), (15, 63))
    assert document.cell_size == barn.CELL


def test_a_cylinder_off_the_lattice_walls_every_cell_it_overlaps(tmp_path):
    # centre on the corner of four cells: the disc overlaps all four
    document = convert_world(*tiny_world(tmp_path, cylinders=[(-2.25, 7.5)]))
    walls = document.grid.occupancy[:-1, :-1]
    assert sorted(map(tuple, np.argwhere(walls).tolist())) == [
        (14, 49),
        (14, 50),
        (15, 49),
        (15, 50),
    ]


@pytest.mark.parametrize("index", [0, 299])
def test_the_benchmark_files_convert_to_the_shipped_maps(index):
    converted = convert_world(*world_files(FIXTURES, index))
    shipped = barn.load_barn_world(index)
    assert np.array_equal(converted.grid.occupancy, shipped.map.grid.occupancy)
    for field in ("cell_size", "start_pose", "goal", "path"):
        assert getattr(converted, field) == getattr(shipped.map, field), field
    cylinders = FIXTURES.joinpath(f"world_{index}.world").read_text().count("<cylinder>")
    # every cylinder sits alone in its cell, some of them twice (models at the same place)
    assert 0 < converted.grid.occupancy[:-1, :-1].sum() <= cylinders


def test_the_shipped_archive_holds_300_maps_that_parse():
    archive = resources.files("skidnav").joinpath("data", "barn", "worlds.zip")
    with archive.open("rb") as stream, zipfile.ZipFile(stream) as worlds:
        names = set(worlds.namelist())
        assert names == {f"world_{n}.txt" for n in range(300)}
        text = worlds.read("world_150.txt").decode()
    assert text.startswith("skidnav-map 2\n# BARN world 150")
    assert parse_map_file(text).grid.connected()


def run_py_optimal_time(points: np.ndarray) -> float:
    """OT as the benchmark's run.py computes it, written out independently: grid (a, b) to
    Gazebo metres, start and goal added, segment lengths summed in order, over 2 m/s."""
    metres = [(-2.25, 3.0)] + [(a * 0.15 - 4.575, b * 0.15 + 5.075) for a, b in points]
    metres.append((-2.25, 13.0))
    length = 0.0
    for (x0, y0), (x1, y1) in itertools.pairwise(metres):
        length += ((x0 - x1) ** 2 + (y0 - y1) ** 2) ** 0.5
    return length / 2


@pytest.mark.parametrize("index", [0, 299])
def test_the_optimal_time_is_the_benchmarks(index):
    points = np.load(FIXTURES / "path_files" / f"path_{index}.npy", allow_pickle=False)
    world = barn.load_barn_world(index)
    assert world.optimal_time == run_py_optimal_time(points.tolist())
    assert world.reference_path.shape == (len(points) + 2, 2)
    assert world.reference_path[0].tolist() == [2.25, 3.0]
    assert world.reference_path[-1].tolist() == [2.25, 13.0]
    assert world.start_pose == (2.25, 3.0, 1.57) and world.goal == (2.25, 13.0)
    assert world.goal_radius == 1.0 and world.discretization.cell_width == pytest.approx(0.15)


def test_a_straight_reference_path_gives_the_hand_computed_optimal_time():
    # (15, b) is x = 15·0.15 − 4.575 = −2.325 m: 0.075 m left of the start's x = −2.25 m
    cells = tuple(barn.field_cell(15, b) for b in (0, 29))
    path = barn.gazebo_reference_path(cells)
    first = np.hypot(0.075, 5.075 - 3.0)
    middle = 29 * 0.15
    last = np.hypot(0.075, 13.0 - (29 * 0.15 + 5.075))
    assert barn.optimal_time(path) == pytest.approx((first + middle + last) / 2, abs=1e-12)


@pytest.mark.parametrize(
    ("success", "actual", "optimal", "score"),
    [
        (True, 10.0, 4.0, 0.4),  # inside the clip: OT / AT
        (True, 8.0, 4.0, 0.5),  # AT = 2·OT, the lower bound
        (True, 3.0, 4.0, 0.5),  # faster than 2·OT counts as 2·OT
        (True, 32.0, 4.0, 0.125),  # AT = 8·OT, the upper bound
        (True, 99.0, 4.0, 0.125),  # slower than 8·OT counts as 8·OT
        (True, 12.0, 5.0, 5.0 / 12.0),
        (False, 10.0, 4.0, 0.0),  # a collision or a timeout scores 0
        (False, 3.0, 4.0, 0.0),
    ],
)
def test_the_score_is_success_times_ot_over_clipped_at(success, actual, optimal, score):
    assert barn.barn_score(success, actual, optimal) == pytest.approx(score, abs=1e-15)


@pytest.mark.parametrize(("actual", "optimal"), [(1.0, 0.0), (-1.0, 4.0), (float("nan"), 4.0)])
def test_the_score_refuses_impossible_times(actual, optimal):
    with pytest.raises(ValueError, match="expected"):
        barn.barn_score(True, actual, optimal)


def test_an_unknown_world_index_is_refused():
    with pytest.raises(ValueError, match=r"expected a BARN world index in \[0, 299\], got 300"):
        barn.load_barn_world(300)


@pytest.mark.parametrize(
    ("world", "path", "message"),
    [
        ("<sdf><world>", None, "world_7.world: not an SDF world"),
        ("<html/>", None, "world_7.world: expected an <sdf> document with a <world>"),
        (
            "<sdf><world><model name='box'><link><collision><geometry><box/></geometry>"
            "</collision></link></model></world></sdf>",
            None,
            "model 'box' collides as box, expected one cylinder",
        ),
        (
            world_text([(-1.0, 2.0)]).replace("-1.0 2.0 0 0 0 0", "-1.0 two"),
            None,
            "expected 6 numbers in the pose of model 'unit_cylinder_0', got '-1.0 two'",
        ),
        (world_text([]), None, "world_7.world: no cylinder models"),
        (world_text([(-1.0, 2.0)], radius=-1), None, "has radius -1.0, expected > 0"),
        (world_text([(3.0, 2.0)]), None, "a cylinder at (7.5, 2) m, radius 0.075 m, is not inside"),
        (world_text([(-2.25, 3.0)]), None, "expected start on a free cell, got wall at (15, 20)"),
        (
            world_text([(-4.425 + 0.15 * k, 9.525) for k in range(30)]),
            None,
            "the goal cell is unreachable from the start cell",
        ),
        (None, np.array([[1.5, 2.0]]), "path_7.npy: expected an integer array, got float64"),
        (None, np.array([1, 2, 3]), "path_7.npy: expected an array of shape (k, 2), got (3,)"),
        (None, np.array([[0, 30]]), "path_7.npy: expected grid points in [0, 29], got [0, 30]"),
        (None, np.array([[15, 12]]), "path_7.npy: reference path point (15, 46) is on a cylinder"),
        (None, "pickled", "path_7.npy: not a NumPy array file"),
        (None, "text", "path_7.npy: not a NumPy array file"),
    ],
)
def test_malformed_inputs_are_one_line_errors_naming_the_file(tmp_path, world, path, message):
    world_file, path_file = tiny_world(tmp_path)
    if world is not None:
        world_file.write_text(world)
    if isinstance(path, np.ndarray):
        np.save(path_file, path)
    elif path == "pickled":
        np.save(path_file, np.array([{"a": 1}], dtype=object), allow_pickle=True)
    elif path == "text":
        path_file.write_text("not numpy")
    with pytest.raises(BarnImportError) as caught:
        convert_world(world_file, path_file)
    text = str(caught.value)
    assert message in text and "\n" not in text and str(tmp_path) in text, text


def test_a_missing_file_is_one_line(tmp_path):
    with pytest.raises(BarnImportError, match=r"world_3\.world"):
        convert_world(*world_files(tmp_path, 3))


def test_the_command_writes_maps_and_reports_problems_in_one_line(tmp_path, capsys):
    source = tmp_path / "BARN"
    source.mkdir()
    tiny_world(source)
    out = tmp_path / "maps"
    assert main(["world", "barn", "import", str(source), str(out), "--world", "7"]) == 0
    assert parse_map_file((out / "world_7.txt").read_text()).path[0] == (15, 34)
    archive = tmp_path / "maps.zip"
    assert main(["world", "barn", "import", str(source), str(archive), "--world", "7"]) == 0
    first = archive.read_bytes()
    assert import_worlds(source, archive, [7]) == 1 and archive.read_bytes() == first
    capsys.readouterr()
    assert main(["world", "barn", "import", str(source), str(out), "--world", "8"]) == 2
    assert main(["world", "barn", "import", str(source), str(out), "--world", "300"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 2 and "world_8.world" in lines[0] and "got 300" in lines[1], lines
