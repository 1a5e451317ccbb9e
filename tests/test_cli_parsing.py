"""The command line's own parsing: every argument error is one line with exit code 2, and a
subcommand imports only its own module."""

from __future__ import annotations

import subprocess
import sys

import pytest

from skidnav.cli import COMMANDS, main, requested_modules


@pytest.mark.parametrize(
    ("argv", "line"),
    [
        (["nosuch"], "skidnav: error: argument command: invalid choice: 'nosuch'"),
        (["run"], "skidnav: error: run: the following arguments are required: config"),
        (["run", "c.toml", "--jobs", "two"], "skidnav: error: run: argument --jobs"),
        (
            ["world", "map", "generate", "--kind", "nope"],
            "skidnav: error: world map generate: argument --kind",
        ),
        (["robot", "run", "--bogus"], "skidnav: error: robot run: "),
        (["robot", "sim-server"], "skidnav: error: robot sim-server: the following arguments"),
    ],
)
def test_an_argument_error_is_one_line(
    argv: list[str], line: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as leave:
        main(argv)
    assert leave.value.code == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(line), captured.err
    assert captured.out == ""


@pytest.mark.parametrize(
    ("argv", "usage", "line"),
    [
        (
            [],
            "usage: skidnav [-h]",
            "skidnav: error: the following arguments are required: command",
        ),
        (["camera"], "usage: skidnav camera [-h]", "skidnav: error: camera: the following"),
        (["study"], "usage: skidnav study [-h]", "skidnav: error: study: the following"),
    ],
)
def test_a_command_group_without_its_verb_shows_its_usage_then_the_error(
    argv: list[str], usage: str, line: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as leave:
        main(argv)
    assert leave.value.code == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert lines[0].startswith(usage) and lines[-1].startswith(line)
    verbs = {"": "run,report,tune,study", "camera": "calibrate", "study": "continuity"}
    assert verbs[" ".join(argv)] in " ".join(lines[:-1])  # the usage lists the verbs
    assert len(lines) <= 4


def test_only_the_named_subcommand_is_imported() -> None:
    assert requested_modules(["-v", "robot", "sim-server"]) == {"robot": "skidnav.commands.robot"}
    assert requested_modules(["study", "continuity", "x.toml"]) == {
        "study": {"continuity": "skidnav.commands.continuity"}
    }
    assert requested_modules(["study", "--help"]) == {"study": COMMANDS["study"]}
    assert requested_modules(["--help"]) == COMMANDS
    assert requested_modules(["nosuch"]) == COMMANDS
    probe = (
        "import sys; from skidnav.cli import build_parser, requested_modules;"
        "build_parser(requested_modules(['robot', 'sim-server']));"
        "print(sorted(m for m in ('cv2', 'sklearn', 'matplotlib') if m in sys.modules))"
    )
    result = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True, timeout=120
    )
    assert result.stdout.strip() == "[]"


def test_help_still_lists_every_subcommand(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as leave:
        main(["--help"])
    assert leave.value.code == 0
    listing = capsys.readouterr().out
    assert all(name in listing for name in COMMANDS)
    assert len(COMMANDS) <= 8


@pytest.mark.parametrize("group", ["study", "world"])
def test_a_group_lists_its_verbs(group: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as leave:
        main([group, "--help"])
    assert leave.value.code == 0
    listing = capsys.readouterr().out
    verbs = COMMANDS[group]
    assert isinstance(verbs, dict)
    assert all(verb in listing for verb in verbs)
