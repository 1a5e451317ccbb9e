"""Hostile results directories and oracle caches: refused in one line (exit 2) through the
command line, nothing left behind; a damaged oracle cache is computed again."""

from __future__ import annotations

import json
import logging
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
import pytest

from skidnav.cli import main
from skidnav.errors import CorruptFileError
from skidnav.experiments.reference.oracle import cache_dir, load_or_compute_oracle
from skidnav.experiments.store import ResultStore
from skidnav.files.jsondepth import json_depth
from skidnav.files.saved import parse_json
from skidnav.world.grid import GridMap, border_walls
from tests.experiments.exp_support import cli_command, cli_env
from tests.saved_file_support import arrays_of, forged_npy, npy_bytes, write_npz

RUN = "run-000003"
NESTED = "[" * 50_000 + "]" * 50_000
Members = dict[str, Any]


def _document(text: str) -> Callable[[Members], None]:
    def change(members: Members) -> None:
        members["document"] = np.array(text)

    return change


def _member(name: str, value: Any) -> Callable[[Members], None]:
    def change(members: Members) -> None:
        members[name] = value

    return change


RUN_FILE_CASES: dict[str, tuple[Callable[[Members], None], str]] = {
    "zip bomb": (_member("episode.return", "bomb"), "bytes stored, its header announces"),
    "unknown member": (_member("array.payload", np.zeros(2)), "unexpected array 'array.payload'"),
    "unknown bomb": (_member("extra", "bomb"), "unexpected array 'extra'"),
    "huge map header": (
        _member("array.value_map", forged_npy((10**6, 10**6))),
        "array 'array.value_map' is float64 of shape (1000000, 1000000)",
    ),
    "too many episodes": (_member("episode.length", np.zeros(7, np.int64)), "of shape (7,)"),
    "object dtype": (_member("episode.success", forged_npy((6,), "|O")), "is object"),
    "nested document": (_document('{"a": ' + NESTED + "}"), "JSON nested 50001 deep"),
    "document without summary": (_document('{"coordinates": {}}'), "without 'summary'"),
}


def _corrupt(run_dir: Path, change: Callable[[Members], None]) -> Path:
    """Rewrite one run file of ``run_dir`` with ``change`` applied; returns its path."""
    path = run_dir / "runs" / f"{RUN}.npz"
    members: Members = arrays_of(path)
    original = dict(members)
    change(members)
    bomb = next((name for name, value in members.items() if isinstance(value, str)), "")
    if bomb:
        members[bomb] = npy_bytes(original.get(bomb, np.zeros(6)))
    write_npz(path, members, bomb=bomb)
    return path


def _listing(root: Path) -> list[tuple[str, int]]:
    return sorted((str(p.relative_to(root)), p.stat().st_size) for p in root.rglob("*"))


@pytest.fixture()
def results_copy(serial_results: Path, tmp_path: Path) -> Path:
    """A private copy of the tiny results without their tidy tables (a resume rebuilds them
    from the run files)."""
    copy = Path(shutil.copytree(serial_results, tmp_path / "results"))
    for name in ("episodes.parquet", "summaries.parquet", "summaries.csv"):
        (copy / name).unlink()
    return copy


@pytest.mark.parametrize("case", RUN_FILE_CASES)
def test_a_hostile_run_file_ends_the_resume_in_one_line(
    case: str,
    results_copy: Path,
    tiny_config_file: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    change, message = RUN_FILE_CASES[case]
    path = _corrupt(results_copy, change)
    before = _listing(results_copy)
    args = ["run", str(tiny_config_file), "--out", str(results_copy), "--backend", "serial"]
    code = main([*args, "--no-progress"])
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(lines) == 1, lines
    assert lines[0].startswith(f"skidnav: error: {path}: ") and message in lines[0], lines
    assert len(lines[0]) < 300
    assert _listing(results_copy) == before  # no table, no temporary, no metadata written


def test_a_nested_config_json_ends_the_report_in_one_line(results_copy: Path) -> None:
    (results_copy / "config.json").write_text('{"fingerprint": ' + NESTED + "}")
    before = _listing(results_copy)
    result = subprocess.run(
        cli_command("report", str(results_copy)), env=cli_env(), capture_output=True, text=True
    )
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1, result.stderr[-2000:]
    assert "config.json: JSON nested 50001 deep" in lines[0]
    assert _listing(results_copy) == before


def test_an_intact_copy_resumes_and_reads(results_copy: Path) -> None:
    store = ResultStore(results_copy)
    run = store.read_run(RUN)
    assert set(run.episodes) >= {"return", "length"} and run.arrays["occupancy"].dtype == bool
    assert store.run_code(RUN)["version"]


def test_json_limits() -> None:
    assert json_depth('{"a": "[[[[", "b": [{"c": []}]}') == 4
    assert parse_json('{"x": NaN}', "f", allow_nonfinite=True)["x"] != 0
    for text, message in (
        ('{"x": 1e400}', "out of range"),
        ('{"x": -Infinity}', "non-finite number -Infinity"),
        ("[1]", "expected a JSON object, got list"),
        ('{"x": ' + "[" * 40 + "]" * 40 + "}", "JSON nested 41 deep"),
        ('{"x": ' + "1" * 5000 + "}", "invalid JSON"),
    ):
        with pytest.raises(CorruptFileError, match=message):
            parse_json(text, "f")


def _small_env() -> gymnasium.Env[Any, Any]:
    grid = GridMap(border_walls((7, 5)), start=(1, 2), goal=(5, 2))
    return gymnasium.make("skidnav/SkidSteerNav-v0", grid_map=grid, slip="rough")


def test_a_damaged_oracle_cache_is_computed_again(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    monkeypatch.setenv("SKIDNAV_CACHE_DIR", str(tmp_path / "cache"))
    first = load_or_compute_oracle(_small_env(), 2, 3, [0], 40)
    (cached,) = (cache_dir() / "oracles").glob("*.npz")
    members = arrays_of(cached)
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stale = cached.with_name(f".{cached.name}.{dead.pid}-0123abcd.tmp")
    stale.write_bytes(b"left by a killed writer")
    for damage in (
        {**members, "q": forged_npy((10**9, 4))},
        {**members, "extra": np.zeros(1)},
        {key: value for key, value in members.items() if key != "sweeps"},
    ):
        write_npz(cached, damage)
        with caplog.at_level(logging.WARNING, logger="skidnav.experiments.reference.oracle"):
            again = load_or_compute_oracle(_small_env(), 2, 3, [0], 40)
        assert "oracle cache unreadable" in caplog.text
        caplog.clear()
        assert np.array_equal(again.q, first.q) and again.start_value == first.start_value
        assert arrays_of(cached).keys() == members.keys()  # rewritten whole
    assert sorted(p.name for p in cached.parent.iterdir()) == [cached.name]  # stale one gone


def test_run_file_documents_keep_nonfinite_summaries(results_copy: Path) -> None:
    document = json.loads(str(arrays_of(results_copy / "runs" / f"{RUN}.npz")["document"]))
    document["summary"]["oracle_length"] = float("inf")
    _corrupt(results_copy, _document(json.dumps(document)))
    assert ResultStore(results_copy).read_run(RUN).summary["oracle_length"] == float("inf")


def test_a_run_file_without_greedy_costs_reads_them_as_nan(results_copy: Path) -> None:
    """A run file written before the evaluations' costs were recorded: its other columns as
    saved, ``greedy_cost`` NaN (not measured), in the tables too."""
    intact = ResultStore(results_copy).read_run(RUN)
    _corrupt(results_copy, lambda members: members.pop("episode.greedy_cost"))
    old = ResultStore(results_copy).read_run(RUN)
    assert np.isnan(old.episodes["greedy_cost"]).all()
    assert len(old.episodes["greedy_cost"]) == len(old.episodes["length"])
    for key in intact.episodes.keys() - {"greedy_cost"}:
        assert np.array_equal(old.episodes[key], intact.episodes[key], equal_nan=True), key
    episodes, _ = ResultStore(results_copy).consolidate()
    assert episodes.loc[episodes["run_id"] == RUN, "greedy_cost"].isna().all()
    assert len(episodes) == 8 * 6
