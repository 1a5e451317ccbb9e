"""The command line's version, and help that says what each command accepts."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import skidnav
from skidnav.cli import COMMANDS, build_parser, main
from skidnav.commands.verbs import HELP
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


HEAVY = ("numba", "pandas", "matplotlib", "gymnasium", "numpy", "scipy", "pyarrow", "tqdm")
"""Modules ``skidnav --help`` and ``--version`` must not import: seconds between them."""


@pytest.mark.parametrize("flag", ["--help", "--version"])
def test_help_and_version_import_nothing_heavy(flag: str) -> None:
    script = (
        "import sys\nfrom skidnav.cli import main\n"
        f"try:\n    main([{flag!r}])\nexcept SystemExit:\n    pass\n"
        f"print('imported:', *sorted(set({HEAVY!r}) & set(sys.modules)))"
    )
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60,
        env={**os.environ, "PYTHONPATH": str(ROOT / "src")},
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[-1] == "imported:", result.stdout


def test_the_listing_names_every_verb_and_group_with_its_help(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with pytest.raises(SystemExit):
        main(["--help"])
    listing = " ".join(capsys.readouterr().out.split())
    for name, line in HELP.items():
        assert f"{name} {' '.join(line.split())}" in listing
    assert list(HELP) == list(COMMANDS)


@pytest.mark.parametrize("order", ["skidnav first", "gymnasium first"])
def test_the_envs_are_registered_whichever_is_imported_first(order: str) -> None:
    imports = ["import skidnav", "import gymnasium"]
    script = ";".join([*imports[:: 1 if order == "skidnav first" else -1],
                       "print(gymnasium.spec('skidnav/SkidSteerNav-v0').id)"])  # fmt: skip
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60,
        env={**os.environ, "PYTHONPATH": str(ROOT / "src")},
    )  # fmt: skip
    assert result.stdout.strip() == "skidnav/SkidSteerNav-v0", result.stderr
