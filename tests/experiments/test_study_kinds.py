"""The registry of study kinds (``skidnav.studies.kind``) and the kind of a results directory,
by which ``skidnav report`` chooses the report."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from skidnav.cli import main
from skidnav.errors import CorruptFileError
from skidnav.experiments.store import results_kind
from skidnav.studies.gap import gap_section
from skidnav.studies.kind import STUDY_MODULES, experiment_sections, study


@pytest.mark.parametrize("kind", sorted(STUDY_MODULES))
def test_every_study_is_found_by_its_kind_and_writes_results_of_that_kind(kind: str) -> None:
    chosen = study(kind)
    assert chosen.kind == kind == chosen.layout.kind
    assert set(chosen.backends) <= {"serial", "process", "dask"}


def test_the_hardware_study_runs_serially_and_the_continuity_study_anywhere() -> None:
    assert study("robot-study").backends == ("serial",)
    assert study("continuity").backends == ("serial", "process", "dask")


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
    known = ", ".join(["experiment", *sorted(STUDY_MODULES)])
    assert lines[0] == f"skidnav: error: {tmp_path}: holds 'nope' results; known kinds: {known}"
    assert not (tmp_path / "report.html").exists()
