"""The registry of study kinds (``skidnav.studies.kind``) and the kind of a results directory,
by which ``skidnav report`` chooses the report."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from skidnav.cli import main
from skidnav.errors import CorruptFileError, UserError
from skidnav.experiments.configfile import parse_config
from skidnav.experiments.store import EXPERIMENT_LAYOUT, results_kind
from skidnav.studies.gap import gap_section
from skidnav.studies.kind import STUDY_MODULES, VerdictStudy, experiment_sections, study
from skidnav.studies.loading import parse_grid
from tests.experiments.exp_support import TINY_TOML


@pytest.mark.parametrize("kind", sorted(STUDY_MODULES))
def test_every_study_is_found_by_its_kind_and_writes_results_of_that_kind(kind: str) -> None:
    chosen = study(kind)
    assert chosen.kind == kind == chosen.layout.kind
    assert set(chosen.backends) <= {"serial", "process", "dask"}


def test_the_hardware_study_runs_serially_and_the_continuity_study_anywhere() -> None:
    assert study("robot-study").backends == ("serial",)
    assert study("continuity").backends == ("serial", "process", "dask")


@pytest.mark.parametrize("kind_line", ["", 'kind = "experiment"\n'])
def test_a_config_without_a_kind_is_the_experiment_study(kind_line: str) -> None:
    loaded = parse_grid(kind_line + TINY_TOML, Path("tiny.toml"))
    assert loaded.study is study("experiment") and loaded.layout is EXPERIMENT_LAYOUT
    assert loaded.grid == parse_config(TINY_TOML, "tiny.toml")
    assert isinstance(loaded.study, VerdictStudy)
    assert not any(
        isinstance(study(kind), VerdictStudy) for kind in STUDY_MODULES if kind != "experiment"
    )


def test_an_experiment_config_is_checked_when_loaded() -> None:
    text = TINY_TOML.replace('name = "dyna-q"', 'name = "dyna-z"')
    with pytest.raises(UserError, match=r"^unknown agent 'dyna-z'; .* in tiny\.toml$"):
        parse_grid(text, Path("tiny.toml"))


def test_the_experiment_report_gets_the_studies_sections() -> None:
    assert experiment_sections() == (gap_section,)


def test_the_kind_of_a_results_directory(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert results_kind(tmp_path) == "experiment"  # no config.json: its report names it
    (tmp_path / "config.json").write_text(json.dumps({"fingerprint": "x", "config": {}}))
    assert results_kind(tmp_path) == "experiment"  # written before kinds were recorded
    (tmp_path / "config.json").write_text(json.dumps({"kind": "continuity"}))
    assert results_kind(tmp_path) == "continuity"
    (tmp_path / "config.json").write_text(json.dumps({"kind": 3}))
    with pytest.raises(CorruptFileError, match="kind: expected a string, got 3"):
        results_kind(tmp_path)
    (tmp_path / "config.json").write_text(json.dumps({"kind": "nope"}))
    assert main(["report", str(tmp_path)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    known = ", ".join(STUDY_MODULES)
    assert known.startswith("experiment, barn, continuity, generalisation, ")
    assert lines[0] == f"skidnav: error: {tmp_path}: holds 'nope' results; known kinds: {known}"
    assert not (tmp_path / "report.html").exists()
