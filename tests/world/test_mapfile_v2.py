"""Map format version 2: cell size, start pose, goal point and radius, reference path."""

from __future__ import annotations

import pytest

from skidnav.world.mapfile import (
    MapFile,
    MapFileError,
    format_map,
    format_map_file,
    load_map,
    load_map_file,
    parse_map,
    parse_map_file,
    save_map,
)

ROWS = "######\n#...G#\n#.##.#\n#S...#\n######\n"
V2 = (
    "skidnav-map 2\n# a comment\nwidth 6\nheight 5\ncell 0.5\nstart 0.75 0.7 1.5\n"
    "goal 2.1 1.6 0.25\npath 1,1 2,1 3,1 4,1 4,2 4,3\nmap\n" + ROWS
)


def test_a_version_2_file_round_trips_and_reads_as_a_grid_too(tmp_path):
    document = parse_map_file(V2, "f.txt")
    assert document.version == 2 and document.cell_size == 0.5
    assert document.start_pose == (0.75, 0.7, 1.5) and document.goal == (2.1, 1.6, 0.25)
    assert document.path[0] == (1, 1) and document.path[-1] == (4, 3)
    arena = document.discretization()
    assert (arena.arena_width, arena.arena_height) == (2.5, 2.0)
    text = format_map_file(document)
    assert format_map_file(parse_map_file(text)) == text  # GridMap compares by identity
    assert parse_map(V2).start == (1, 1)
    save_map(document, tmp_path / "m.txt")
    assert format_map_file(load_map_file(tmp_path / "m.txt")) == text
    assert load_map(tmp_path / "m.txt").goal == (4, 3)


def test_a_map_without_version_2_facts_is_written_as_version_1():
    grid = parse_map(V2)
    assert format_map_file(MapFile(grid)) == format_map(grid)
    assert format_map(grid).startswith("skidnav-map 1\nwidth 6\n")
    with pytest.raises(ValueError, match="expected a map with a cell size"):
        MapFile(grid).discretization()


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("skidnav-map 2", "skidnav-map 1", "f.txt:5: expected 'width N', 'height N' or 'map'"),
        ("cell 0.5", "cell -1", "f.txt:5: expected a cell size > 0 m, got '-1'"),
        ("cell 0.5", "cell 0.5 1", "f.txt:5: expected 1 number(s) after cell"),
        ("goal 2.1 1.6 0.25", "goal 2.1 1.6 0", "f.txt:7: expected a goal size > 0 m"),
        ("start 0.75 0.7 1.5", "start 0.75 nan 1.5", "f.txt:6: expected finite numbers"),
        ("start 0.75 0.7 1.5", "start 0.75 x 1.5", "f.txt:6: expected numbers after start"),
        ("start 0.75 0.7 1.5", "start 1.75 0.7 1.5", "f.txt:6: start (1.75, 0.7) m lies in cell"),
        ("goal 2.1 1.6 0.25", "goal 2.1 1.6 0.25\ngoal 2 1 1", "f.txt:8: repeated goal"),
        ("cell 0.5\n", "", "f.txt:5: expected a 'cell' size before start can be in metres"),
        ("path 1,1", "path 1;1", "f.txt:8: expected path cells 'I,J', got '1;1'"),
        ("path 1,1", "path 2,2", "f.txt:8: path cell (2, 2) is not a free cell of the map"),
        ("path 1,1", "path 9,1", "f.txt:8: path cell (9, 1) is not a free cell of the map"),
    ],
)
def test_bad_version_2_lines_are_one_line_errors(old, new, message):
    with pytest.raises(MapFileError) as caught:
        parse_map_file(V2.replace(old, new, 1), "f.txt")
    assert message in str(caught.value) and "\n" not in str(caught.value), str(caught.value)
