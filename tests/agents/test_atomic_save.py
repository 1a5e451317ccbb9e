"""Saved agents and kinematic models, and the pictures and tables of ``map show --png`` and
``reproduce``, are written all-or-nothing (a full disk leaves the previous files); restored
geometries are checked before they allocate; messages about a saved agent quote at most 40
characters of it, through the command line too."""

from __future__ import annotations

import csv
import json
import re
import tracemalloc
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from skidnav.agents.tabular.registry import load_agent, make_agent
from skidnav.cli import main
from skidnav.errors import CorruptFileError
from skidnav.models.kinematic import KinematicModel
from skidnav.models.kinematic_config import KinematicModelConfig
from skidnav.models.kinematic_files import load_model, save_model
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization
from tests.saved_file_support import (
    arrays_of,
    listing,
    run_with_full_disk,
    skidnav_with_full_disk,
    write_checkpoint,
    write_npz,
)

REALTIME = Path(__file__).resolve().parents[2] / "configs" / "realtime.toml"
SMALL_GRID = Discretization(n_x=6, n_y=5, n_headings=4, regions_x=2, regions_y=2)

SAVE_ON_FULL_DISK = """
import sys
import numpy as np

rng = np.random.default_rng(1)
if sys.argv[1] == "agent":
    from skidnav.agents.tabular.registry import make_agent

    saved = make_agent("dyna-q", 5400, 4, {}, rng)
    saved.q[:] = rng.random(saved.q.shape)  # incompressible: far past the limit
    save = saved.save
else:
    from skidnav.models.kinematic import KinematicModel
    from skidnav.models.kinematic_config import KinematicModelConfig
    from skidnav.robot.params import RobotParams
    from skidnav.world.discretization import Discretization

    saved = KinematicModel(RobotParams(), Discretization(), KinematicModelConfig(window=400))
    saved.data[:] = rng.random(saved.data.shape)
    from skidnav.models.kinematic_files import save_model

    def save(path):
        return save_model(saved, path)
try:
    save(sys.argv[2])
except OSError as error:
    print(error.strerror)
    sys.exit(3)
"""


def _old_agent(path: Path) -> None:
    agent = make_agent("dyna-q", 54, 4, {}, np.random.default_rng(0))
    agent.q[:] = 1.0
    agent.save(path)


def _old_model(path: Path) -> None:
    save_model(
        KinematicModel(RobotParams(), Discretization(), KinematicModelConfig(window=16)), path
    )


@pytest.mark.parametrize("kind", ["agent", "model"])
def test_a_save_on_a_full_disk_leaves_the_previous_files(kind: str, tmp_path: Path) -> None:
    path = tmp_path / "saved"
    (_old_agent if kind == "agent" else _old_model)(path)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    assert sorted(before) == ["saved.json", "saved.npz"]
    limit = 2 * max(len(data) for data in before.values())
    result = run_with_full_disk(["-c", SAVE_ON_FULL_DISK, kind, str(path)], max_file_bytes=limit)
    assert result.returncode == 3 and result.stdout.strip() == "File too large", result.stderr
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before  # no torn file, no tmp
    if kind == "agent":
        assert np.all(load_agent(path).q == 1.0)
    else:
        assert load_model(path).config.window == 16


def _kinematic_agent(window: int = 16) -> Any:
    return make_agent(
        "dyna-kinematic", SMALL_GRID.n_states, 4, {"kinematic_window": window},
        np.random.default_rng(0), discretization=SMALL_GRID,
    )  # fmt: skip


def _huge_regions(meta: dict[str, Any], arrays: dict[str, np.ndarray]) -> None:
    meta["geometry"]["discretization"].update(regions_x=10**6, regions_y=10**6)


def _no_geometry(meta: dict[str, Any], arrays: dict[str, np.ndarray]) -> None:
    meta["geometry"]["discretization"] = None


def _other_window(meta: dict[str, Any], arrays: dict[str, np.ndarray]) -> None:
    arrays["kinematic_data"] = np.zeros((4, 32, 5))


def _text_field(meta: dict[str, Any], arrays: dict[str, np.ndarray]) -> None:
    meta["geometry"]["robot"]["substeps"] = "ten" * 1000


def _fractional_cells(meta: dict[str, Any], arrays: dict[str, np.ndarray]) -> None:
    meta["geometry"]["discretization"]["n_x"] = 6.5


def _extra_field(meta: dict[str, Any], arrays: dict[str, np.ndarray]) -> None:
    meta["geometry"]["robot"]["mass"] = 1.0


Change = Callable[[dict[str, Any], dict[str, np.ndarray]], None]
GEOMETRY_CASES: dict[str, tuple[Change, str]] = {
    "huge regions": (_huge_regions, "1000000 × 1000000 slip regions for 6 × 5 cells"),
    "no geometry, kinematic data": (_no_geometry, "unexpected array 'kinematic_"),
    "other window": (_other_window, "kinematic_data"),
    "text field": (_text_field, "expected robot.substeps like 10, got "),
    "fractional cells": (_fractional_cells, "expected discretization.n_x like 25, got 6.5"),
    "extra field": (_extra_field, "expected the robot fields"),
}


@pytest.mark.parametrize("case", GEOMETRY_CASES)
def test_a_saved_geometry_is_checked_before_it_allocates(case: str, tmp_path: Path) -> None:
    npz_path, json_path = _kinematic_agent().save(tmp_path / "k")
    meta, arrays = json.loads(json_path.read_text()), arrays_of(npz_path)
    change, message = GEOMETRY_CASES[case]
    change(meta, arrays)
    json_path.write_text(json.dumps(meta))
    write_npz(npz_path, arrays)
    tracemalloc.start()
    try:
        with pytest.raises(CorruptFileError, match=re.escape(message)) as caught:
            load_agent(npz_path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 2**22 and "\n" not in str(caught.value)  # refused before any table is built
    assert len(str(caught.value)) < 400


def test_a_saved_geometry_that_fits_is_restored(tmp_path: Path) -> None:
    agent = _kinematic_agent()
    agent.kinematic.data[:] = 0.25
    agent.save(tmp_path / "k")
    restored = load_agent(tmp_path / "k")
    assert restored.discretization == SMALL_GRID and np.all(restored.kinematic.data == 0.25)


LONG = "v" * 10_000


def _config(key: str, value: Any) -> Callable[[dict[str, Any]], None]:
    def change(meta: dict[str, Any]) -> None:
        meta["config"] = {**meta["config"], key: value}

    return change


def _rng(state: dict[str, Any]) -> Callable[[dict[str, Any]], None]:
    def change(meta: dict[str, Any]) -> None:
        meta["rng"] = state

    return change


def _counter(meta: dict[str, Any]) -> None:
    meta["counters"] = {**meta["counters"], "episodes": LONG}


QUOTING_CASES: dict[str, tuple[Callable[[dict[str, Any]], None], str]] = {
    "long planning mode": (_config("planning_mode", LONG), "expected planning_mode in"),
    "long alpha": (_config("alpha", LONG), "'<' not supported"),
    "long unknown option": (_config(LONG, 1), "unknown key"),
    "long bit generator": (_rng({"bit_generator": LONG}), "unknown bit generator"),
    "text in the generator state": (
        _rng({"bit_generator": "SFC64", "state": {"state": [LONG] * 4, "counter": 0}}),
        "unusable SFC64 state (ValueError)",
    ),
    "long counter": (_counter, "counter episodes to be an integer in [0, "),
}


@pytest.fixture(scope="module")
def saved_dyna_q(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Any], Any]:
    agent = make_agent("dyna-q", 54, 4, {"planning_steps": 3}, np.random.default_rng(0))
    npz_path, json_path = agent.save(tmp_path_factory.mktemp("agent") / "agent")
    return json.loads(json_path.read_text()), arrays_of(npz_path)


@pytest.mark.parametrize("case", QUOTING_CASES)
def test_messages_about_a_saved_agent_quote_at_most_40_characters(
    case: str,
    saved_dyna_q: tuple[dict[str, Any], Any],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    change, message = QUOTING_CASES[case]
    meta = json.loads(json.dumps(saved_dyna_q[0]))
    change(meta)
    out = tmp_path / "run"
    directory = write_checkpoint(out, agent=(json.dumps(meta), saved_dyna_q[1]))
    before = listing(out)
    args = ["robot", "run", "--quiet", "--driver", "sim", "--agent", "dyna-q", "--resume"]
    code = main([*args, "--config", str(REALTIME), "--out", str(out)])
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(lines) == 1, lines
    assert lines[0].startswith(f"skidnav: error: {directory / 'agent.'}"), lines
    assert message in lines[0], lines
    assert "v" * 41 not in lines[0]  # at most an excerpt of the long value
    assert listing(out) == before


def _error_line(stderr: str) -> str:
    """The one line of ``stderr``: a ``skidnav: error:`` line, no traceback."""
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("skidnav: error: "), stderr[-2000:]
    return lines[0]


def test_a_picture_on_a_full_disk_leaves_the_previous_one(tmp_path: Path) -> None:
    room, picture = tmp_path / "room.txt", tmp_path / "room.png"
    assert main(["world", "map", "generate", "--kind", "maze", "--out", str(room)]) == 0
    assert main(["world", "map", "show", str(room), "--png", str(picture)]) == 0
    size = picture.stat().st_size
    picture.write_bytes(b"the previous picture")
    result = skidnav_with_full_disk(
        ["world", "map", "show", str(room), "--png", str(picture)], size // 2
    )
    assert result.returncode == 2
    assert _error_line(result.stderr) == (
        f"skidnav: error: {picture}: cannot write the picture (File too large)"
    )
    assert picture.read_bytes() == b"the previous picture"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["room.png", "room.txt"]


def test_reproduce_on_a_full_disk_keeps_whole_files(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    args = ["study", "reproduce", "sutton-barto", "--runs", "1", "--backend", "serial"]
    args += ["--no-progress", "--out"]
    assert main([*args, str(tmp_path / "warm")]) == 0  # compiled and cached before the disk fills
    out = tmp_path / "out"
    out.mkdir()
    plot = out / "dyna_maze.png"
    plot.write_bytes(b"the previous plot")
    # the results (run files, tables, metadata: < 12 kB each) and the first CSV fit, the plot not
    result = skidnav_with_full_disk([*args, str(out)], max_file_bytes=20_000)
    assert result.returncode == 2
    assert _error_line(result.stderr) == (
        f"skidnav: error: {plot}: cannot write the plot (File too large)"
    )
    assert plot.read_bytes() == b"the previous plot"
    assert sorted(p.name for p in out.iterdir()) == [
        ".skidnav.lock", "config.json", "config.toml", "dyna_maze.csv", "dyna_maze.png",
        "episodes.parquet", "metadata.json", "runs", "summaries.csv", "summaries.parquet",
    ]  # fmt: skip
    assert len(list((out / "runs").iterdir())) == 13  # every run whole
    with (out / "dyna_maze.csv").open(newline="") as stream:
        rows = list(csv.reader(stream))
    assert rows[0] == ["planning_steps", "run", "episode", "steps"] and len(rows) == 1 + 3 * 50
    capsys.readouterr()
    assert main([*args, str(out)]) == 0  # with room again, the same command finishes the files
    assert "(0 run now, 13 already done)" in capsys.readouterr().out
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
