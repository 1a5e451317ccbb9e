"""``skidnav study transfer``: policies from the kinematic simulator run on the MuJoCo robot."""

from __future__ import annotations

import csv
import subprocess
import sys
from dataclasses import astuple
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco")

from skidnav.studies.transfer import transfer_run


def test_same_seed_same_gap_and_shares_are_shares() -> None:
    runs = [transfer_run("q-learning", 3, 3, rollouts=2, max_steps=30) for _ in range(2)]
    np.testing.assert_equal(astuple(runs[0]), astuple(runs[1]))  # NaN equals NaN here
    for share in (runs[0].success_kinematic, runs[0].success_physics):
        assert share in (0.0, 0.5, 1.0)


def test_command_writes_one_row_per_agent_and_seed(tmp_path: Path) -> None:
    out = tmp_path / "gap.csv"
    done = subprocess.run(
        [sys.executable, "-m", "skidnav.cli", "study", "transfer", "--agent", "dyna-q", "--seeds",
        "2",
         "--episodes", "2", "--planning-steps", "5", "--rollouts", "1", "--out", str(out)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    rows = list(csv.DictReader(out.open()))
    assert [(row["agent"], row["seed"]) for row in rows] == [("dyna-q", "0"), ("dyna-q", "1")]
    assert "success, physics" in done.stdout


@pytest.mark.parametrize("flag, value", [("--seeds", "0"), ("--rollouts", "1000")])
def test_bad_arguments_are_one_line(flag: str, value: str) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "skidnav.cli", "study", "transfer", flag, value],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1
