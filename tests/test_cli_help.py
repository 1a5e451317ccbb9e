"""The command line's version, and help that says what each command accepts."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import pytest

import skidnav
from skidnav.cli import build_parser, main
from skidnav.experiments.provenance import skidnav_version
from skidnav.robot.slip import SLIP_PRESETS

ROOT = Path(__file__).resolve().parents[1]


def test_version_prints_the_installed_version(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as leave:
        main(["--version"])
    assert leave.value.code == 0
    assert capsys.readouterr().out == f"skidnav {skidnav_version()}\n"


def test_one_version_in_pyproject_the_package_and_the_changelog() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    changelog = (ROOT / "CHANGELOG.md").read_text()
    releases = re.findall(r"^## \[(\d+\.\d+\.\d+)\] - \d{4}-\d{2}-\d{2}$", changelog, re.M)
    assert project["version"] == skidnav.__version__ == releases[0]
    assert changelog.index("## [Unreleased]") < changelog.index(f"## [{releases[0]}]")


def test_a_reproduce_target_has_its_own_help(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["study", "reproduce", "sutton-barto", "--help"])
    help_text = capsys.readouterr().out
    assert help_text.startswith("usage: skidnav study reproduce sutton-barto [-h]")
    assert "Examples 8.1" in help_text and "--runs" in help_text


def test_the_sim_server_help_lists_every_slip_preset_it_accepts(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with pytest.raises(SystemExit):
        main(["robot", "sim-server", "--help"])
    # argparse wraps lines after hyphens ("rough-" / "physics"): join those back
    flat = " ".join(capsys.readouterr().out.split()).replace("- ", "-")
    assert f"slip preset: {', '.join(SLIP_PRESETS)}" in flat
    parser = build_parser()
    for preset in SLIP_PRESETS:
        args = parser.parse_args(["robot", "sim-server", "--port", "0", "--slip", preset])
        assert args.slip == preset
