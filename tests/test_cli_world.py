"""``skidnav map`` and ``skidnav simulate`` from the command line."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from skidnav.cli import main

SRC = str(Path(__file__).parents[1] / "src")


def run_cli(*args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=SRC)
    return subprocess.run(
        [sys.executable, "-m", "skidnav.cli", *args], env=env, capture_output=True, text=True
    )


def test_map_generate_then_show_as_text_and_png(tmp_path, capsys):
    path = tmp_path / "maze.txt"
    assert main(["map", "generate", "--kind", "maze", "--seed", "2", "--out", str(path)]) == 0
    assert main(["map", "show", str(path)]) == 0
    shown = capsys.readouterr().out
    assert "skidnav-map 1" in shown and shown.count("S") >= 1
    png = tmp_path / "maze.png"
    assert main(["map", "show", str(path), "--png", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_simulate_writes_a_picture_and_csv(tmp_path, capsys):
    png, table = tmp_path / "t.png", tmp_path / "t.csv"
    code = main(
        [
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
    lines = table.read_text().splitlines()
    assert lines[0] == "step,action,x,y,heading,reward,collision" and len(lines) == 8


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["simulate", "--actions", "f f jump"], "unknown action 'jump'"),
        (["map", "show", "missing.txt"], "missing.txt: no such map file"),
        (["map", "generate", "--size", "3", "3"], "at least 5"),
        (["simulate", "--random", "0"], "--random >= 1"),
    ],
)
def test_user_errors_are_one_line_and_exit_2(args, message):
    result = run_cli(*args)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and "Traceback" not in result.stderr
