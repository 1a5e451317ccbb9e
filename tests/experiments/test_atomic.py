"""Nothing half-written: atomic writes that fail leave the old file and no temporary, stale
temporaries of dead writers are removed, and one process at a time writes a results directory
(a second is refused naming the holder; a SIGKILLed holder's lock is taken over)."""

from __future__ import annotations

import errno
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from skidnav.cli import main
from skidnav.experiments.lock import LOCK_FILE, directory_lock
from skidnav.experiments.report import html
from skidnav.experiments.store import ResultStore
from skidnav.files.atomic import remove_stale_temporaries, write_atomic
from tests.experiments.exp_support import cli_command, cli_env


def _dead_pid() -> int:
    """The pid of a process that has ended (and been reaped)."""
    process = subprocess.Popen([sys.executable, "-c", "pass"])
    process.wait()
    return process.pid


def _fail(*args: object) -> None:
    raise OSError(errno.ENOSPC, "No space left on device")


@pytest.mark.parametrize(
    ("step", "error"), [("fsync", OSError), ("replace", OSError), ("replace", KeyboardInterrupt)]
)
def test_a_failed_atomic_write_leaves_the_old_file_and_no_temporary(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, step: str, error: type[BaseException]
) -> None:
    target = tmp_path / "table.csv"
    target.write_bytes(b"old,complete\n")

    def broken(*args: object) -> None:
        raise error("interrupted mid-write")

    monkeypatch.setattr(os, step, broken)
    with pytest.raises(error):
        write_atomic(target, b"new" * 100_000)
    monkeypatch.undo()
    assert target.read_bytes() == b"old,complete\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table.csv"]
    write_atomic(target, b"new\n")
    assert target.read_bytes() == b"new\n" and len(list(tmp_path.iterdir())) == 1


def test_only_temporaries_of_dead_writers_are_removed(tmp_path: Path) -> None:
    dead = _dead_pid()
    names = {
        "dead": f".report.html.{dead}-0a1b2c3d.tmp",
        "dead-other-target": f".summaries.csv.{dead}-0a1b2c3d.tmp",
        "old-format": f".metadata.json.{dead}.tmp",
        "alive": f".report.html.{os.getpid()}-0a1b2c3d.tmp",
        "not-ours": "notes.tmp",
    }
    for name in names.values():
        (tmp_path / name).write_text("partial")
    assert remove_stale_temporaries(tmp_path, "report.html") == 1
    assert not (tmp_path / names["dead"]).exists()
    assert remove_stale_temporaries(tmp_path) == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([names["alive"], "notes.tmp"])


def test_a_report_failing_mid_write_keeps_the_previous_one(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    run_dir = tmp_path / "results"
    run_dir.mkdir()
    report = run_dir / "report.html"
    report.write_text("<html>previous report</html>")
    stale = run_dir / f".report.html.{_dead_pid()}-00000000.tmp"
    stale.write_text("<html>half")
    # The writing is under test, not the (slow) analysis: a large report built instantly.
    monkeypatch.setattr(
        html,
        "render_report",
        lambda run_dir, sections=(), progress=False: ("<p>new</p>" * 10**6, ""),
    )
    monkeypatch.setattr(os, "fsync", _fail)
    assert main(["report", str(run_dir)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert lines == [f"skidnav: error: {report}: cannot write the report (No space left on device)"]
    assert report.read_text() == "<html>previous report</html>"
    assert sorted(p.name for p in run_dir.iterdir()) == ["report.html"]  # the stale one went too
    monkeypatch.undo()
    monkeypatch.setattr(
        html, "render_report", lambda run_dir, sections=(), progress=False: ("<p>new</p>", "")
    )
    assert main(["report", str(run_dir)]) == 0
    assert report.read_text() == "<p>new</p>" and len(list(run_dir.iterdir())) == 1


def test_out_naming_a_file_is_one_line(
    tiny_config_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "results.txt"
    path.write_text("not a directory")
    for command in ("run", "tune"):
        config = tiny_config_file if command == "run" else _tune_config(tmp_path)
        assert main([command, str(config), "--out", str(path), "--backend", "serial"]) == 2
        lines = capsys.readouterr().err.strip().splitlines()
        assert lines == [f"skidnav: error: {path}: not a directory; choose another --out"]
        assert path.read_text() == "not a directory"


def _tune_config(tmp_path: Path) -> Path:
    from tests.experiments.test_tune import TINY_TUNE

    path = tmp_path / "tune.toml"
    path.write_text(TINY_TUNE)
    return path


def test_a_directory_in_use_is_refused_naming_the_holder(
    tiny_config_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "busy"
    with directory_lock(out):
        assert (out / LOCK_FILE).read_text() == f"{os.getpid()}\n"
        for command, config in (("run", tiny_config_file), ("tune", _tune_config(tmp_path))):
            assert main([command, str(config), "--out", str(out), "--backend", "serial"]) == 2
            lines = capsys.readouterr().err.strip().splitlines()
            assert len(lines) == 1 and f"process (pid {os.getpid()})" in lines[0], lines
        assert sorted(p.name for p in out.iterdir()) == [LOCK_FILE]  # the refused wrote nothing
    assert not out.exists()  # made for the lock only, removed with it


def _wait_for_lock_holder(lock: Path, process: subprocess.Popen[str], timeout: float) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if lock.exists() and lock.read_text().strip() == str(process.pid):
            return
        if process.poll() is not None:
            pytest.fail(f"the holder ended early: {process.communicate()[1][-2000:]}")
        time.sleep(0.02)
    pytest.fail("the holder never took the lock")


def test_a_second_run_is_refused_and_a_killed_holders_lock_is_taken_over(
    tiny_config_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "shared"
    args = ["run", str(tiny_config_file), "--out", str(out), "--backend", "serial", "--no-progress"]
    holder = subprocess.Popen(
        cli_command(*args), env=cli_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        _wait_for_lock_holder(out / LOCK_FILE, holder, timeout=120)
        os.kill(holder.pid, signal.SIGSTOP)  # frozen while holding the lock
        assert main(args) == 2
        lines = capsys.readouterr().err.strip().splitlines()
        assert lines == [
            f"skidnav: error: {out}: in use by another skidnav process (pid {holder.pid}); "
            "wait for it to finish or choose another --out"
        ]
    finally:
        holder.kill()
        holder.communicate()
    assert holder.returncode == -signal.SIGKILL
    stale = [
        out / f".metadata.json.{holder.pid}-5e5e5e5e.tmp",
        out / "runs" / f".r.{holder.pid}.tmp",
    ]
    for path in stale:
        path.write_text("cut short by the kill")
    assert main(args) == 0  # the dead holder's lock is taken over; its runs are kept
    assert "8 runs in" in capsys.readouterr().out
    assert not any(path.exists() for path in stale)
    assert len(ResultStore(out).finished()) == 8
    assert not list(out.rglob("*.tmp"))
