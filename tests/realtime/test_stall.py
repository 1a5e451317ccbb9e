"""A robot that stalls mid-action (its process frozen by SIGSTOP for 0.4 s while ``skidnav robot
run`` drives it): the host trips on the stale pose, and when the robot resumes its wheels never
run a command from before the trip — checked on the sim server's own log of what its physics
ran — and the host's stop is confirmed. Once on a quiet machine, once with both cores busy."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from tests.realtime.realtime_helpers import (
    ServerProcess,
    read_events,
    start_run,
    wait_for,
    write_config,
)

TIME_SCALE = 5.0  # 20 ms periods: an action of 10 periods lasts 0.2 s, most of the time moving
FREEZE = 0.4


@contextmanager
def busy_cores(count: int) -> Iterator[None]:
    """``count`` processes spinning on the CPU for the duration."""
    spinners = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(count)]
    try:
        yield
    finally:
        for spinner in spinners:
            spinner.kill()
            spinner.wait()


def ran_wheels(event: dict[str, Any]) -> tuple[float, float] | None:
    """The wheel speeds a server period ran, for ``wheels`` and ``late`` records."""
    if event["event"] in ("wheels", "late"):
        return (event["wheels"][0], event["wheels"][1])
    return None


def freeze_while_moving(server: ServerProcess) -> tuple[float, float]:
    """SIGSTOP the server while its wheels turn, SIGCONT after :data:`FREEZE`; the monotonic
    times of both signals."""

    def moving() -> bool:
        ran = [w for w in map(ran_wheels, server.events()) if w is not None]
        return bool(ran) and ran[-1] != (0.0, 0.0)

    wait_for(moving, 30.0, "the wheels to turn")
    frozen_at = time.monotonic()
    server.signal(signal.SIGSTOP)
    time.sleep(FREEZE)
    resumed_at = time.monotonic()
    server.signal(signal.SIGCONT)
    return frozen_at, resumed_at


def assert_no_stale_command_ran(events: list[dict[str, Any]], resumed_at: float) -> None:
    """From the resume to the next connection the physics ran only zero wheels, the robot did
    not move, and no command was applied."""
    after = [e for e in events if e["mono"] >= resumed_at]
    reconnect = next((i for i, e in enumerate(after) if e["event"] == "connect"), len(after))
    before_reconnect = after[:reconnect]
    stalled = [e for e in before_reconnect if ran_wheels(e) is not None and e["late"] > 0.2]
    assert stalled, "the server logged no stalled period"
    first = stalled[0]
    assert ran_wheels(first) == (0.0, 0.0) and first["after"] == first["pose"]
    assert all(ran_wheels(e) in (None, (0.0, 0.0)) for e in before_reconnect)
    assert not [e for e in before_reconnect if e["event"] == "cmd"]


def test_a_robot_frozen_mid_action_never_resumes_the_old_command(
    tmp_path: Path, server_process: Any
) -> None:
    """One run, two freezes: the first on a quiet machine, the second with both cores busy."""
    server: ServerProcess = server_process("--time-scale", str(TIME_SCALE))
    config = write_config(
        tmp_path,
        f"""
[run]
episodes = 4
max_actions = 40
time_scale = {TIME_SCALE}
reconnect_timeout = 8.0
homing_timeout = 20.0

[tcp]
port = {server.port}
""",
    )
    out = tmp_path / "out"
    run = start_run(tmp_path, "--driver", "tcp", "--agent", "q-learning", "--config", str(config))
    try:
        check_stall(out, run, server)
        with busy_cores(2):
            check_stall(out, run, server)
    finally:
        run.send_signal(signal.SIGINT)
        run.communicate(timeout=30)


def check_stall(out: Path, run: subprocess.Popen[str], server: ServerProcess) -> None:
    """Freeze the server mid-action; check the trip, the confirmed stop, the recovery and what
    the server's wheels ran."""

    def transitions() -> bool:
        assert run.poll() is None, run.communicate()
        return any(e["event"] == "transition" for e in read_events(out / "run.jsonl"))

    wait_for(transitions, 60.0, "the run's first transition")
    frozen_at, resumed_at = freeze_while_moving(server)

    def recorded(kind: str) -> bool:
        return any(
            e["event"] == kind and e["mono"] > frozen_at for e in read_events(out / "run.jsonl")
        )

    wait_for(lambda: recorded("stopped"), 10.0, "the host's stop record")
    run_events = [e for e in read_events(out / "run.jsonl") if e["mono"] > frozen_at]
    trip = next(e for e in run_events if e["event"] == "trip")
    stopped = next(e for e in run_events if e["event"] == "stopped")
    assert "pose stale" in trip["reason"]
    assert frozen_at < trip["mono"] < resumed_at  # tripped during the freeze
    assert stopped["confirmed"] and stopped["mono"] >= resumed_at  # only a live robot confirms
    wait_for(lambda: recorded("reconnected"), 20.0, "the run to reconnect")
    assert_no_stale_command_ran(server.events(), resumed_at)
