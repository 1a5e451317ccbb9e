"""What ``skidnav robot run`` asks for reaches the real-time run as a checked settings object."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from skidnav.cli import main
from skidnav.realtime.control.run import RobotRunSettings, RunOutcome


def test_the_command_line_becomes_the_settings(tmp_path: Path, monkeypatch) -> None:
    seen: list[RobotRunSettings] = []

    def run_robot(settings: RobotRunSettings, **callbacks: Any) -> RunOutcome:
        seen.append(settings)
        return RunOutcome(0, "done")

    monkeypatch.setattr("skidnav.realtime.control.run.run_robot", run_robot)
    out = tmp_path / "run"
    argv = ["robot", "run", "--policy", "goal-tracker", "--driver", "tcp", "--episodes", "3"]
    argv += ["--time-scale", "2.5", "--reset", "manual", "--resume", "--quiet", "--out", str(out)]
    assert main(argv) == 0
    assert seen == [
        RobotRunSettings(
            out=out, driver="tcp", policy="goal-tracker", episodes=3, time_scale=2.5,
            reset="manual", resume=True,
        )
    ]  # fmt: skip


@pytest.mark.parametrize(
    ("pilots", "message"),
    [
        ({}, "exactly one of agent, policy, policy_file and agent_file, got 0"),
        ({"agent": "dyna-q", "policy": "goal-tracker"}, "exactly one of .* got 2"),
        ({"agent": "dyna-q", "driver": "bluetooth"}, "driver one of sim, tcp, serial, ros2"),
    ],
)
def test_settings_refuse_what_no_run_can_do(pilots: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        RobotRunSettings(out=Path("run"), **pilots)
