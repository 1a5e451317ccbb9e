"""``[run] command_latency``: each kinematic log row is paired with the commands in effect over
its period (the one before for the latency, the new one for the rest), so a pilot that changes
its command every period learns the robot's speed, not a fraction of it."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from skidnav.realtime.config import RealtimeConfig, RunSettings
from skidnav.realtime.control.periods import PeriodicControl


class Still:
    """A driver that is never asked for anything here."""

    def latest_pose(self) -> None:
        return None


def control(tmp_path: Path, latency: float) -> PeriodicControl:
    config = RealtimeConfig(run=RunSettings(period=0.1, substeps=1, settle_periods=0,
                                            command_latency=latency))  # fmt: skip
    driver: Any = Still()
    return PeriodicControl(driver, None, config, tmp_path)  # type: ignore[arg-type]


def test_the_row_pairs_the_motion_with_the_commands_in_effect(tmp_path: Path) -> None:
    lagging = control(tmp_path, 0.08)
    # the wheels ran the old command 80 ms of the 100, the new one 20
    assert lagging._in_effect((1.0, -1.0), (0.0, 1.5), 0.1) == pytest.approx((0.8, -0.5))
    # a longer period (a pose given up): the share of the old command is smaller
    assert lagging._in_effect((1.0, -1.0), (0.0, 1.5), 0.2) == pytest.approx((0.4, 0.5))
    # a latency beyond the period: the old command all along
    assert lagging._in_effect((1.0, -1.0), (0.0, 1.5), 0.05) == pytest.approx((1.0, -1.0))
    assert lagging._in_effect((1.0, 1.0), (1.0, 1.0), 0.1) == (1.0, 1.0)
    assert control(tmp_path, 0.0)._in_effect((1.0, -1.0), (0.0, 1.5), 0.1) == (0.0, 1.5)


def test_a_negative_latency_is_refused() -> None:
    with pytest.raises(ValueError, match="expected command_latency >= 0"):
        RunSettings(command_latency=-0.01)
