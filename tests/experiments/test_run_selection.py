"""``skidnav run --runs``: a grid run in parts into one directory gives the whole run's results,
and a selection outside the grid is refused in one line."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pandas as pd
import pytest

from skidnav.errors import UserError
from skidnav.experiments.configfile import parse_config
from skidnav.experiments.runner import run_experiment
from skidnav.experiments.runs import expand_runs, select_runs
from tests.experiments.exp_support import TINY_TOML, cli_command, cli_env, comparable


def test_a_grid_run_in_two_parts_gives_the_whole_runs_results(
    serial_results: Path, tmp_path: Path
) -> None:
    """The first part in this process, the rest through the command line; every run keeps its
    streams, so the episodes equal those of the grid run at once."""
    out = tmp_path / "parts"
    first = run_experiment(parse_config(TINY_TOML), out, backend="serial", only="0:3,6")
    assert (first.n_runs, first.executed, first.grid_runs) == (4, 4, 8)
    assert sorted(comparable(out)["run_id"].unique()) == [
        "run-000000",
        "run-000001",
        "run-000002",
        "run-000006",
    ]
    config = tmp_path / "tiny.toml"
    config.write_text(TINY_TOML)
    command = ["run", str(config), "--out", str(out), "--runs", "3:6,7:", "--backend", "serial"]
    result = subprocess.run(
        cli_command(*command, "--no-progress"),
        capture_output=True,
        text=True,
        env=cli_env(),
        check=False,
    )
    assert result.returncode == 0, result.stderr
    assert "4 of the grid's 8 runs in" in result.stdout
    assert "(4 run now, 0 already done)" in result.stdout
    pd.testing.assert_frame_equal(comparable(out), comparable(serial_results))
    metadata = json.loads((out / "metadata.json").read_text())
    assert len(metadata["seeds"]["runs"]) == 8
    assert [session["runs"] for session in metadata["sessions"]] == ["0:3,6", "3:6,7:"]
    assert [session["runs_done"] for session in metadata["sessions"]] == [4, 4]


def test_a_selection_resumes_only_its_own_runs(tmp_path: Path) -> None:
    """Run again, a part skips its finished runs and leaves the rest of the grid alone."""
    config = parse_config(TINY_TOML)
    run_experiment(config, tmp_path, backend="serial", only="5")
    again = run_experiment(config, tmp_path, backend="serial", only="4:6")
    assert (again.n_runs, again.skipped, again.executed) == (2, 1, 1)
    assert sorted(p.stem for p in (tmp_path / "runs").glob("run-*.npz")) == [
        "run-000004",
        "run-000005",
    ]


def test_parts_run_in_two_directories_join_by_copying_their_run_files(
    serial_results: Path, tmp_path: Path
) -> None:
    """Parts run apart (on two machines, say) join by copying one's run files into the
    other's ``runs/``: the whole grid run there then runs nothing and gives the whole run's
    results."""
    config = parse_config(TINY_TOML)
    here, there = tmp_path / "here", tmp_path / "there"
    run_experiment(config, here, backend="serial", only=":5")
    run_experiment(config, there, backend="serial", only="5:")
    for path in (there / "runs").iterdir():
        target = here / "runs" / path.name
        if path.is_dir():
            shutil.copytree(path, target)
        else:
            shutil.copy2(path, target)
    whole = run_experiment(config, here, backend="serial")
    assert (whole.n_runs, whole.skipped, whole.executed) == (8, 8, 0)
    pd.testing.assert_frame_equal(comparable(here), comparable(serial_results))


@pytest.mark.parametrize(
    ("selection", "problem"),
    [
        ("8", "'8' is not a non-empty range of the grid's run indices 0 to 7"),
        ("3:3", "'3:3' is not a non-empty range"),
        ("-1", "'-1' is not a non-empty range"),
        ("0:9", "'0:9' is not a non-empty range"),
        ("one", "'one' is not a run index N or a range A:B"),
        ("1:2:3", "'1:2:3' is not a run index N or a range A:B"),
        ("", "'' is not a run index N or a range A:B"),
        ("0,,2", "'' is not a run index N or a range A:B"),
    ],
)
def test_a_selection_outside_the_grid_is_refused(selection: str, problem: str) -> None:
    with pytest.raises(UserError, match=r"^--runs ") as raised:
        select_runs(expand_runs(parse_config(TINY_TOML)), selection)
    assert problem in str(raised.value)


def test_the_command_refuses_a_bad_selection_in_one_line_before_any_run(tmp_path: Path) -> None:
    config = tmp_path / "tiny.toml"
    config.write_text(TINY_TOML)
    out = tmp_path / "out"
    result = subprocess.run(
        cli_command("run", str(config), "--out", str(out), "--runs", "2:20"),
        capture_output=True,
        text=True,
        env=cli_env(),
        check=False,
    )
    assert result.returncode == 2
    assert result.stderr.strip().count("\n") == 0, result.stderr
    assert "'2:20' is not a non-empty range of the grid's run indices 0 to 7" in result.stderr
    assert not (out / "runs").exists()
