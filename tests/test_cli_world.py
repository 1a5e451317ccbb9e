"""``skidnav world map`` and ``skidnav world simulate`` from the command line."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from skidnav.cli import main
from skidnav.world.grid import generate_map
from skidnav.world.mapfile import format_map

SRC = str(Path(__file__).parents[1] / "src")


def run_cli(*args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=SRC)
    return subprocess.run(
        [sys.executable, "-m", "skidnav.cli", *args], env=env, capture_output=True, text=True
    )


def test_map_generate_then_show_as_text_and_png(tmp_path, capsys):
    path = tmp_path / "maze.txt"
    assert (
        main(["world", "map", "generate", "--kind", "maze", "--seed", "2", "--out", str(path)]) == 0
    )
    assert main(["world", "map", "show", str(path)]) == 0
    shown = capsys.readouterr().out
    assert "skidnav-map 1" in shown and shown.count("S") >= 1
    png = tmp_path / "maze.png"
    assert main(["world", "map", "show", str(path), "--png", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    _assert_start_green_goal_red_with_a_legend(png)


def _assert_start_green_goal_red_with_a_legend(png) -> None:
    """The picture's start cell is green and its goal cell red (skidnav.world.colours), and the
    strip below the arena shows both colours beside their names."""
    from PIL import Image

    from skidnav.world.colours import GOAL, START
    from skidnav.world.rendering import LEGEND_HEIGHT

    pixels = np.asarray(Image.open(png).convert("RGB"))
    arena, legend = pixels[:-LEGEND_HEIGHT], pixels[-LEGEND_HEIGHT:]
    for colour in (START, GOAL):
        assert (arena == colour).all(axis=2).sum() > 50  # a whole cell
        assert (legend == colour).all(axis=2).sum() > 50  # its swatch


def test_simulate_writes_a_picture_and_csv(tmp_path, capsys):
    png, table = tmp_path / "t.png", tmp_path / "t.csv"
    code = main(
        [
            "world",
            "simulate",
            "--map-kind",
            "free",
            "--actions",
            "f f l f r b",
            "--out",
            str(png),
            "--csv",
            str(table),
        ]
    )
    assert code == 0
    assert "6 actions" in capsys.readouterr().out
    assert png.read_bytes()[:4] == b"\x89PNG"
    _assert_start_green_goal_red_with_a_legend(png)
    lines = table.read_text().splitlines()
    assert lines[0] == "step,action,x,y,heading,reward,collision" and len(lines) == 8
    assert b"\r" not in table.read_bytes()  # plain "\n" line endings on every platform


ONE_STEP = ["world", "simulate", "--map-kind", "free", "--actions", "f"]
EDGE_MAP = "skidnav-map 1\nwidth 6\nheight 5\nmap\n######\n#....S\n#....#\n#G...#\n######\n"
"""A hand-written map with the start in the last column (i = 5: the arena's edge x = W)."""


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["world", "simulate", "--actions", "f f jump"], "unknown action 'jump'"),
        (["world", "map", "show", "missing.txt"], "missing.txt: no such map file"),
        (["world", "map", "generate", "--size", "3", "3"], "at least 5"),
        (["world", "simulate", "--random", "0"], "--random >= 1"),
        (
            ["world", "simulate", "--drift", "-1", "--random", "1"],
            "expected drift_amplitude to be a",
        ),
        (
            ["world", "simulate", "--drift", "inf", "--random", "1"],
            "drift_amplitude to be a finite",
        ),
        (
            ["world", "simulate", "--world-seed", "-5", "--random", "1"],
            "expected --world-seed >= 0",
        ),
        (["world", "simulate", "--seed", "-5", "--random", "1"], "expected --seed >= 0"),
        ([*ONE_STEP, "--out", "/nonexistent/x.png"], "/nonexistent/x.png: cannot write"),
        ([*ONE_STEP, "--out", "{tmp}/x.unknown"], "x.unknown: unknown picture format"),
        (
            [*ONE_STEP, "--out", "{tmp}/t.png", "--csv", "/nonexistent/x.csv"],
            "/nonexistent/x.csv: cannot write there (no directory /nonexistent); choose another",
        ),
        (
            ["world", "simulate", "--map", "{edge}", "--actions", "f"],
            "m.txt:6:6: start 'S' in the last",
        ),
        (
            ["world", "map", "generate", "--out", "/nonexistent/x.txt"],
            "/nonexistent/x.txt: cannot write",
        ),
        (
            ["world", "map", "show", "{map}", "--png", "/nonexistent/x.png"],
            "/nonexistent/x.png: cannot",
        ),
        (["world", "map", "generate", "--size", "1001", "5"], "at most 1000 × 1000 cells"),
    ],
)
def test_user_errors_are_one_line_and_exit_2(args, message, tmp_path):
    map_file, edge_file = tmp_path / "g.txt", tmp_path / "m.txt"
    map_file.write_text(format_map(generate_map("free", np.random.default_rng(0))))
    edge_file.write_text(EDGE_MAP)
    args = [arg.format(tmp=tmp_path, map=map_file, edge=edge_file) for arg in args]
    result = run_cli(*args)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and "Traceback" not in result.stderr


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["world", "simulate", "--actions-file", "/dev/zero"],
            "action file (a character device, not a",
        ),
        (
            ["world", "simulate", "--actions-file", "{huge}"],
            "action file larger than 2,097,152 bytes",
        ),
        (["world", "simulate", "--actions-file", "{tmp}/none"], "none: no such action file"),
        (
            ["world", "simulate", "--actions-file", "{long}"],
            "100,001 actions, expected at most 100,000",
        ),
        (["world", "simulate", "--actions", "f " + "x" * 10**5], "unknown action 'xxxxxxxxx"),
        (["world", "simulate", "--random", "100001"], "expected --random >= 1 and <= 100,000"),
        (
            ["world", "map", "show", "/dev/zero"],
            "/dev/zero: cannot read map file (a character device",
        ),
        (
            ["world", "simulate", "--map", "/dev/zero", "--actions", "f"],
            "map file (a character device",
        ),
        (["world", "map", "show", "{huge}"], "huge.txt: map file larger than 4,194,304 bytes"),
    ],
)
def test_arguments_naming_endless_or_huge_inputs_are_one_line(args, message, tmp_path, capsys):
    long_script, huge = tmp_path / "long.txt", tmp_path / "huge.txt"
    long_script.write_text("f " * 100_001)
    huge.write_bytes(b" " * (4 * 2**20 + 1))
    assert main([arg.format(tmp=tmp_path, long=long_script, huge=huge) for arg in args]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and len(lines[0]) < 200, lines


def test_a_map_file_naming_the_environment_does_not_print_it():
    # The variable comes first in the child's environment and its name is 41 characters long:
    # the 40 quoted characters show part of the name, never a value.
    env = {"SKIDNAV_TEST_VARIABLE_WITH_A_LONG_NAME_XY": "never-printed"}
    result = subprocess.run(
        [sys.executable, "-m", "skidnav.cli", "world", "map", "show", "/proc/self/environ"],
        env={**env, **os.environ, "PYTHONPATH": SRC},
        capture_output=True,
        text=True,
    )
    assert result.returncode == 2
    assert result.stderr == (
        "skidnav: error: /proc/self/environ:1: expected first line 'skidnav-map 1', got "
        "'SKIDNAV_TEST_VARIABLE_WITH_A_LONG_NAME_X'…\n"
    )


def test_a_script_runs_to_its_end_past_the_episode_limit(tmp_path, capsys):
    script = tmp_path / "script.txt"
    script.write_text("l r " * 300)  # 600 turns in place: never the goal, past the 500 limit
    table = tmp_path / "t.csv"
    args = ["world", "simulate", "--map-kind", "free", "--actions-file", str(script)]
    assert main([*args, "--out", str(tmp_path / "t.png"), "--csv", str(table)]) == 0
    assert capsys.readouterr().out.startswith("600 actions,")
    assert len(table.read_text().splitlines()) == 1 + 601
    assert sorted(p.name for p in tmp_path.iterdir()) == ["script.txt", "t.csv", "t.png"]


def test_a_script_that_reaches_the_goal_says_what_it_did_not_run(tmp_path, capsys):
    room = tmp_path / "room.txt"
    room.write_text("skidnav-map 1\nwidth 8\nheight 5\nmap\n" + "########\n" * 2
                    + "#S.G...#\n" + "########\n" * 2)  # fmt: skip
    code = main(
        [
            "world",
            "simulate",
            "--map",
            str(room),
            "--actions",
            "f " * 20,
            "--out",
            str(tmp_path / "r.png"),
        ]
    )
    out = capsys.readouterr().out
    assert code == 0 and "reached the goal (the episode ended there: " in out
    ran = int(out.split(" actions,")[0])
    assert f"{20 - ran} actions of the script not run" in out and ran < 20
