"""A study's results directory is the experiment runner's: Ctrl-C keeps the finished runs and
the next call runs the others, all-or-nothing files on a full disk, stale temporaries removed,
one writer at a time, a damaged run file named in one line."""

from __future__ import annotations

import signal
import subprocess
import sys
from pathlib import Path

import pytest

from skidnav.cli import main
from skidnav.experiments.lock import directory_lock
from skidnav.studies.hardware.study import load_study, run_study
from tests.realtime.realtime_helpers import cli_env, wait_for
from tests.realtime.test_study import fake_realtime, study_config
from tests.saved_file_support import skidnav_with_full_disk


def _finished_study(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> tuple[Path, list[str]]:
    """(out, command line) of a study whose four runs are finished (by a stand-in for the
    real-time run: a second call with the same command line runs nothing)."""
    config, out = study_config(tmp_path), tmp_path / "study"
    monkeypatch.setattr("skidnav.studies.hardware.trial.realtime_run", fake_realtime([]))
    grid, text = load_study(config, {"episodes": 2})
    assert run_study(grid, out, source_text=text).finished == 4
    argv = ["robot", "study", "--config", str(config), "--episodes", "2", "--quiet"]
    return out, [*argv, "--out", str(out)]


def _one_error_line(stderr: str) -> str:
    errors = [line for line in stderr.splitlines() if line.startswith("skidnav: error: ")]
    assert len(errors) == 1 and "Traceback" not in stderr, stderr[-2000:]
    return errors[0]


def _dead_pid() -> int:
    process = subprocess.Popen([sys.executable, "-c", "pass"])
    process.wait()
    return process.pid


def test_study_files_are_kept_whole_when_the_disk_fills(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out, argv = _finished_study(tmp_path, monkeypatch)
    (out / "study.md").write_text("the previous report\n")
    tables = {name: (out / name).read_bytes() for name in ("summaries.csv", "metadata.json")}
    result = skidnav_with_full_disk(argv, max_file_bytes=600)  # every table is larger
    assert result.returncode == 2
    line = _one_error_line(result.stderr)
    assert line.startswith(f"skidnav: error: {out}") and "(File too large)" in line, line
    assert (out / "study.md").read_text() == "the previous report\n"  # not a torn new one
    assert {name: (out / name).read_bytes() for name in tables} == tables
    assert not list(out.rglob("*.tmp"))


def test_stale_temporaries_are_removed_and_a_second_writer_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    out, argv = _finished_study(tmp_path, monkeypatch)
    pid = _dead_pid()
    stale = [out / f".study.md.{pid}-0123abcd.tmp", out / "runs" / f".run-000001.npz.{pid}.tmp"]
    for path in stale:
        path.write_text("left by a killed study")
    with directory_lock(out):  # another process writing there
        assert main(argv) == 2
    assert "in use by another skidnav process" in capsys.readouterr().err
    assert all(path.exists() for path in stale)
    assert main(argv) == 0
    assert "4 of 4 runs finished (0 run now, 4 done before)" in capsys.readouterr().out
    assert not any(path.exists() for path in stale)


def test_a_damaged_run_file_is_named_in_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    out, argv = _finished_study(tmp_path, monkeypatch)
    damaged = out / "runs" / "run-000002.npz"
    damaged.write_bytes(b"not a zip archive")
    report = (out / "study.md").read_bytes()
    assert main(argv) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert line.startswith(f"skidnav: error: {damaged}") and len(line) < len(str(damaged)) + 150
    assert (out / "study.md").read_bytes() == report


def test_ctrl_c_keeps_the_finished_runs_and_the_next_call_runs_the_others(tmp_path: Path) -> None:
    config, out = study_config(tmp_path), tmp_path / "study"
    argv = ["robot", "study", "--config", str(config), "--agents", "q-learning", "--quiet"]
    argv += ["--episodes", "2", "--out", str(out)]
    study = subprocess.Popen(
        [sys.executable, "-m", "skidnav.cli", *argv],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=cli_env(),
    )  # fmt: skip
    second = out / "runs" / "q-learning" / "slippery-drifting" / "seed-0" / "run.jsonl"
    wait_for(lambda: second.exists() and "transition" in second.read_text(), 120, "run 2")
    study.send_signal(signal.SIGINT)  # in the middle of the second run
    stdout, stderr = study.communicate(timeout=60)
    assert study.returncode == 130, stderr[-2000:]
    assert "1 of 2 runs finished (1 run now, 0 done before)" in stdout
    assert (out / "runs" / "run-000000.npz").exists()
    assert not (out / "runs" / "run-000001.npz").exists()
    assert "| q-learning | rough-stationary | 1 | 2 |" in (out / "study.md").read_text()
    interrupted = (out / "study.md").read_text()
    assert "slippery-drifting" not in interrupted

    result = subprocess.run(
        [sys.executable, "-m", "skidnav.cli", *argv],
        capture_output=True, text=True, env=cli_env(), timeout=300,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr[-2000:]
    assert "2 of 2 runs finished (1 run now, 1 done before)" in result.stdout
    assert second.read_text().count('"event": "episode_start"') == 2  # started over, not appended
    assert "| q-learning | slippery-drifting | 1 | 2 |" in (out / "study.md").read_text()
