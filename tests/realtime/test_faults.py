"""Injected faults against a running ``skidnav robot run``: each is answered by a confirmed stop
within 100 ms (measured on the sim server's own command log, system-wide monotonic clock), the
episode is marked aborted, the checkpoint stays loadable, and the run recovers or ends cleanly."""

from __future__ import annotations

import signal
import subprocess
import time
from pathlib import Path
from typing import Any

import pytest

from skidnav.agents.tabular.registry import load_agent
from skidnav.realtime.control.checkpoint import Checkpoints
from tests.realtime.realtime_helpers import (
    ServerProcess,
    ServerThread,
    read_events,
    start_run,
    wait_for,
    write_config,
)

TIME_SCALE = 20.0
POSE_TIMEOUT = 0.1  # max(5 periods of 5 ms, the 0.1 s floor)
STOP_WITHIN = 0.1


def config_for(tmp_path: Path, port: int, episodes: int = 2, max_actions: int = 10) -> Path:
    return write_config(
        tmp_path,
        f"""
[run]
episodes = {episodes}
max_actions = {max_actions}
time_scale = {TIME_SCALE}
reconnect_timeout = 8.0
homing_timeout = 10.0

[tcp]
port = {port}
""",
    )


def wait_mid_episode(out: Path, process: subprocess.Popen[str]) -> None:
    def started() -> bool:
        assert process.poll() is None, process.communicate()
        return any(e["event"] == "transition" for e in read_events(out / "run.jsonl"))

    wait_for(started, 60.0, "the run's first transition")


def first_after(events: list[dict[str, Any]], kind: str, after: float) -> dict[str, Any]:
    return next(e for e in events if e["event"] == kind and e["mono"] >= after)


def assert_quiet_until_reconnect(events: list[dict[str, Any]], stop: dict[str, Any]) -> None:
    """No wheel command but zero between the emergency stop and the next connection."""
    for event in events:
        if event["mono"] <= stop["mono"]:
            continue
        if event["event"] == "connect":
            return
        if event["event"] == "cmd":
            assert (event["omega_left"], event["omega_right"]) == (0.0, 0.0)


def assert_checkpoint_intact(out: Path, reason: str) -> dict[str, Any]:
    latest = Checkpoints(out / "checkpoints").latest()
    assert latest is not None
    _, directory, state = latest
    agent = load_agent(directory / "agent")
    assert agent.q.shape == (12500, 4)
    aborted = [r for r in state["results"] if r["aborted"]]
    assert aborted and reason in aborted[0]["reason"]
    return state


def finish(process: subprocess.Popen[str], timeout: float = 60.0) -> int:
    try:
        process.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        process.kill()
        pytest.fail(f"the run did not end: {process.communicate()}")
    return process.returncode


def wait_transition_after(out: Path, process: subprocess.Popen[str], after: float) -> None:
    def resumed() -> bool:
        assert process.poll() is None, process.communicate()
        events = read_events(out / "run.jsonl")
        return any(e["event"] == "transition" and e["mono"] > after for e in events)

    wait_for(resumed, 30.0, "a transition after the recovery")


FAULTS = [  # (fault, reason in the run, detection delay allowed)
    ("garbage", "malformed", 0.0),
    ("silence", "pose stale", POSE_TIMEOUT),
    ("escape", "outside the arena", 0.0),
]


def test_faults_are_answered_by_a_confirmed_stop(tmp_path: Path) -> None:
    """Garbage bytes and lost poses: stop, abort, reconnect, go on; leaving the arena: stop, end
    with exit code 3. One run, one fault per injection."""
    kinds = tuple(fault for fault, _, _ in FAULTS)
    with ServerThread(TIME_SCALE, log=tmp_path / "server.jsonl", faults=kinds) as server:
        check_faults(tmp_path, server)


def check_faults(tmp_path: Path, server: ServerThread) -> None:
    out = tmp_path / "out"
    config = config_for(tmp_path, server.port, episodes=6)
    run = start_run(tmp_path, "--driver", "tcp", "--agent", "q-learning", "--config", str(config))
    wait_mid_episode(out, run)
    for index, (_, reason, delay) in enumerate(FAULTS):
        server.server.inject()
        wait_for(
            lambda n=index: sum(e["event"] == "fault" for e in server.events()) > n,
            5.0,
            "the fault",
        )
        injected = [e for e in server.events() if e["event"] == "fault"][index]
        wait_for(
            lambda t=injected["mono"]: any(
                e["event"] == "stop" and e["mono"] > t for e in server.events()
            ),
            5.0,
            "a stop",
        )
        events = server.events()
        stop = first_after(events, "stop", injected["mono"])
        assert stop["mono"] - injected["mono"] < delay + STOP_WITHIN, reason
        assert_quiet_until_reconnect(events, stop)
        trip = first_after(read_events(out / "run.jsonl"), "trip", injected["mono"])
        assert reason in trip["reason"]
        if index < len(FAULTS) - 1:
            wait_transition_after(out, run, stop["mono"])
    assert finish(run) == 3
    state = assert_checkpoint_intact(out, "malformed")
    reasons = [r["reason"] for r in state["results"] if r["aborted"]]
    assert [any(reason in r for r in reasons) for _, reason, _ in FAULTS] == [True] * 3
    stopped = [e for e in read_events(out / "run.jsonl") if e["event"] == "stopped"]
    assert len(stopped) == 3 and all(e["confirmed"] for e in stopped)


def test_killed_server_aborts_then_the_run_reconnects(tmp_path: Path, server_process: Any) -> None:
    server: ServerProcess = server_process("--time-scale", str(TIME_SCALE))
    out = tmp_path / "out"
    run = start_run(
        tmp_path,
        "--driver",
        "tcp",
        "--agent",
        "q-learning",
        "--config",
        str(config_for(tmp_path, server.port)),
    )
    wait_mid_episode(out, run)
    killed_at = time.monotonic()
    server.process.kill()
    server.process.wait()
    with ServerThread(TIME_SCALE, log=tmp_path / "new.jsonl", port=server.port) as replacement:
        assert finish(run) == 0
        replaced = replacement.events()
    trip = first_after(read_events(out / "run.jsonl"), "trip", killed_at)
    # the kernel closes a killed process's sockets only once its memory is freed, 60-120 ms
    # for the server on a busy machine: the stale pose may trip first
    reason = "link lost" if "link lost" in trip["reason"] else "pose stale"
    assert reason in trip["reason"] and trip["mono"] - killed_at < POSE_TIMEOUT + STOP_WITHIN
    assert any(e["event"] == "reconnected" for e in read_events(out / "run.jsonl"))
    assert any(e["event"] == "cmd" for e in replaced)  # the run went on there
    state = assert_checkpoint_intact(out, reason)
    assert len(state["results"]) == 2


def test_sigint_stops_the_wheels_and_ends_the_run(tmp_path: Path) -> None:
    with ServerThread(TIME_SCALE, log=tmp_path / "server.jsonl") as server:
        config = config_for(tmp_path, server.port, episodes=3, max_actions=200)
        out = tmp_path / "out"
        run = start_run(tmp_path, "--driver", "tcp", "--agent", "dyna-q", "--config", str(config))
        wait_mid_episode(out, run)
        sent_at = time.monotonic()
        run.send_signal(signal.SIGINT)
        assert finish(run) == 130
        events = server.events()
    stop = first_after(events, "stop", sent_at)
    assert stop["mono"] - sent_at < STOP_WITHIN
    assert_quiet_until_reconnect(events, stop)
    assert_checkpoint_intact(out, "signal SIGINT")
