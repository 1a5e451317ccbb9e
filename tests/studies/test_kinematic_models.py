"""The kinematic-model comparison as a study: a config run by ``skidnav run`` (one run file per
model and seed, the same numbers on the serial and the process backend, the table of the
comparison before it became a study), its shortcut ``skidnav study kinematic compare`` (the same
config, the same table, resumable), and bad configs and flags as one line and exit code 2."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from skidnav.cli import main
from skidnav.experiments.store import ResultStore
from skidnav.studies.kinematic_models.grid import LAYOUT, ModelComparison
from skidnav.studies.kinematic_models.table import report_section, table_rows, text_table
from tests.cli_support import exit_code

TINY = """kind = "kinematic-models"
seeds = 2
samples = 300
drift = 0.5
window = 20
"""
SHORTCUT = ["study", "kinematic", "compare", "--seeds", "2", "--samples", "300", "--window", "20"]
SHORTCUT += ["--drift", "0.5", "--backend", "serial", "--no-progress"]
TABLE_BEFORE_THE_STUDY = """\
ridge  v_x                2.21 [2.06, 2.36]     0.663 [0.660, 0.667]          4.81 [4.27, 5.36]
ridge  v_y                0.66 [0.20, 1.13]     0.770 [0.540, 1.000]          1.46 [1.16, 1.76]
ridge  yaw_rate        38.72 [29.84, 47.60]     0.570 [0.460, 0.680]       59.67 [57.49, 61.85]
gp     v_x             25.30 [20.06, 30.54]     0.427 [0.280, 0.573]        20.65 [1.87, 39.44]
gp     v_y                2.31 [1.13, 3.49]     0.530 [0.513, 0.547]        10.44 [4.27, 16.61]
gp     yaw_rate      286.26 [47.86, 524.66]     0.530 [0.513, 0.547]    672.25 [641.85, 702.65]"""
"""``skidnav study kinematic compare`` of these arguments before it ran on the runner, but for
the fit-time column (a wall time)."""
NOT_MEASURED = "fit_seconds"
"""The one summary column that differs between two runs of the same config (a wall time)."""


@pytest.fixture(scope="module")
def serial(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The results of :data:`TINY` run by ``skidnav run --backend serial``."""
    folder = tmp_path_factory.mktemp("kinematic")
    (folder / "tiny.toml").write_text(TINY)
    out = folder / "serial"
    assert main(["run", str(folder / "tiny.toml"), "--out", str(out), "--backend", "serial"]) == 0
    return out


def _summaries(out: Path) -> pd.DataFrame:
    return ResultStore(out, LAYOUT).load_tables()[1].drop(columns=NOT_MEASURED)


def _measured_cells(lines: list[str]) -> str:
    """The table's rows without the fit-time column."""
    return "\n".join(line[:95] for line in lines[1:])


def test_one_run_file_per_model_and_seed_the_same_on_both_backends(
    serial: Path, tmp_path: Path
) -> None:
    assert sorted(path.name for path in (serial / "runs").iterdir()) == [
        f"run-00000{index}.npz" for index in range(4)
    ]
    summaries = _summaries(serial)
    assert list(zip(summaries["algorithm"], summaries["seed"], strict=True)) == [
        ("ridge", 0), ("ridge", 1), ("gp", 0), ("gp", 1)
    ]  # fmt: skip
    episodes = ResultStore(serial, LAYOUT).load_tables()[0]
    assert len(episodes) == 12 and (episodes["rmse"] > 0).all()  # one row per output
    process = tmp_path / "process"
    arguments = ["--backend", "process", "--jobs", "2", "--no-progress"]
    assert main(["run", str(serial.parent / "tiny.toml"), "--out", str(process), *arguments]) == 0
    pd.testing.assert_frame_equal(_summaries(process), summaries)


def test_the_table_is_the_one_of_the_comparison_before_the_study(serial: Path) -> None:
    store = ResultStore(serial, LAYOUT)
    lines = text_table(table_rows(store.config(), store.load_tables()[1]))
    assert _measured_cells(lines) == TABLE_BEFORE_THE_STUDY


def test_the_shortcut_is_the_config_and_prints_its_table(
    serial: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "shortcut"
    assert main([*SHORTCUT, "--out", str(out)]) == 0
    ran, *lines = capsys.readouterr().out.splitlines()
    assert "(4 run now, 0 already done)" in ran
    assert "drift A = 0.5 over P = 30 s" in lines[0] and "window 20; means over 2 seeds" in lines[0]
    assert _measured_cells(lines[1:]) == TABLE_BEFORE_THE_STUDY
    pd.testing.assert_frame_equal(_summaries(out), _summaries(serial))
    comparison = ResultStore(out, LAYOUT).config()
    assert comparison == ResultStore(serial, LAYOUT).config()  # the config of TINY
    assert comparison == ModelComparison(seeds=2, samples=300, drift=0.5, window=20)
    assert main(["run", str(out / "config.toml"), "--out", str(out), "--no-progress"]) == 0
    assert "(0 run now, 4 already done)" in capsys.readouterr().out  # the same config
    assert main([*SHORTCUT, "--out", str(out)]) == 0  # resumed: nothing left to run
    ran, *lines = capsys.readouterr().out.splitlines()
    assert "(0 run now, 4 already done)" in ran
    assert _measured_cells(lines[1:]) == TABLE_BEFORE_THE_STUDY


def test_the_report_section_is_the_table(serial: Path) -> None:
    section = report_section(serial)
    assert section.startswith("<h2>") and "4 of 4 runs finished" in section
    for cell in ("2.21 [2.06, 2.36]", "0.530 [0.513, 0.547]", "672.25 [641.85, 702.65]"):
        assert cell in section


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("seedz = 2", "(did you mean 'seeds'? expected one of kind, name, models, seeds"),
        ("seeds = 0", "expected seeds to be an integer in [1, 1000], got 0"),
        ('models = ["ridge", "lasso"]', "expected models to be distinct names among ridge, gp"),
        ('slip = "ice"', "expected slip to be one of thesis, slippery"),
        ("train_fraction = 1", "expected train_fraction to be a finite number in [0.1, 0.9]"),
        ("window = 10", "expected window to be an integer in [20, 2000], got 10"),
    ],
)
def test_a_bad_config_is_one_line_and_exit_code_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], line: str, message: str
) -> None:
    config = tmp_path / "bad.toml"
    config.write_text(f'kind = "kinematic-models"\n{line}\n')
    assert exit_code(["run", str(config), "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and str(config) in error and message in error, error
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        ("--seeds", "0", "expected --seeds to be an integer in [1, 1000], got 0"),
        ("--samples", "99", "expected --samples to be an integer in [100, 1000000], got 99"),
        ("--drift", "-1", "expected --drift to be a finite number >= 0, got -1.0"),
        ("--drift-period", "0", "expected --drift-period to be a finite number > 0, got 0.0"),
        ("--train-fraction", "1", "expected --train-fraction to be a finite number in [0.1, 0.9]"),
        ("--window", "10", "expected --window to be an integer in [20, 2000], got 10"),
        ("--slip", "ice", "invalid choice: 'ice'"),
    ],
)
def test_bad_flags_give_one_line_and_exit_code_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], option: str, value: str, message: str
) -> None:
    out = tmp_path / "out"
    assert exit_code([*SHORTCUT, option, value, "--out", str(out)]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and message in error, error
    assert not out.exists()
