"""Map generation and the plain-text map format, including every error."""

import numpy as np
import pytest

from skidnav.errors import UserError
from skidnav.world.grid import GridMap, generate_map
from skidnav.world.mapfile import (
    MAX_MAP_BYTES,
    MapFileError,
    format_map,
    load_map,
    parse_map,
    save_map,
)

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
        (_broken("skidnav-map 1", "skidnav-map 3"), "f.txt:1: expected first line"),
        (_broken("width 6", "width six"), "f.txt:3: expected an integer width"),
        (_broken("width 6", "width \uff16"), "f.txt:3: expected ASCII numbers after width"),
        (_broken("width 6", "width 0_6"), "f.txt:3: expected an integer width, got '0_6'"),
        (_broken("width 6", "width +6"), "f.txt:3: expected an integer width, got '+6'"),
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


def test_errors_quote_at_most_a_short_escaped_excerpt_of_the_file(tmp_path):
    secret = "TOKEN=" + "s" * 200
    path = tmp_path / "environ"
    path.write_bytes(f"PATH=/usr/bin\0HOME=/root\0{secret}\0".encode())
    with pytest.raises(MapFileError) as caught:
        load_map(path)
    message = str(caught.value)
    assert message == (
        f"{path}:1: expected first line 'skidnav-map 1', got "
        "'PATH=/usr/bin\\x00HOME=/root\\x00TOKEN=sssssssss'…"  # 40 characters
    )
    with pytest.raises(MapFileError, match=r"got 'wide\\tgarbage'$"):
        parse_map("skidnav-map 1\nwide\tgarbage\nmap\n", "f.txt")


def test_map_files_longer_than_the_limit_are_refused_without_reading_them_whole(tmp_path):
    path = tmp_path / "huge.txt"
    path.write_text(SMALL + "# " + "x" * MAX_MAP_BYTES)
    with pytest.raises(MapFileError, match=f"map file larger than {MAX_MAP_BYTES:,} bytes"):
        load_map(path)
    with pytest.raises(MapFileError, match=r"map file \(a character device, not a regular file\)"):
        load_map("/dev/zero")


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"max_tries": 10**12}, r"max_tries to be an integer in \[1, 10,000\], got 1000000000000"),
        ({"max_tries": 0}, "max_tries to be an integer"),
        ({"max_tries": 2.5}, "max_tries to be an integer"),
        ({"max_tries": True}, "max_tries to be an integer"),
        ({"shape": (10**6, 25)}, r"each side of shape to be an integer in \[3, 1,000\]"),
        ({"shape": (25,)}, "expected shape to be two integers"),
        ({"min_distance": 0}, "min_distance to be an integer"),
        ({"min_distance": 10**9}, "min_distance to be an integer in"),
    ],
)
def test_generation_options_are_bounded(options, message):
    with pytest.raises(ValueError, match=message):
        generate_map("obstacles", np.random.default_rng(0), **options)


def test_a_config_map_option_out_of_range_is_one_line(tmp_path, capsys):
    from skidnav.cli import main

    config = tmp_path / "c.toml"
    config.write_text(
        '[experiment]\nname = "x"\nepisodes = 2\n[[maps]]\nkind = "free"\n'
        "options = { max_tries = 1000000000000000 }\n"
        '[[agents]]\nname = "q-learning"\n'
    )
    assert main(["run", str(config), "--out", str(tmp_path / "out")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "max_tries to be an integer in [1, 10,000]" in lines[0]
    assert not (tmp_path / "out").exists()
