"""``skidnav study search``: its files on the happy path, one line and exit code 2 on bad input."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from skidnav.agents.policies.search.policy_file import load_policy
from skidnav.cli import main

TINY = [
    "study", "search", "--map", "free", "--world-seed", "3", "--max-steps", "20", "--hidden", "2",
    "--population", "6", "--generations", "2", "--episodes", "1", "--eval-episodes", "2",
]  # fmt: skip


def exit_code(argv: list[str]) -> int:
    """``main``'s exit code, argparse's exits included."""
    try:
        return main(argv)
    except SystemExit as exit:
        return int(exit.code or 0)


def test_search_writes_the_policy_and_the_learning_curve(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    assert main([*TINY, "--out", str(out)]) == 0
    assert "generation 2/2: 12 episodes" in capsys.readouterr().out
    with open(out / "curve.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [row["generation"] for row in rows] == ["0", "1", "2"]
    assert rows[0]["best_return"] == "" and float(rows[2]["episodes"]) == 12
    policy = load_policy(out / "policy")
    assert policy.layout.hidden == 2 and policy.lidar_rays == 8
    summary = json.loads((out / "search.json").read_text())
    assert summary["config"]["population"] == 6 and summary["last"]["generation"] == 2
    more = [*TINY[:-6], "--generations", "3", *TINY[-4:]]
    assert main([*more, "--out", str(out), "--resume"]) == 0
    assert "generation 3/3: 18 episodes" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--population", "1"], "expected --population to be an integer in [2, 10000], got 1"),
        (["--control-period", "0.15"], "expected --control-period to be a whole number"),
        (["--sigma", "nan"], "expected --sigma to be a finite number in (0, 1e+30]"),
        (["--sigma", "1e40"], "expected --sigma to be a finite number in (0, 1e+30], got 1e+40"),
        (["--control-period", "1e300"], "expected --control-period to be a finite number in"),
        (
            ["--population", "10000", "--episodes", "10000"],
            "827 GiB for the episodes of --population 10000 × --episodes 10000",
        ),
        (["--hidden", "1024", "--lidar-rays", "1024"], "parameters from --hidden 1024 and"),
        (["--lidar-rays", "1025"], "expected --lidar-rays to be an integer in [0, 1024], got 1025"),
        (["--resume"], "no checkpoint.json to resume from"),
        (["--map", "cave"], "invalid choice"),
    ],
)
def test_bad_input_is_one_line_and_exit_code_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str], message: str
) -> None:
    assert exit_code([*TINY, "--out", str(tmp_path / "run"), *extra]) == 2
    error = capsys.readouterr().err
    assert message in error and error.count("\n") == 1 and error.startswith("skidnav: error:")


def test_a_folder_holding_a_search_is_not_overwritten(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    out.mkdir()
    (out / "checkpoint.json").write_text("{}")
    assert main([*TINY, "--out", str(out)]) == 2
    assert "holds a search already" in capsys.readouterr().err
    assert main([*TINY, "--out", str(out), "--resume"]) == 2
    assert "checkpoint.npz: no such file" in capsys.readouterr().err


def test_a_hand_edited_checkpoint_is_one_line_and_exit_code_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The review's edit: a 400-digit wall time in the readable copy (an OverflowError)."""
    out = tmp_path / "run"
    assert main([*TINY, "--out", str(out)]) == 0
    copy = out / "checkpoint.json"
    huge = '"wall_time": 1' + "0" * 400 + ', "w": '
    copy.write_text(copy.read_text().replace('"wall_time": ', huge, 1))
    capsys.readouterr()
    assert main([*TINY, "--out", str(out), "--resume"]) == 2
    error = capsys.readouterr().err
    assert "checkpoint.json: does not match checkpoint.npz" in error and error.count("\n") == 1
