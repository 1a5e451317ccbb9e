"""The robot commands' edges: bad arguments end in one line and exit code 2 with nothing left
behind, and a ``skidnav robot run`` killed with SIGKILL takes its sim server down with it."""

from __future__ import annotations

import os
import signal
import subprocess
from pathlib import Path

import pytest

from skidnav.cli import main
from tests.realtime.realtime_helpers import read_events, start_run, wait_for, write_config


def blocked_path(tmp_path: Path) -> Path:
    """A path no one can create, root included: its parent is a regular file."""
    blocker = tmp_path / "a-file"
    blocker.write_text("not a directory\n", encoding="utf-8")
    return blocker / "inside"


def run_cli(argv: list[str]) -> int:
    """``main(argv)``, with argparse's exit turned into its code."""
    try:
        return main(argv)
    except SystemExit as leave:
        return int(leave.code or 0)


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["robot", "sim-server", "--port", "70000"], "expected a port in [0, 65535], got 70000"),
        (["robot", "sim-server", "--port", "http"], "expected a port number, got 'http'"),
        (["robot", "sim-server", "--port", "0", "--time-scale", "inf"], "time_scale"),
        (["robot", "sim-server", "--port", "0", "--idle-timeout", "0.1"], "idle_timeout"),
        (["robot", "sim-server", "--port", "0", "--integrator", "rk4"], "invalid choice: 'rk4'"),
        (["robot", "sim-server", "--port", "0", "--latency", "inf"], "expected a finite latency"),
        (["robot", "sim-server", "--port", "0", "--latency", "nan"], "expected a finite latency"),
        (["robot", "sim-server", "--port", "0", "--latency", "-0.1"], "expected a finite latency"),
        (["robot", "sim-server", "--port", "0", "--pose-noise", "inf"], "finite pose_noise"),
        (["robot", "sim-server", "--port", "0", "--idle-timeout", "inf"], "finite idle_timeout"),
        (["robot", "sim-server", "--port", "0", "--drift-period", "inf"], "finite number > 0"),
        (["robot", "sim-server", "--port", "0", "--max-lease", "1e300"], "expected max_lease in"),
        (["robot", "sim-server", "--port", "0", "--max-lease", "nan"], "expected max_lease in"),
        (
            ["robot", "sim-server", "--port", "0", "--host", "0.0.0.0"],
            "refusing to serve the robot link on 0.0.0.0 without a secret",
        ),
        (
            ["robot", "sim-server", "--port", "0", "--secret-file", "{blocked}/robot.key"],
            "cannot read secret file",
        ),
        (
            ["robot", "sim-server", "--port", "0", "--secret-file", "{short}"],
            "expected a link secret of at least 16 bytes, got 6",
        ),
        (["robot", "sim-server", "--port", "0", "--log", "{blocked}/server.jsonl"], "cannot write"),
        (["robot", "run", "--agent", "q-learning", "--out", "{blocked}/run"], "cannot write"),
        (["robot", "run", "--agent", "q-learning", "--episodes", "many"], "invalid int value"),
    ],
)
def test_bad_arguments_end_in_one_line_and_exit_code_2(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    argv: list[str],
    needle: str,
) -> None:
    monkeypatch.delenv("SKIDNAV_LINK_SECRET", raising=False)
    blocked = blocked_path(tmp_path)
    short = tmp_path / "short.key"
    short.write_text("secret\n", encoding="utf-8")
    before = sorted(tmp_path.rglob("*"))
    code = run_cli([part.format(blocked=blocked, short=short) for part in argv])
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert code == 2
    assert len(lines) == 1 and lines[0].startswith("skidnav: error: "), captured.err
    assert needle in lines[0]
    assert captured.out == ""
    assert sorted(tmp_path.rglob("*")) == before  # nothing written


@pytest.mark.parametrize("integrator", ["euler", "exact"])
def test_the_sim_server_takes_the_integrator_asked_for(
    integrator: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    from skidnav.realtime.robot_server import simulated_robot

    built = []

    def build(**arguments: object) -> None:
        built.append(arguments["robot"])
        raise SystemExit(0)  # stop before the server binds

    monkeypatch.setattr(simulated_robot, "build_robot", build)
    run_cli(["robot", "sim-server", "--port", "0", "--integrator", integrator])
    assert [robot.integrator for robot in built] == [integrator]  # type: ignore[attr-defined]


def process_gone(pid: int) -> bool:
    """True once ``pid`` no longer runs (exited, or a zombie nobody has reaped yet)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return True
    except OSError:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        return False
    return state in ("Z", "X")


def test_sigkill_of_robot_run_takes_its_sim_server_down(tmp_path: Path) -> None:
    config = write_config(tmp_path, "[run]\nepisodes = 50\ntime_scale = 20.0\n")
    run = start_run(tmp_path, "--driver", "sim", "--agent", "q-learning", "--config", str(config))
    server_log = tmp_path / "out" / "sim-server.jsonl"

    def connected() -> bool:
        assert run.poll() is None, run.communicate()
        return any(e["event"] == "hello" for e in read_events(server_log))

    wait_for(connected, 60.0, "the sim server's first client")
    pid = next(e["pid"] for e in read_events(server_log) if e["event"] == "listening")
    assert not process_gone(pid)
    run.send_signal(signal.SIGKILL)
    run.wait(timeout=10)
    wait_for(lambda: process_gone(pid), 10.0, "the orphaned sim server to exit")
    assert any(e["event"] == "parent_gone" for e in read_events(server_log))
    try:  # nothing holds the run's output pipes any more
        run.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        pytest.fail("a process still holds the killed run's output")
