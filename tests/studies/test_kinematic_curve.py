"""The learned kinematic model's data curve as a study: a config run by ``skidnav run`` (one run
file per dynamics, floor and seed, the same numbers on the serial and the process backend), a
curve that separates the learned model from the prior where the datasheet is wrong, the table
of the docs and the report, and bad configs as one line and exit code 2."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from skidnav.cli import main
from skidnav.experiments.store import ResultStore
from skidnav.studies.kinematic_models.curve import PLATEAU_RATIO, plateau_seconds
from skidnav.studies.kinematic_models.curve_grid import LAYOUT, KinematicCurve
from skidnav.studies.kinematic_models.curve_table import markdown_table, report_section
from tests.cli_support import exit_code

TINY = """kind = "kinematic-curve"
floors = ["thesis", "rough-physics"]
seeds = 2
driving_seconds = [1, 5, 10]
test_seconds = 5
"""


@pytest.fixture(scope="module")
def serial(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The results of :data:`TINY` run by ``skidnav run --backend serial``."""
    folder = tmp_path_factory.mktemp("curve")
    (folder / "tiny.toml").write_text(TINY)
    out = folder / "serial"
    assert main(["run", str(folder / "tiny.toml"), "--out", str(out), "--backend", "serial"]) == 0
    return out


def test_one_run_per_floor_and_seed_the_same_on_both_backends(serial: Path, tmp_path: Path) -> None:
    episodes, summaries = ResultStore(serial, LAYOUT).load_tables()
    assert list(zip(summaries["preset"], summaries["seed"], strict=True)) == [
        ("thesis", 0), ("thesis", 1), ("rough-physics", 0), ("rough-physics", 1)
    ]  # fmt: skip
    assert len(episodes) == 12  # one row per t
    process = tmp_path / "process"
    arguments = ["--backend", "process", "--jobs", "2", "--no-progress"]
    assert main(["run", str(serial.parent / "tiny.toml"), "--out", str(process), *arguments]) == 0
    pd.testing.assert_frame_equal(ResultStore(process, LAYOUT).load_tables()[1], summaries)


def test_the_curve_learns_where_the_datasheet_is_wrong_and_not_where_it_is_right(
    serial: Path,
) -> None:
    episodes = ResultStore(serial, LAYOUT).load_tables()[0]
    first, later = episodes[episodes["episode"] == 1], episodes[episodes["episode"] > 1]
    # 1 s of driving is fewer samples than a refit needs: the learned model is still the prior
    np.testing.assert_array_equal(first["learned_one_second"], first["prior_one_second"])
    assert first["learned_coverage"].isna().all() and episodes["prior_coverage"].isna().all()
    rough, thesis = later[later["preset"] == "rough-physics"], later[later["preset"] == "thesis"]
    # the calibrated floor turns at half the datasheet's rate: learning cuts the 1-s error 10x
    assert (rough["learned_one_second"] < 0.1 * rough["prior_one_second"]).all()
    assert (rough["learned_coverage"] > 0.8).all()
    # on the thesis floor the datasheet is the robot: both stay below a tenth of a millimetre
    assert (thesis[["learned_one_second", "prior_one_second"]] < 1e-4).all().all()


def test_the_table_and_the_report_section(serial: Path) -> None:
    table = markdown_table(serial).splitlines()
    assert table[0] == "| floor | model | 1 s | 5 s | 10 s | plateau [s] | coverage ≥ 10 s |"
    assert [row.split(" | ")[:2] for row in table[2:]] == [
        ["| thesis", "learned"], ["| thesis", "prior"],
        ["| rough-physics", "learned"], ["| rough-physics", "prior"],
    ]  # fmt: skip
    section = report_section(serial)
    assert section.startswith("<h2>") and "2 floors, 2 seeds each" in section
    assert f"within {PLATEAU_RATIO:g}×" in section


def test_the_plateau_is_where_the_error_stops_falling() -> None:
    seconds = (1.0, 2.0, 5.0, 10.0, 20.0)
    assert plateau_seconds(seconds, np.array([10.0, 1.0, 1.0, 1.0, 1.0])) == 2.0
    assert plateau_seconds(seconds, np.array([10.0, 1.0, 3.0, 1.0, 1.0])) == 10.0  # came back
    assert plateau_seconds(seconds, np.array([1.0, 1.0, 1.0, 1.0, 1.0])) == 1.0
    assert plateau_seconds(seconds, np.array([16.0, 8.0, 4.0, 2.0, 1.0])) == 20.0  # still falls


def test_the_shipped_config_is_the_default_curve() -> None:
    shipped = Path(__file__).parents[2] / "configs" / "kinematic-models-curve.toml"
    from skidnav.studies.loading import parse_grid

    curve = parse_grid(shipped.read_text(), shipped).grid
    assert isinstance(curve, KinematicCurve) and curve.seeds == 10
    assert curve.dynamics == ("kinematic", "mujoco") and curve.samples == 1000


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("seedz = 2", "(did you mean 'seeds'? expected one of kind, name, floors, dynamics"),
        ('floors = ["ice"]', "expected floors to be distinct names among thesis, slippery"),
        ('dynamics = ["kinematic", "kinematic"]', "expected dynamics to be distinct names"),
        ("driving_seconds = [5, 2]", "expected driving_seconds to increase, got [5.0, 2.0]"),
        ("driving_seconds = []", "expected driving_seconds to be a non-empty list"),
        ("driving_seconds = [0]", "expected driving_seconds to be a finite number in (0, 3600]"),
        ("test_seconds = 0.5", "expected test_seconds to be a finite number in [1"),
        ("test_seconds = 3600", "expected at most 3600 s of driving per run, got 3640"),
    ],
)
def test_a_bad_config_is_one_line_and_exit_code_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], line: str, message: str
) -> None:
    config = tmp_path / "bad.toml"
    config.write_text(f'kind = "kinematic-curve"\n{line}\n')
    assert exit_code(["run", str(config), "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and str(config) in error and message in error, error
    assert not (tmp_path / "out").exists()
