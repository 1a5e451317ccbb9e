"""Arguments of ``skidnav run``, ``tune`` and ``report`` that name the wrong thing: one line,
exit code 2, nothing written."""

from __future__ import annotations

from pathlib import Path

import pytest

from skidnav.cli import main
from skidnav.experiments.report import html
from tests.cli_support import exit_code


@pytest.mark.parametrize("command", ["run", "tune"])
def test_a_device_or_a_huge_config_is_refused(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out, huge = tmp_path / "out", tmp_path / "huge.toml"
    huge.write_bytes(b"#" * 4_000_001)
    for config, problem in [
        ("/dev/zero", "cannot read config file (a character device, not a regular file)"),
        (str(huge), "config file larger than 4,000,000 bytes"),
    ]:
        assert main([command, config, "--out", str(out), "--backend", "serial"]) == 2
        lines = capsys.readouterr().err.strip().splitlines()
        assert lines == [f"skidnav: error: {config}: {problem}"]
    assert not out.exists()


def test_a_config_that_is_not_text_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config = tmp_path / "binary.toml"
    config.write_bytes(b"\xff\xfe\x00[experiment]")
    assert main(["run", str(config), "--out", str(tmp_path / "out")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert lines == [f"skidnav: error: {config}: cannot read config (UnicodeDecodeError)"]


def test_a_report_into_a_missing_folder_is_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(
        html, "render_report", lambda run_dir, sections=(), progress=False: ("<p>report</p>", "")
    )
    target = tmp_path / "missing" / "r.html"
    assert main(["report", str(tmp_path), "-o", str(target)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert lines == [
        f"skidnav: error: {target}: cannot write there (no directory {target.parent}); choose "
        "another --output"
    ]
    assert sorted(tmp_path.iterdir()) == []
    assert main(["report", str(tmp_path), "-o", str(tmp_path)]) == 2  # a directory
    assert "a directory, not a file; choose another --output" in capsys.readouterr().err
    assert sorted(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "arguments",
    [
        ["run", "{config}", "--out", "{out}", "--tensorboard", ""],
        ["run", "{config}", "--out", ""],
        ["tune", "{config}", "--out", ""],
        ["report", ""],
        ["world", "simulate", "--random", "1", "--out", ""],
    ],
)
def test_an_empty_path_is_refused_not_taken_for_the_working_directory(
    arguments: list[str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.chdir(tmp_path)
    filled = [a.format(config=tmp_path / "c.toml", out=tmp_path / "out") for a in arguments]
    assert exit_code(filled) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].endswith("expected a path, got an empty one"), lines
    assert list(tmp_path.iterdir()) == []
