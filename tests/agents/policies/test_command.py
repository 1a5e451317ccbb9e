"""``skidnav study search``: its files on the happy path, the same command resuming a search cut
short from its checkpoint (the numbers of a search never stopped), one line and exit code 2 on
bad input."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from skidnav.agents.policies.search.curve import GenerationRecord
from skidnav.agents.policies.search.policy_file import load_policy
from skidnav.cli import main
from tests.cli_support import exit_code

TINY = [
    "study", "search", "--map", "free", "--world-seed", "3", "--max-steps", "20", "--hidden", "2",
    "--population", "6", "--generations", "2", "--episodes", "1", "--eval-episodes", "2",
]  # fmt: skip


def curve(out: Path) -> list[dict[str, str]]:
    """The rows of ``out/curve.csv`` without their wall time."""
    with open(out / "curve.csv", newline="") as handle:
        return [
            {k: v for k, v in row.items() if k != "wall_time"} for row in csv.DictReader(handle)
        ]


def test_search_writes_the_policy_and_the_learning_curve(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    assert main([*TINY, "--out", str(out)]) == 0
    assert "generation 2/2: 12 episodes" in capsys.readouterr().out
    rows = curve(out)
    assert [row["generation"] for row in rows] == ["0", "1", "2"]
    assert rows[0]["best_return"] == "" and float(rows[2]["episodes"]) == 12
    policy = load_policy(out / "policy")
    assert policy.layout.hidden == 2 and policy.lidar_rays == 8
    summary = json.loads((out / "search.json").read_text())
    assert summary["config"]["population"] == 6 and summary["last"]["generation"] == 2
    provenance = json.loads((out / "policy.json").read_text())["provenance"]
    assert provenance["config"] == summary["config"] and provenance["run_id"] == "run-000000"
    assert (out / "runs" / "run-000000.npz").exists() and (out / "config.toml").exists()
    assert main([*TINY, "--out", str(out)]) == 0  # finished: not run again
    assert "had finished already" in capsys.readouterr().out
    assert np.array_equal(load_policy(out / "policy").parameters, policy.parameters)


def test_a_search_cut_short_continues_from_its_checkpoint(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    whole, cut = tmp_path / "whole", tmp_path / "cut"
    assert main([*TINY, "--out", str(whole)]) == 0

    def interrupt_after_generation_1(spec: object, record: GenerationRecord) -> None:
        if record.generation == 1:
            raise KeyboardInterrupt

    monkeypatch.setattr("skidnav.commands.search.print_generation", interrupt_after_generation_1)
    assert main([*TINY, "--out", str(cut)]) == 130
    assert (cut / "checkpoints" / "run-000000.npz").exists() and not list(
        (cut / "runs").glob("*.npz")
    )
    monkeypatch.undo()
    capsys.readouterr()
    assert main([*TINY, "--out", str(cut)]) == 0
    printed = capsys.readouterr().out
    assert "generation 2/2" in printed and "generation 1/2" not in printed  # resumed after 1
    assert curve(cut) == curve(whole)
    parameters = [load_policy(out / "policy").parameters for out in (cut, whole)]
    assert np.array_equal(*parameters)


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
        (["--seed", "-1"], "expected --seed to be an integer in [0, 9223372036854775807], got -1"),
        (["--map", "cave"], "invalid choice"),
    ],
)
def test_bad_input_is_one_line_and_exit_code_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str], message: str
) -> None:
    assert exit_code([*TINY, "--out", str(tmp_path / "run"), *extra]) == 2
    error = capsys.readouterr().err
    assert message in error and error.count("\n") == 1 and error.startswith("skidnav: error:")
    assert not (tmp_path / "run").exists()


def test_a_folder_holding_another_search_is_not_overwritten(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    earlier = tmp_path / "earlier"
    earlier.mkdir()
    (earlier / "checkpoint.json").write_text("{}")  # what the command wrote before the study
    assert main([*TINY, "--out", str(earlier)]) == 2
    assert "holds a search in an earlier format" in capsys.readouterr().err
    out = tmp_path / "run"
    assert main([*TINY, "--out", str(out)]) == 0
    assert main([*TINY[:-2], "--eval-episodes", "3", "--out", str(out)]) == 2
    assert "holds results of a different config" in capsys.readouterr().err


def test_a_hand_edited_checkpoint_is_one_line_and_exit_code_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The review's edit: a 400-digit wall time in the readable copy (an OverflowError)."""
    out = tmp_path / "run"
    assert main([*TINY, "--out", str(out)]) == 0
    (out / "runs" / "run-000000.npz").unlink()  # the search resumes from its checkpoint
    copy = out / "checkpoints" / "run-000000.json"
    huge = '"wall_time": 1' + "0" * 400 + ', "w": '
    copy.write_text(copy.read_text().replace('"wall_time": ', huge, 1))
    capsys.readouterr()
    assert main([*TINY, "--out", str(out)]) == 2
    error = capsys.readouterr().err
    assert "run-000000.json: does not match run-000000.npz" in error and error.count("\n") == 1
