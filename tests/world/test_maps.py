"""Map generation and the plain-text map format, including every error."""

import numpy as np
import pytest

from skidnav.errors import UserError
from skidnav.world.grid import GridMap, generate_map
from skidnav.world.mapfile import MapFileError, format_map, load_map, parse_map, save_map

SMALL = """skidnav-map 1
# a small test arena
width 6
height 5
map
######
#S...#
#.##.#
#...G#
######
"""


@pytest.mark.parametrize("kind", ["free", "obstacles", "maze"])
def test_generated_maps_are_connected_bordered_and_seeded(kind):
    for seed in range(5):
        grid = generate_map(kind, np.random.default_rng(seed))
        assert grid.connected()
        assert grid.occupancy[0, :].all() and grid.occupancy[-1, :].all()
        assert grid.occupancy[:, 0].all() and grid.occupancy[:, -1].all()
        again = generate_map(kind, np.random.default_rng(seed))
        assert np.array_equal(grid.occupancy, again.occupancy)
        assert (grid.start, grid.goal) == (again.start, again.goal)
        assert grid.shortest_cell_distance() >= 12


def test_obstacle_maps_have_interior_walls():
    grid = generate_map("obstacles", np.random.default_rng(3))
    assert grid.occupancy[1:-1, 1:-1].sum() >= 3 * 4


def test_text_format_orientation_and_round_trip(tmp_path):
    grid = parse_map(SMALL)
    assert grid.shape == (6, 5)
    assert grid.start == (1, 3) and grid.goal == (4, 1)  # first row is the top (j = height − 1)
    assert grid.occupancy[2, 2] and grid.occupancy[3, 2] and not grid.occupancy[1, 2]
    path = tmp_path / "small.txt"
    save_map(grid, path)
    loaded = load_map(path)
    assert np.array_equal(loaded.occupancy, grid.occupancy)
    assert (loaded.start, loaded.goal) == (grid.start, grid.goal)
    generated = generate_map("maze", np.random.default_rng(1))
    assert format_map(parse_map(format_map(generated))) == format_map(generated)


def _broken(old: str, new: str) -> str:
    assert old in SMALL
    return SMALL.replace(old, new, 1)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        (_broken("skidnav-map 1", "skidnav-map 2"), "f.txt:1: expected first line"),
        (_broken("width 6", "width six"), "f.txt:3: expected an integer width"),
        (_broken("width 6", "width 2"), "f.txt:3: expected width between 3 and 1000"),
        (_broken("width 6\n", ""), "missing width before 'map'"),
        (_broken("height 5", "depth 5"), "f.txt:4: expected 'width N'"),
        (_broken("#S...#", "#S..#"), "f.txt:7: expected 6 characters, got 5"),
        (_broken("#.##.#", "#.#x.#"), "f.txt:8:4: unknown map character 'x'"),
        (_broken("#.##.#", "#.##S#"), "f.txt:8:5: a second start 'S'"),
        (_broken("#S...#", "#....#"), "no start 'S'"),
        (_broken("#...G#", "#....#"), "no goal 'G'"),
        (_broken("#...G#\n######\n", "#...G#\n"), "expected 5 map rows, got 4"),
        (SMALL + "extra\n", "f.txt:11: unexpected text after the map rows"),
        (_broken("#.##.#", "######"), "f.txt:9:5: goal unreachable from the start"),
        (_broken("map\n", ""), "f.txt:5: expected 'width N', 'height N' or 'map', got '######'"),
        (
            _broken("height 5", "height 5\nwidth 7"),
            "f.txt:5: repeated width (first given on line 3)",
        ),
        (_broken("height 5", "height 5\n# note\nheight 6"), "f.txt:6: repeated height"),
        (_broken("#...G#", "#....G"), "f.txt:9:6: goal 'G' in the last column or the top row"),
        (
            _broken("######\n#S...#", "#S####\n#....#"),
            "f.txt:6:2: start 'S' in the last column or the top row",
        ),
    ],
)
def test_every_map_error_is_one_line_naming_file_line_and_column(text, expected):
    with pytest.raises(MapFileError) as caught:
        parse_map(text, "f.txt")
    message = str(caught.value)
    assert expected in message
    assert "\n" not in message
    assert isinstance(caught.value, UserError)


def test_unreadable_files(tmp_path):
    with pytest.raises(MapFileError, match="no such map file"):
        load_map(tmp_path / "missing.txt")
    binary = tmp_path / "binary.txt"
    binary.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(MapFileError, match="cannot read map file"):
        load_map(binary)


def test_grid_map_validation():
    occupancy = np.zeros((5, 5), dtype=bool)
    occupancy[2, 2] = True
    with pytest.raises(ValueError, match="start on a free cell"):
        GridMap(occupancy, start=(2, 2), goal=(0, 0))
    with pytest.raises(ValueError, match="goal inside"):
        GridMap(occupancy, start=(0, 0), goal=(9, 0))
    with pytest.raises(ValueError, match="differ"):
        GridMap(occupancy, start=(0, 0), goal=(0, 0))
    # the last column and the top row are the zero-width cells at x = W and y = H
    with pytest.raises(ValueError, match="start off the last column and the top row"):
        GridMap(occupancy, start=(4, 1), goal=(1, 1))
    with pytest.raises(ValueError, match="goal off the last column and the top row"):
        GridMap(occupancy, start=(1, 1), goal=(1, 4))
    assert GridMap(occupancy, start=(3, 3), goal=(0, 0)).start == (3, 3)
