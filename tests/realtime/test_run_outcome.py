"""What a ``skidnav robot run`` ends with and where it writes: a run whose every episode was
aborted exits 4 with one line, one with a completed episode exits 0; a robot pose stamped from
the future trips the run instead of rushing its actions; ``--out`` takes a new or empty folder or
a run of the same config, nothing else."""

from __future__ import annotations

import json
import re
import subprocess
from pathlib import Path

import pytest

from skidnav.errors import UserError
from skidnav.realtime.config import config_from_mapping
from skidnav.realtime.control.checkpoint import LATEST
from skidnav.realtime.control.episodes import EXIT_ALL_ABORTED
from skidnav.realtime.control.run_folder import MARKER, check_run_folder, mark_run_folder
from skidnav.realtime.link.robot_clock import RobotClock
from skidnav.realtime.robot_server.server import FUTURE_STAMP
from tests.cli_support import exit_code
from tests.realtime.realtime_helpers import (
    ServerThread,
    read_events,
    start_run,
    wait_for,
    write_config,
)

TIME_SCALE = 20.0


def run_with_fault(
    tmp_path: Path, fault: str, episodes: int, max_actions: int
) -> tuple[int, list[str], list[str], list[dict[str, object]]]:
    """A q-learning run over TCP on a sim server that injects ``fault`` once, after the run's
    first transition: (exit code, stdout lines, stderr lines, server events)."""
    out = tmp_path / "out"
    with ServerThread(TIME_SCALE, log=tmp_path / "server.jsonl", faults=(fault,)) as server:
        config = write_config(
            tmp_path,
            f"[run]\nepisodes = {episodes}\nmax_actions = {max_actions}\n"
            f"time_scale = {TIME_SCALE}\nreconnect_timeout = 8.0\nhoming_timeout = 10.0\n"
            f"[tcp]\nport = {server.port}\n",
        )
        run = start_run(
            tmp_path, "--driver", "tcp", "--agent", "q-learning", "--config", str(config)
        )

        def started() -> bool:
            assert run.poll() is None, run.communicate()
            return any(e["event"] == "transition" for e in read_events(out / "run.jsonl"))

        wait_for(started, 120.0, "the run's first transition")
        server.server.inject()
        try:
            stdout, stderr = run.communicate(timeout=120)
        except subprocess.TimeoutExpired:
            run.kill()
            pytest.fail(f"the run did not end: {run.communicate()}")
        events = server.events()
    return run.returncode, stdout.splitlines(), stderr.splitlines(), events


def test_a_run_whose_every_episode_was_aborted_exits_4_in_one_line(tmp_path: Path) -> None:
    """Garbage from the robot mid-episode: the one episode aborts, the run reconnects and ends."""
    code, stdout, stderr, _ = run_with_fault(tmp_path, "garbage", episodes=1, max_actions=400)
    assert code == EXIT_ALL_ABORTED == 4
    assert stdout == [f"1 episode, 0 reached the goal, 1 aborted; results in {tmp_path / 'out'}"]
    # the fault and the trip were logged as they happened; the run ends with one error line
    errors = [line for line in stderr if line.startswith("skidnav: error: ")]
    assert errors == stderr[-1:], stderr
    assert errors[0].startswith(
        "skidnav: error: every episode run was aborted, the last by: malformed message"
    )
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["exit_code"] == 4 and summary["aborted"] == 1


def test_a_pose_from_the_future_trips_the_run_instead_of_rushing_it(tmp_path: Path) -> None:
    """Poses stamped 1e308 from mid-episode on: the host takes none of them, stops the robot,
    aborts the episode and reconnects; the second episode completes, so the run exits 0 (at
    least one episode not aborted)."""
    code, stdout, stderr, events = run_with_fault(tmp_path, "future", episodes=2, max_actions=20)
    assert code == 0, stderr
    assert len(stdout) == 1 and re.fullmatch(
        rf"2 episodes, [01] reached the goal, 1 aborted; results in {re.escape(str(tmp_path))}.*",
        stdout[0],
    )
    assert not any(line.startswith("skidnav: error") for line in stderr), stderr
    run = read_events(tmp_path / "out" / "run.jsonl")
    trips = [e for e in run if e["event"] == "trip"]
    assert "ahead of the robot's clock" in str(trips[0]["reason"])
    assert all(e["robot_stamp"] < FUTURE_STAMP / 2 for e in run if e["event"] == "pose")
    fault = next(e for e in events if e["event"] == "fault")
    assert any(e["event"] == "stop" and e["mono"] > fault["mono"] for e in events)
    ends = [e for e in run if e["event"] == "episode_end"]
    assert [e["aborted"] for e in ends] == [True, False] and ends[1]["actions"] >= 1
    assert "ahead of the robot's clock" in str(ends[0]["reason"])


def test_the_robot_clock_refuses_what_lies_ahead_and_never_learns_it() -> None:
    clock = RobotClock(time_scale=10.0, ttl=0.5)  # 5 s of robot time
    assert clock.tolerance == 5.0
    for k in range(5):
        assert clock.refuse(100.0 + k, received=10.0 + k / 10) is None
    assert clock.refuse(110.0, received=10.5) is None  # 5 s ahead: the bound
    assert clock.refuse(111.6, received=10.6) is not None  # 5.5 s ahead
    for k in range(6, 10):  # a clock that jumped ahead for good stays refused
        assert clock.refuse(1e9 + k, received=10.0 + k / 10) is not None
    assert clock.refuse(111.0, received=11.0) is None  # the robot's clock as it was
    assert clock.refuse(0.0, received=11.1) is None  # one restarted: taken, and adopted
    assert clock.refuse(0.1, received=11.11) is None
    assert clock.refuse(0.2, received=11.12) is None
    assert clock.refuse(9.0, received=11.13) is not None
    lockstep = RobotClock(time_scale=1.0, ttl=0.5, lockstep=True)
    assert lockstep.refuse(0.0, 0.0) is None and lockstep.refuse(1e308, 0.001) is None
    with pytest.raises(ValueError, match="time_scale and ttl > 0"):
        RobotClock(time_scale=0.0, ttl=0.5)


@pytest.fixture
def run_folder(tmp_path: Path) -> Path:
    """The folder of a robot run of the default config with one checkpoint."""
    folder = tmp_path / "run"
    (folder / "checkpoints").mkdir(parents=True)
    (folder / "checkpoints" / LATEST).write_text('{"episode": 0, "directory": "ep-00000"}')
    (folder / "run.jsonl").write_text("")
    mark_run_folder(folder, config_from_mapping({}))
    return folder


def test_out_takes_a_new_or_empty_folder_or_a_run_of_the_same_config(
    run_folder: Path, tmp_path: Path
) -> None:
    config = config_from_mapping({})
    check_run_folder(tmp_path / "new", config, resume=False)
    (tmp_path / "empty").mkdir()
    check_run_folder(tmp_path / "empty", config, resume=False)
    check_run_folder(run_folder, config, resume=True)
    # what the command line may change is not the config: more episodes, another speed, reset
    others = config_from_mapping({"run": {"episodes": 99, "time_scale": 4.0, "reset": "manual"}})
    check_run_folder(run_folder, others, resume=True)
    check_run_folder(run_folder, config_from_mapping({"tcp": {"port": 6000}}), resume=True)
    (run_folder / "checkpoints" / LATEST).unlink()  # it ended before its first checkpoint
    check_run_folder(run_folder, config, resume=False)
    (run_folder / "checkpoints" / LATEST).write_text("{}")
    (run_folder / MARKER).unlink()  # a run of an earlier version, with --resume only
    check_run_folder(run_folder, config, resume=True)
    with pytest.raises(UserError, match="holds a robot run; continue it with --resume"):
        check_run_folder(run_folder, config, resume=False)


@pytest.mark.parametrize(
    ("setup", "resume", "problem"),
    [
        ("files", False, "not empty and not a robot run; choose another --out"),
        ("files", True, "not empty and not a robot run; choose another --out"),
        ("other config", True, "holds a robot run of another config; choose another --out"),
        ("same config", False, "holds a robot run; continue it with --resume or choose another"),
        ("bad marker", True, f"{MARKER}: not a robot run's marker; choose another --out"),
    ],
)
def test_out_refuses_any_other_folder_in_one_line(
    setup: str,
    resume: bool,
    problem: str,
    run_folder: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    folder = run_folder
    if setup == "files":
        folder = tmp_path / "home"
        folder.mkdir()
        (folder / "notes.txt").write_text("keep me\n")
    elif setup == "bad marker":
        (folder / MARKER).write_text('{"format": "something else"}')
    before = sorted((p.relative_to(folder), p.stat().st_mtime_ns) for p in folder.rglob("*"))
    config = write_config(tmp_path, "[run]\nseed = 7\n" if setup == "other config" else "")
    argv = ["robot", "run", "--driver", "tcp", "--policy", "goal-tracker", "--config", str(config)]
    argv += ["--out", str(folder), *(["--resume"] if resume else [])]
    assert exit_code(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    assert captured.err.startswith("skidnav: error: ") and problem in captured.err
    after = sorted((p.relative_to(folder), p.stat().st_mtime_ns) for p in folder.rglob("*"))
    assert after == before  # nothing written
