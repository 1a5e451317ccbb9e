"""Every command that writes checks where before it works: an output path that cannot be written
is one line at once, the command's work never starts, nothing is created. A full disk that a
writer did not report itself is one line too (tests/experiments/test_full_disk.py: ``skidnav
run``)."""

from __future__ import annotations

import errno
import re
from pathlib import Path
from typing import Any

import pytest

from skidnav.cli import main
from skidnav.errors import UserError
from skidnav.files.outputs import check_output_dir, check_output_file
from tests.experiments.exp_support import TINY_TOML
from tests.saved_file_support import listing

REPOSITORY = Path(__file__).resolve().parents[2]
REALTIME = REPOSITORY / "configs" / "realtime.toml"

COMMANDS: dict[str, tuple[list[str], str]] = {
    # name: (arguments, {out} the output, the function that starts the work)
    "run": (["run", "{config}", "--out", "{dir}"], "skidnav.studies.loading.run_experiment"),
    "tune": (["tune", "{tune}", "--out", "{dir}"], "skidnav.studies.tuning.search.tune_experiment"),
    "generalise": (
        ["study", "generalise", "--out", "{dir}"],
        "skidnav.studies.loading.run_experiment",
    ),
    "transfer": (["study", "transfer", "--out", "{dir}"], "skidnav.studies.loading.run_experiment"),
    "floors calibrate": (
        ["world", "floors", "calibrate", "--out", "{file}"],
        "skidnav.physics.calibration.calibrate",
    ),
    "continuity": (
        ["study", "continuity", "--out", "{dir}"],
        "skidnav.studies.loading.run_experiment",
    ),
    "search": (["study", "search", "--out", "{dir}"], "skidnav.studies.loading.run_experiment"),
    "kinematic compare": (
        ["study", "kinematic", "compare", "--out", "{dir}"],
        "skidnav.studies.loading.run_experiment",
    ),
    "reproduce": (
        ["study", "reproduce", "sutton-barto", "--out", "{dir}"],
        "skidnav.studies.loading.run_experiment",
    ),
    "map generate": (
        ["world", "map", "generate", "--out", "{file}"],
        "skidnav.commands.map.generate_map",
    ),
    "map show": (
        ["world", "map", "show", "{map}", "--png", "{file}"],
        "skidnav.commands.map.load_map",
    ),
    "simulate --out": (
        ["world", "simulate", "--out", "{file}"],
        "skidnav.commands.simulate._make_env",
    ),
    "simulate --csv": (
        ["world", "simulate", "--out", "{tmp}/t.png", "--csv", "{file}"],
        "skidnav.commands.simulate._make_env",
    ),
    "report": (
        ["report", "{tmp}", "--output", "{file}"],
        "skidnav.experiments.report.html.write_report",
    ),
    "camera calibrate": (
        ["camera", "calibrate", "--source", "0", "--out", "{file}"],
        "skidnav.commands.camera_actions.open_frames",
    ),
    "camera intrinsics": (
        ["camera", "intrinsics", "--images", "{tmp}", "--out", "{file}"],
        "skidnav.commands.camera_actions.read_images",
    ),
    "camera board": (
        ["camera", "board", "--out", "{file}"],
        "skidnav.realtime.camera.intrinsics.CharucoBoardSpec.image",
    ),
    "camera markers": (
        ["camera", "markers", "--out", "{dir}"],
        "skidnav.realtime.camera.opencv.cv2.aruco.generateImageMarker",
    ),
    "robot run": (
        ["robot", "run", "--agent", "q-learning", "--out", "{dir}"],
        "skidnav.realtime.control.run.run_robot",
    ),
    "robot study": (
        ["robot", "study", "--config", str(REALTIME), "--out", "{dir}"],
        "skidnav.studies.hardware.study.run_study",
    ),
}


def _work_started(*args: Any, **kwargs: Any) -> None:
    raise AssertionError("the command started its work before checking its output")


@pytest.fixture
def inputs(tmp_path: Path) -> dict[str, str]:
    """The files the commands read, and a regular file ``blocker`` where a directory should be."""
    from tests.experiments.test_tune import TINY_TUNE

    (tmp_path / "tiny.toml").write_text(TINY_TOML)
    (tmp_path / "tune.toml").write_text(TINY_TUNE)
    assert (
        main(["world", "map", "generate", "--kind", "free", "--out", str(tmp_path / "m.txt")]) == 0
    )
    (tmp_path / "blocker").write_text("a file, not a directory\n")
    return {
        "config": str(tmp_path / "tiny.toml"),
        "tune": str(tmp_path / "tune.toml"),
        "map": str(tmp_path / "m.txt"),
        "tmp": str(tmp_path),
        "dir": str(tmp_path / "blocker" / "results"),
        "file": str(tmp_path / "blocker" / "out.csv"),
    }


@pytest.mark.parametrize("command", COMMANDS)
def test_an_output_that_cannot_be_written_is_refused_before_the_work(
    command: str,
    inputs: dict[str, str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    arguments, work = COMMANDS[command]
    monkeypatch.setattr(work, _work_started)
    capsys.readouterr()
    before = listing(tmp_path)
    assert main([argument.format(**inputs) for argument in arguments]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    blocker = tmp_path / "blocker"
    assert f"cannot write there ({blocker} is not a directory); choose another" in lines[0]
    assert listing(tmp_path) == before


def test_output_checks(tmp_path: Path) -> None:
    (tmp_path / "file").write_text("")
    (tmp_path / "folder").mkdir()
    assert check_output_file(tmp_path / "new.csv") == tmp_path / "new.csv"
    assert check_output_file(tmp_path / "a" / "b" / "new.png", parents=True)
    assert check_output_dir(tmp_path / "a" / "b") == tmp_path / "a" / "b"
    assert check_output_dir(tmp_path / "folder")
    problems = {
        "a directory, not a file": lambda: check_output_file(tmp_path / "folder"),
        "(no directory ": lambda: check_output_file(tmp_path / "a" / "new.csv"),
        "file: not a directory": lambda: check_output_dir(tmp_path / "file"),
        "file is not a directory)": lambda: check_output_dir(tmp_path / "file" / "x" / "y"),
        "; choose another --png": lambda: check_output_file(tmp_path / "folder", "--png"),
    }
    for message, check in problems.items():
        with pytest.raises(UserError, match=re.escape(message)):
            check()
    assert not (tmp_path / "a").exists()  # nothing created


def test_a_full_disk_a_writer_did_not_report_is_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def full(*args: Any, **kwargs: Any) -> None:
        raise OSError(errno.ENOSPC, "No space left on device", "/data/journal.log")

    monkeypatch.setattr("skidnav.commands.map.generate_map", full)
    assert main(["world", "map", "generate"]) == 2
    assert capsys.readouterr().err.strip() == (
        "skidnav: error: /data/journal.log: cannot write (No space left on device)"
    )

    def broken(*args: Any, **kwargs: Any) -> None:
        raise OSError(errno.EIO, "Input/output error")

    monkeypatch.setattr("skidnav.commands.map.generate_map", broken)
    with pytest.raises(OSError, match="Input/output error"):  # not the user's to fix
        main(["world", "map", "generate"])
