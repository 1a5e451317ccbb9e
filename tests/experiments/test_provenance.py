"""Which code produced which runs: run-file records, the resume warning, the list of sessions."""

from __future__ import annotations

import json
import logging
import shutil
from pathlib import Path

import pytest

import skidnav
from skidnav.experiments import dask_backend, runner
from skidnav.experiments.configfile import parse_config
from skidnav.experiments.provenance import (
    CODE_KEYS,
    code_version,
    describe_code,
    git_commit,
    source_digest,
)
from skidnav.experiments.report.html import build_report
from skidnav.experiments.store import ResultStore
from tests.experiments.exp_support import TINY_TOML

OLD_CODE = {
    "version": "0.0.9",
    "commit": "0123456789abcdef0123456789abcdef01234567",
    "dirty": True,
    "source_sha256": "f" * 64,
    "session": "2000-01-01T00:00:00+00:00",
}


def test_code_version_names_this_code(tmp_path: Path) -> None:
    code = code_version()
    assert tuple(code) == CODE_KEYS
    assert code["version"] == skidnav.__version__
    assert code["commit"] == git_commit()
    assert code["dirty"] in (True, False, None)
    package = tmp_path / "pkg"
    (package / "sub").mkdir(parents=True)
    (package / "a.py").write_text("x = 1\n")
    (package / "sub" / "b.py").write_text("y = 2\n")
    before = source_digest(package)
    assert source_digest(package) == before
    (package / "sub" / "b.py").write_text("y = 3\n")
    assert source_digest(package) != before
    assert describe_code(OLD_CODE) == (
        "skidnav 0.0.9, commit 0123456789 (dirty), source ffffffffff"
    )


def test_every_run_records_its_code_and_session(serial_results: Path) -> None:
    store = ResultStore(serial_results)
    sessions = store.metadata()["sessions"]
    started = {entry["started"] for entry in sessions}
    codes = [store.run_code(run_id) for run_id in sorted(store.finished())]
    assert all(code == codes[0] for code in codes)  # one session wrote them all
    assert set(codes[0]) == {*CODE_KEYS, "session"} and codes[0]["session"] in started
    assert codes[0]["version"] == skidnav.__version__ and len(codes[0]["source_sha256"]) == 64
    assert sum(entry["runs_done"] for entry in sessions) == 8
    assert all(entry["completed"] for entry in sessions)
    assert sessions[0]["runs_done"] == 8 and sessions[0]["runs_from_other_code"] == 0


def test_resume_warns_about_runs_from_other_code(
    serial_results: Path,
    tmp_path: Path,
    caplog: pytest.LogCaptureFixture,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    out = tmp_path / "mixed"
    shutil.copytree(serial_results, out)
    (out / "metadata.json").write_text(json.dumps({"last_session": {"started": "1999"}}))
    store = ResultStore(out)
    # This session runs the code that wrote the fixture (the tree may change during the tests).
    fixture_code = {key: store.run_code("run-000005")[key] for key in CODE_KEYS}
    monkeypatch.setattr(runner, "code_version", lambda: dict(fixture_code))
    for run_id in ("run-000000", "run-000001", "run-000002"):  # "written by older code"
        store.write_run(store.read_run(run_id), OLD_CODE)
    for run_id in ("run-000006", "run-000007"):  # "killed before these were written"
        store.run_path(run_id).unlink()
    with caplog.at_level(logging.WARNING, logger="skidnav.experiments.runner"):
        outcome = runner.run_experiment(parse_config(TINY_TOML), out, backend="serial")
    assert outcome.executed == 2
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 1
    assert "3 of 6 finished runs were produced by other code" in warnings[0]
    assert "3 × skidnav 0.0.9, commit 0123456789 (dirty)" in warnings[0]

    sessions = store.metadata()["sessions"]
    assert [entry["started"] for entry in sessions[:2]] == ["1999", OLD_CODE["session"]]
    legacy, killed, original, now = sessions  # the fixture's own session: from its run files
    assert legacy["runs_done"] == 0
    assert original["completed"] is False and original["runs_done"] == 3
    assert killed["completed"] is False and killed["runs_done"] == 3
    assert killed["commit"] == OLD_CODE["commit"] and killed["version"] == "0.0.9"
    assert now["completed"] is True and now["runs_done"] == 2
    assert now["runs_from_other_code"] == 3 and "3 of 6" in now["warning"]
    assert sum(entry.get("runs_done", 0) for entry in sessions) == 8
    assert "produced by 2 different code versions" in build_report(out)


def test_unreachable_scheduler_creates_no_directory(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("distributed")
    monkeypatch.setattr(dask_backend, "DASK_CONNECT_TIMEOUT", "1s")
    out = tmp_path / "out"
    with pytest.raises(runner.UserError, match="cannot connect to Dask scheduler"):
        runner.run_experiment(
            parse_config(TINY_TOML), out, backend="dask", scheduler="tcp://127.0.0.1:9"
        )
    assert not out.exists()
