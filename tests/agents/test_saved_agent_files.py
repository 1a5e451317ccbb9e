"""Hostile saved agents: each refused in one line, through the command line too, before any
array it announces is allocated or decompressed."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from skidnav.agents.tabular.registry import load_agent, make_agent
from skidnav.agents.training import train_agent
from skidnav.cli import main
from skidnav.envs.mazes import dyna_maze
from skidnav.errors import CorruptFileError
from skidnav.files.saved import SavedArchive
from skidnav.models.kinematic import KinematicModel
from skidnav.models.kinematic_config import KinematicModelConfig
from skidnav.models.kinematic_files import load_model, save_model
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization
from tests.saved_file_support import (
    arrays_of,
    forged_header_length,
    forged_npy,
    listing,
    npy_bytes,
    write_checkpoint,
    write_npz,
)

REALTIME = Path(__file__).resolve().parents[2] / "configs" / "realtime.toml"
Files = tuple[dict[str, Any], dict[str, Any]]
"""(JSON metadata, npz members) of a saved agent, changed by a case and written back."""


@pytest.fixture(scope="module")
def saved_dyna_q(tmp_path_factory: pytest.TempPathFactory) -> Files:
    """The two files of a Dyna-Q agent trained for 2 episodes on the Dyna Maze."""
    agent = make_agent("dyna-q", 54, 4, {"planning_steps": 3}, np.random.default_rng(0))
    train_agent(agent, dyna_maze(), 2, seed=0)
    npz_path, json_path = agent.save(tmp_path_factory.mktemp("agent") / "agent")
    return json.loads(json_path.read_text()), arrays_of(npz_path)


def _set(key: str, value: Any) -> Callable[[Files], None]:
    def change(files: Files) -> None:
        files[0][key] = value

    return change


def _member(name: str, value: Any) -> Callable[[Files], None]:
    def change(files: Files) -> None:
        files[1][name] = value

    return change


def _nan_q(files: Files) -> None:
    files[1]["q"] = files[1]["q"].copy()
    files[1]["q"][3, 1] = np.nan


def _without_pair_keys(files: Files) -> None:
    del files[1]["model.pair_key"]


def _counter(name: str, value: Any) -> Callable[[Files], None]:
    def change(files: Files) -> None:
        files[0]["counters"] = {**files[0]["counters"], name: value}

    return change


def _config(name: str, value: Any) -> Callable[[Files], None]:
    def change(files: Files) -> None:
        files[0]["config"] = {**files[0]["config"], name: value}

    return change


NESTED = "[" * 100_000 + "]" * 100_000
"""Deeper than any recursive parser survives."""

CASES: dict[str, tuple[Callable[[Files], None], str, str]] = {
    # name: (change, raw JSON text replacement "old=>new" or "", message)
    "zip bomb in q": (_member("q", "bomb"), "", "bytes stored, its header announces"),
    "unknown member": (_member("payload", np.zeros(3)), "", "unexpected array 'payload'"),
    "unknown bomb member": (_member("payload", "bomb"), "", "unexpected array 'payload'"),
    "huge header shape": (
        _member("q", forged_npy((10**12, 4))),
        "",
        r"is float64 of shape (1000000000000, 4)",
    ),
    "huge header length": (_member("q", forged_header_length(2**31)), "", "header of"),
    "object dtype": (_member("q", forged_npy((54, 4), "|O")), "", "is object of shape"),
    "missing member": (_without_pair_keys, "", "missing model array 'model.pair_key'"),
    "NaN in Q": (_nan_q, "", "Q table holds NaN"),
    "fractional n_states": (_set("n_states", 54.7), "", "n_states to be an integer"),
    "boolean n_actions": (_set("n_actions", True), "", "n_actions to be an integer"),
    "huge n_states": (_set("n_states", 10**12), "", "n_states to be an integer in [1, "),
    "1e400": (_set("n_states", "X"), '"X"=>1e400', "out of range"),
    "NaN constant": (_config("alpha", "X"), '"X"=>NaN', "non-finite number NaN"),
    "nested JSON": (_set("extra", "X"), f'"X"=>{NESTED}', "JSON nested 100001 deep"),
    "planning_steps 1e15": (_config("planning_steps", 10**15), "", "planning_steps in [0, "),
    "huge counter": (_counter("steps", 2**70), "", "counter steps to be an integer"),
    "boolean counter": (_counter("episodes", False), "", "counter episodes to be an integer"),
}


def _write(directory: Path, files: Files, change: Callable[[Files], None], raw: str) -> Path:
    """Write the changed files as ``directory/agent.{json,npz}``; returns the npz path."""
    meta, members = json.loads(json.dumps(files[0])), dict(files[1])
    change((meta, members))
    text = json.dumps(meta)
    if raw:
        old, new = raw.split("=>")
        text = text.replace(old, new)
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "agent.json").write_text(text)
    bomb = next((name for name, value in members.items() if isinstance(value, str)), "")
    if bomb:
        members[bomb] = npy_bytes(files[1].get(bomb, np.zeros((54, 4))))
    write_npz(directory / "agent.npz", members, bomb=bomb)
    return directory / "agent.npz"


@pytest.mark.parametrize("case", CASES)
def test_a_hostile_agent_file_ends_the_resume_in_one_line(
    case: str, saved_dyna_q: Files, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    change, raw, message = CASES[case]
    out = tmp_path / "run"
    npz_path = _write(write_checkpoint(out), saved_dyna_q, change, raw)
    before = listing(out)
    args = ["robot", "run", "--quiet", "--driver", "sim", "--agent", "dyna-q"]
    code = main([*args, "--config", str(REALTIME), "--resume", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("skidnav: error: "), err[:500]
    assert message in lines[0] and str(npz_path.parent / "agent.") in lines[0]
    assert len(lines[0]) < 400
    assert listing(out) == before  # nothing written, nothing left behind


def test_the_intact_checkpoint_files_load(saved_dyna_q: Files, tmp_path: Path) -> None:
    npz_path = _write(tmp_path / "a", saved_dyna_q, lambda files: None, "")
    agent = load_agent(npz_path)
    assert np.array_equal(agent.q, saved_dyna_q[1]["q"])
    assert agent.steps == saved_dyna_q[0]["counters"]["steps"]


def test_no_data_is_read_before_every_member_is_checked(
    saved_dyna_q: Files, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    read: list[str] = []
    original = SavedArchive._data

    def spy(self: SavedArchive, name: str, header: Any) -> np.ndarray:
        read.append(name)
        return original(self, name, header)

    monkeypatch.setattr(SavedArchive, "_data", spy)
    for change in (_member("payload", "bomb"), _member("model.entry_count", "bomb")):
        read.clear()
        with pytest.raises(CorruptFileError):
            load_agent(_write(tmp_path / "b", saved_dyna_q, change, ""))
        assert read == []  # refused from the zip directory and the headers alone


def test_json_through_a_device_is_refused_and_a_long_one_cut(
    saved_dyna_q: Files, tmp_path: Path
) -> None:
    npz_path = _write(tmp_path / "c", saved_dyna_q, lambda files: None, "")
    json_path = npz_path.with_suffix(".json")
    json_path.unlink()
    json_path.symlink_to("/dev/zero")
    with pytest.raises(CorruptFileError, match=r"agent file \(a character device, not a regular"):
        load_agent(npz_path)
    json_path.unlink()
    json_path.write_bytes(b" " * (2**20 + 1))
    with pytest.raises(CorruptFileError, match="agent file larger than 1,048,576 bytes"):
        load_agent(npz_path)


def test_a_saved_geometry_cannot_ask_for_huge_tables(tmp_path: Path) -> None:
    grid = Discretization(n_x=6, n_y=5, n_headings=4, regions_x=2, regions_y=2)
    agent = make_agent("dyna-kinematic", grid.n_states, 4, {}, discretization=grid)
    npz_path, json_path = agent.save(tmp_path / "k")
    assert load_agent(npz_path).kinematic is not None
    meta = json.loads(json_path.read_text())
    saved = meta["geometry"]["discretization"]
    for change, message in (
        ({"regions_x": 10**6, "regions_y": 10**6, "n_x": 10**6, "n_y": 10**6, "n_headings": 1},
         "saved geometry has 1000000000000 states"),
        ({"n_x": 10**9}, "saved geometry has"),  # the states no longer match the metadata
    ):  # fmt: skip
        meta["geometry"]["discretization"] = {**saved, **change}
        json_path.write_text(json.dumps(meta))
        with pytest.raises(CorruptFileError, match=message) as caught:
            load_agent(npz_path)
        assert str(caught.value).startswith(str(json_path))


@pytest.mark.parametrize(
    ("section", "key", "value", "message"),
    [
        ("grid", "regions_x", 10**7, "kinematic model of 70,000,000 slip regions"),
        ("config", "window", 10**12, "window of 1,000,000,000,000 samples is too large"),
        ("grid", "n_x", 12500.7, "n_x to be an integer"),
        ("robot", "unknown", 1, "unexpected keyword argument 'unknown'"),
    ],
)
def test_a_kinematic_model_file_is_checked_before_allocation(
    tmp_path: Path, section: str, key: str, value: Any, message: str
) -> None:
    model = KinematicModel(RobotParams(), Discretization(), KinematicModelConfig(window=16))
    save_model(model, tmp_path / "kin")
    assert load_model(tmp_path / "kin").config.window == 16
    meta = json.loads((tmp_path / "kin.json").read_text())
    meta[section][key] = value
    (tmp_path / "kin.json").write_text(json.dumps(meta))
    with pytest.raises(CorruptFileError, match=message) as caught:
        load_model(tmp_path / "kin")
    assert str(caught.value).startswith(str(tmp_path / "kin")) and "\n" not in str(caught.value)


def test_a_kinematic_model_archive_with_a_stranger_is_refused(tmp_path: Path) -> None:
    model = KinematicModel(RobotParams(), Discretization(), KinematicModelConfig(window=16))
    save_model(model, tmp_path / "kin")
    members = arrays_of(tmp_path / "kin.npz")
    write_npz(tmp_path / "kin.npz", {**members, "extra": np.zeros(2)})
    with pytest.raises(CorruptFileError, match="unexpected array 'extra'"):
        load_model(tmp_path / "kin")
    write_npz(tmp_path / "kin.npz", {**members, "kinematic_data": forged_npy((49, 10**9, 5))})
    with pytest.raises(CorruptFileError, match="kinematic_data' is float64 of shape"):
        load_model(tmp_path / "kin")
