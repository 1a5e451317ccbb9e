"""Helpers shared by the tests of the studies run by ``skidnav run`` (generalisation, transfer):
run a config in this process, read its tables back for equality checks."""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any

import pandas as pd
import pytest

from skidnav.cli import build_parser, main
from skidnav.commands.shortcut import FLAGS
from skidnav.files.configtables import toml_document
from skidnav.studies.loading import load_grid, parse_grid

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def run_config(config: Path, out: Path, *options: str) -> None:
    """``skidnav run CONFIG --out OUT OPTIONS`` in this process; asserts it succeeded."""
    assert main(["run", str(config), "--out", str(out), "--no-progress", *options]) == 0


def tables(out: Path) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(episodes without wall times, summaries) of a results directory, in run order."""
    episodes = pd.read_parquet(out / "episodes.parquet").drop(columns=["wall_time"])
    summaries = pd.read_parquet(out / "summaries.parquet")
    return (
        episodes.sort_values(["run_id", "episode"]).reset_index(drop=True),
        summaries.sort_values("run_id").reset_index(drop=True),
    )


def check_serial_and_process_agree(config: Path, tmp_path: Path, n_runs: int) -> None:
    """The config run serially gives one run file per run, and the same tables as on two worker
    processes."""
    run_config(config, tmp_path / "serial", "--backend", "serial")
    run_files = sorted(path.name for path in (tmp_path / "serial" / "runs").iterdir())
    assert run_files == [f"run-{index:06d}.npz" for index in range(n_runs)]
    run_config(config, tmp_path / "process", "--backend", "process", "--jobs", "2")
    for serial, process in zip(
        tables(tmp_path / "serial"), tables(tmp_path / "process"), strict=True
    ):
        pd.testing.assert_frame_equal(serial, process)


def check_bad_key_is_one_line(
    config: Path, text: str, expected: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """``skidnav run`` on config ``text`` ends in one line naming the file and ``expected``
    (``{config}`` in it: the file), exit code 2."""
    config.write_text(text)
    assert main(["run", str(config), "--out", str(config.parent / "out")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    expected = expected.replace("{config}", str(config))
    assert len(lines) == 1 and str(config) in lines[0] and expected in lines[0], lines
    assert not (config.parent / "out").exists()


def shipped_config_grid_and_defaults(verb: str, config: str) -> tuple[Any, Any]:
    """(the grid of ``configs/CONFIG``, the grid ``skidnav study VERB`` runs without flags)."""
    arguments = build_parser().parse_args(["study", verb])
    module = importlib.import_module(f"skidnav.commands.{arguments.func.__module__.split('.')[-1]}")
    text = toml_document(module.config_document(arguments))
    return load_grid(CONFIGS / config).grid, parse_grid(text, FLAGS).grid
