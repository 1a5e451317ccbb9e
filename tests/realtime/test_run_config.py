"""``skidnav robot run`` refuses a config, a secret or a command line it cannot take as meant, in
one line and before any link opens: every table checked (unknown keys, types, ranges) whatever
the driver, no secret in a config file, a secret named but unusable never a plain link, no
abbreviated option, and an authentication refusal said once."""

from __future__ import annotations

import argparse
import socket
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from skidnav.cli import build_parser
from skidnav.realtime.reference_robot import cli as reference_cli
from tests.cli_support import exit_code
from tests.realtime.realtime_helpers import ServerThread, cli_env, write_config

SECRET = "the lab's shared secret, 33 bytes"
TCP_KEYS = "expected one of host, port, secret_file, lockstep)"


def one_error_line(capsys: pytest.CaptureFixture[str]) -> str:
    """The one line a refused command printed (nothing on standard output)."""
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and captured.out == "", captured
    return lines[0]


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        (
            '[tcp]\nsecret_fle = "robot.key"\n',
            "unknown key 'secret_fle' in {config}: [tcp] (did you mean 'secret_file'? " + TCP_KEYS,
        ),
        ('[tcp]\nport = "abc"\n', "expected port to be an integer, got 'abc' in {config}: [tcp]"),
        (
            "[tcp]\nport = 70000\n",
            "expected port to be an integer in [1, 65535], got 70000 in {config}: [tcp]",
        ),
        ("[tcp]\nport = true\n", "expected port to be an integer, got True in {config}: [tcp]"),
        (
            '[tcp]\nlockstep = "yes"\n',
            "expected lockstep to be true or false, got 'yes' in {config}: [tcp]",
        ),
        ('[tcp]\nhost = ""\n', "expected host to be a non-empty string, got '' in {config}: [tcp]"),
        (
            '[tcp]\nsecret_file = ""\n',
            "expected secret_file to be a non-empty string, got '' in {config}: [tcp]",
        ),
        (
            "[serial]\nlockstep = 1\n",
            "expected lockstep to be true or false, got 1 in {config}: [serial]",
        ),
        (
            "[serial]\nbaudrate = 0\n",
            "expected baudrate to be an integer >= 1, got 0 in {config}: [serial]",
        ),
        (
            "[serial]\nbaud = 9600\n",
            "unknown key 'baud' in {config}: [serial] (did you mean 'baudrate'? expected one "
            "of url, ",
        ),
        (
            '[sim]\nlockstep = "yes"\n',
            "expected lockstep to be true or false, got 'yes' in {config}: [sim]",
        ),
        (
            '[sim]\nlatency = "0.1"\n',
            "expected latency to be a number, got '0.1' in {config}: [sim]",
        ),
        ('[ros2]\nport = "abc"\n', "expected port to be an integer, got 'abc' in {config}: [ros2]"),
        (
            '[ros2]\nstamped = "yes"\n',
            "expected stamped to be true or false, got 'yes' in {config}: [ros2]",
        ),
        (
            "[ros2]\nsecret_file = 3\n",
            "unknown key 'secret_file' in {config}: [ros2] (expected one of host, ",
        ),
        (
            "[presets.lab.tcp]\nprot = 5757\n",
            "unknown key 'prot' in {config}: preset 'lab': [tcp] (did you mean 'port'? " + TCP_KEYS,
        ),
    ],
)
def test_every_table_is_checked_whatever_the_driver(
    text: str, problem: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config, out = write_config(tmp_path, text), tmp_path / "out"
    argv = ["robot", "run", "--policy", "goal-tracker", "--config", str(config), "--out", str(out)]
    assert exit_code(argv) == 2  # the sim driver, which reads none of [tcp] …, and no preset
    assert one_error_line(capsys).startswith(f"skidnav: error: {problem.format(config=config)}")
    assert not out.exists()


@pytest.mark.parametrize("table", ["tcp", "serial", "sim", "run", "presets.lab.tcp", "agents.x"])
def test_a_secret_in_the_config_is_refused_without_showing_it(
    table: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config = write_config(tmp_path, f'[{table}]\nsecret = "{SECRET}"\n')
    argv = ["robot", "run", "--driver", "tcp", "--policy", "goal-tracker"]
    assert exit_code([*argv, "--config", str(config), "--out", str(tmp_path / "out")]) == 2
    line = one_error_line(capsys)
    assert line.startswith(
        "skidnav: error: key 'secret': a link secret does not belong in a config file "
        f"in {config}: [{table}] (put it in a file only you can read"
    )
    assert "secret_file in [tcp] or [serial], or set SKIDNAV_LINK_SECRET" in line
    assert SECRET not in line and "shared" not in line


@pytest.fixture
def listener() -> Iterator[socket.socket]:
    """A loopback TCP port that only listens: a connection to it waits in its backlog."""
    with socket.create_server(("127.0.0.1", 0)) as server:
        server.settimeout(0.0)
        yield server


def connected(server: socket.socket) -> bool:
    """Whether anything connected to ``server`` (accepted and closed here)."""
    try:
        peer, _ = server.accept()
    except BlockingIOError:
        return False
    peer.close()
    return True


SECRET_PROBLEMS = [  # (table lines, file contents or None for no file, the environment, line)
    ('secret_fle = "{key}"', SECRET, None, "unknown key 'secret_fle'"),
    ('secret_file = "{key}"', None, None, "{key}: no such secret file"),
    (
        'secret_file = "{key}"',
        "",
        None,
        "{key}: expected a link secret of at least 16 bytes, got 0",
    ),
    ('secret_file = "{key}"', "short\n", None, "{key}: expected a link secret of at least 16"),
    ("", None, "", "SKIDNAV_LINK_SECRET: expected a link secret of at least 16 bytes, got 0"),
]


@pytest.mark.parametrize(("lines", "contents", "environment", "problem"), SECRET_PROBLEMS)
def test_a_misconfigured_secret_never_opens_a_plain_link(
    lines: str,
    contents: str | None,
    environment: str | None,
    problem: str,
    listener: socket.socket,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    key = tmp_path / "robot.key"
    if contents is not None:
        key.write_text(contents, encoding="utf-8")
    monkeypatch.delenv("SKIDNAV_LINK_SECRET", raising=False)
    if environment is not None:
        monkeypatch.setenv("SKIDNAV_LINK_SECRET", environment)
    port = listener.getsockname()[1]
    text = f"[tcp]\nport = {port}\n" + lines.format(key=key) + "\n"
    config, out = write_config(tmp_path, text), tmp_path / "out"
    argv = ["robot", "run", "--driver", "tcp", "--policy", "goal-tracker"]
    assert exit_code([*argv, "--config", str(config), "--out", str(out)]) == 2
    assert problem.format(key=key) in one_error_line(capsys)
    assert not connected(listener)  # no link at all, plain or not
    assert not out.exists()


def test_without_a_secret_the_same_run_does_reach_the_robot(
    listener: socket.socket, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The control of the test above: its listener sees a run that connects."""
    monkeypatch.delenv("SKIDNAV_LINK_SECRET", raising=False)
    port = listener.getsockname()[1]
    config = write_config(tmp_path, f"[tcp]\nport = {port}\n")
    argv = ["robot", "run", "--driver", "tcp", "--policy", "goal-tracker", "--quiet"]
    assert exit_code([*argv, "--config", str(config), "--out", str(tmp_path / "out")]) == 2
    assert connected(listener)  # it connected, then found no robot's hello


def parsers(parser: argparse.ArgumentParser) -> Iterator[argparse.ArgumentParser]:
    """``parser`` and every subparser below it."""
    yield parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in action.choices.values():
                yield from parsers(child)


def test_no_parser_takes_an_abbreviated_option() -> None:
    every = list(parsers(build_parser()))
    assert len(every) > 30 and all(not parser.allow_abbrev for parser in every)
    assert not reference_cli.parser().allow_abbrev


@pytest.mark.parametrize(
    ("argv", "line"),
    [
        (["robot", "sim-server", "--port", "0", "--secret", SECRET], "--secret …"),
        (["robot", "sim-server", "--port", "0", f"--secret={SECRET}"], "--secret=…"),
        (["robot", "run", "--agent", "q-learning", "--secret-fil", SECRET], "--secret-fil …"),
        (["robot", "run", "--agent", "q-learning", "--ep", "3"], "--ep …"),
    ],
)
def test_a_prefix_of_an_option_is_unknown_and_its_value_not_shown(
    argv: list[str], line: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert exit_code(argv) == 2
    assert one_error_line(capsys) == f"skidnav: error: unrecognized arguments: {line}"


def test_the_reference_robot_takes_no_abbreviated_option(
    capsys: pytest.CaptureFixture[str],
) -> None:
    argv = ["--tcp", "127.0.0.1:0", "--secret", SECRET]
    assert exit_code(argv, reference_cli.main) == 2
    assert one_error_line(capsys) == "reference-robot: error: unrecognized arguments: --secret …"


@pytest.mark.parametrize(
    ("host_secret", "line"),
    [
        (None, "robot error (auth): the peer's hello has no nonce: it does not authenticate"),
        ("another secret of the lab, 34 bytes", "robot not authenticated (auth): wrong MAC"),
    ],
)
def test_an_authentication_refusal_is_one_line(
    host_secret: str | None, line: str, tmp_path: Path
) -> None:
    """A real ``skidnav robot run`` (its own process, its own logging) against a robot that
    knows another secret: the error line alone, no warning before it."""
    options = {"secret": SECRET.encode()}
    with ServerThread(options=options) as server:
        text = f"[tcp]\nport = {server.port}\n"
        env = cli_env()
        env.pop("SKIDNAV_LINK_SECRET", None)
        if host_secret is not None:
            (tmp_path / "robot.key").write_text(host_secret, encoding="utf-8")
            text += f'secret_file = "{tmp_path / "robot.key"}"\n'
        config = write_config(tmp_path, text)
        command = [sys.executable, "-m", "skidnav.cli", "robot", "run", "--driver", "tcp"]
        command += ["--policy", "goal-tracker", "--quiet", "--config", str(config)]
        command += ["--out", str(tmp_path / "out")]
        done = subprocess.run(command, capture_output=True, text=True, env=env, timeout=300)
        assert not server.robot.moving
    assert done.returncode == 2
    prefix = "skidnav: error: cannot connect to the robot (tcp): "
    assert done.stderr.splitlines() == [prefix + line], done.stderr


def test_an_unknown_preset_lists_the_presets_by_name(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config = write_config(tmp_path, "[presets.lab]\n[presets.field]\n")
    argv = ["robot", "run", "--policy", "goal-tracker", "--config", str(config), "--preset", "x"]
    assert exit_code([*argv, "--out", str(tmp_path / "out")]) == 2
    assert one_error_line(capsys) == (
        f"skidnav: error: unknown preset 'x' in {config} (expected one of 'lab', 'field')"
    )
