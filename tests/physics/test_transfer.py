"""The sim-to-sim transfer study: policies from the kinematic simulator run on the MuJoCo robot;
the study as a config run by ``skidnav run``, and ``skidnav study transfer``."""

from __future__ import annotations

import csv
import subprocess
import sys
from dataclasses import astuple
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco")

from skidnav.cli import main
from skidnav.studies.agent_grid import study_results
from skidnav.studies.transfer.evaluation import transfer_run
from skidnav.studies.transfer.report import results_of, summary_text
from skidnav.studies.transfer.study import STUDY
from tests.experiments.study_support import (
    check_bad_key_is_one_line,
    check_serial_and_process_agree,
    run_config,
    shipped_config_grid_and_defaults,
)

TINY_CONFIG = """
kind = "transfer"

[transfer]
seeds = 2
episodes = 3
max_steps = 25
rollouts = 1
slip = "thesis"

[[agents]]
name = "dyna-q"
params = { planning_steps = 5 }
"""
"""1 agent × 2 seeds = 2 runs of 3 short episodes, one rollout per dynamics."""
SHORTCUT = ["study", "transfer", "--agent", "dyna-q", "--seeds", "2", "--episodes", "3",
            "--max-steps", "25", "--rollouts", "1", "--slip", "thesis",
            "--planning-steps", "5"]  # fmt: skip
"""The flags of :data:`TINY_CONFIG` (named ``transfer``, as the shortcut names it)."""


def test_same_seed_same_gap_and_shares_are_shares() -> None:
    runs = [transfer_run("q-learning", 3, 3, rollouts=2, max_steps=30) for _ in range(2)]
    np.testing.assert_equal(astuple(runs[0].result), astuple(runs[1].result))  # NaN equals NaN
    for share in (runs[0].result.success_kinematic, runs[0].result.success_physics):
        assert share in (0.0, 0.5, 1.0)
    assert len(runs[0].log.lengths) == 3 and np.all(runs[0].log.lengths <= 30)


def test_command_writes_one_row_per_agent_and_seed(tmp_path: Path) -> None:
    out = tmp_path / "gap"
    done = subprocess.run(
        [sys.executable, "-m", "skidnav.cli", "study", "transfer", "--agent", "dyna-q", "--seeds",
        "2",
         "--episodes", "2", "--planning-steps", "5", "--rollouts", "1", "--max-steps", "25",
         "--out", str(out), "--backend", "serial"],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    rows = list(csv.DictReader((out / "transfer.csv").open()))
    assert [(row["agent"], row["seed"]) for row in rows] == [("dyna-q", "0"), ("dyna-q", "1")]
    assert "success, physics" in done.stdout


@pytest.mark.parametrize(
    "flag, value, expected",
    [
        ("--seeds", "0", "expected seeds to be an integer in [1, 1,000], got 0"),
        ("--rollouts", "1000", "expected rollouts to be an integer in [1, 100], got 1000"),
        (
            "--planning-steps",
            "-1",
            "error: expected an integer planning_steps in [0, 10,000,000], got -1 "
            "in <flags>: [[agents]]: agent 'dyna-full'\n",
        ),
    ],
)
def test_bad_arguments_are_one_line(flag: str, value: str, expected: str) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "skidnav.cli", "study", "transfer", flag, value, "--out", "x"],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert expected in done.stderr


def test_a_config_run_by_skidnav_run_gives_one_file_per_run_on_every_backend(
    tmp_path: Path,
) -> None:
    (tmp_path / "tiny.toml").write_text(TINY_CONFIG)
    check_serial_and_process_agree(tmp_path / "tiny.toml", tmp_path, 2)
    grid, summaries = study_results(tmp_path / "serial", STUDY.layout)
    assert grid.name == "tiny" and list(summaries["seed"]) == [0, 1]
    assert "<h2>The sim-to-sim gap</h2>" in STUDY.report(tmp_path / "serial")


@pytest.mark.parametrize(
    "text, expected",
    [
        (
            TINY_CONFIG.replace("rollouts =", "rollout ="),
            "bad.toml: [transfer] (did you mean 'rollouts'?",
        ),
        (
            TINY_CONFIG.replace('"thesis"', '"icy"'),
            "expected slip one of thesis, slippery, rough, nominal, rough-physics, "
            "slippery-physics, ice-physics, got 'icy' in {config}: [transfer]",
        ),
        (
            TINY_CONFIG.replace('"dyna-q"', '"dqn"'),
            "expected name to be a tabular agent, got 'dqn' in {config}: [[agents]] (tabular",
        ),
        (TINY_CONFIG.replace("seeds = 2", "seeds = 2.5"), "expected seeds to be an integer"),
        (
            TINY_CONFIG.replace("[[agents]]", "[[agent]]"),
            "bad.toml: top level (did you mean 'agents'?",
        ),
    ],
)
def test_a_bad_config_is_one_line_naming_the_file_and_key(
    text: str, expected: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    check_bad_key_is_one_line(tmp_path / "bad.toml", text, expected, capsys)


def test_the_shortcut_and_the_config_give_the_same_table(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    shortcut = tmp_path / "shortcut"
    assert main([*SHORTCUT, "--out", str(shortcut), "--backend", "serial", "--no-progress"]) == 0
    printed = capsys.readouterr().out
    (tmp_path / "transfer.toml").write_text(TINY_CONFIG)  # named as the shortcut names it
    run_config(tmp_path / "transfer.toml", tmp_path / "config", "--backend", "serial")
    table = summary_text(results_of(study_results(tmp_path / "config", STUDY.layout)[1]))
    assert table in printed and "dyna-q" in table
    run_config(tmp_path / "transfer.toml", shortcut)  # the same config: nothing to run
    assert "(0 run now, 2 already done)" in capsys.readouterr().out


def test_the_shipped_config_is_the_command_s_defaults() -> None:
    shipped, defaults = shipped_config_grid_and_defaults("transfer", "transfer.toml")
    assert shipped == defaults and shipped.fingerprint() == defaults.fingerprint()
