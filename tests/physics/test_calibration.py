"""``skidnav world floors calibrate``: the ICR fit on the physics robot, and its command line."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco")

from skidnav.physics.calibration import calibrate, fit_floor
from skidnav.robot.kinematics import body_velocities
from skidnav.robot.params import RobotParams


def test_fit_recovers_a_known_icr_model_from_its_own_log() -> None:
    """On rows made by the ICR model itself the fit must return its r, c and x_ICR."""
    rng = np.random.default_rng(1)
    wheels = rng.uniform(-1.7, 1.7, (400, 2))
    twists = np.array([body_velocities(wl, wr, 0.03, 0.02, 0.08) for wl, wr in wheels])
    fit = fit_floor("laminate", np.column_stack([wheels, twists]), rng)
    assert fit.wheel_radius == pytest.approx(0.02, rel=1e-3)
    assert fit.half_track == pytest.approx(0.08, rel=1e-3)
    assert fit.x_icr == pytest.approx(0.03, rel=1e-3)
    assert fit.vx_noise < 1e-6


def test_physics_robot_turns_as_if_its_track_were_wider_and_grippier_floors_widen_it() -> None:
    fits = {
        fit.material: fit
        for fit in calibrate(["laminate", "rubber-mat"], np.random.default_rng(0), 12)
    }
    geometric = RobotParams().half_track
    for fit in fits.values():
        low, high = fit.half_track_interval
        assert low <= fit.half_track <= high
        assert low > 1.4 * geometric  # measured ≈ 1.7–1.9 × c
        assert fit.wheel_radius == pytest.approx(RobotParams().wheel_radius, rel=0.05)
        assert abs(fit.x_icr) < 2e-3  # a = b: the ICR lies under the centre of mass
    assert fits["rubber-mat"].half_track_interval[0] > fits["laminate"].half_track_interval[1]


def run_cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "skidnav.cli", "world", "floors", "calibrate", *args],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip


def test_command_writes_the_fits_and_refuses_bad_arguments_in_one_line(tmp_path: Path) -> None:
    out = tmp_path / "floors.json"
    done = run_cli("--material", "wet-tile", "--seconds", "4", "--out", str(out))
    assert done.returncode == 0, done.stderr
    assert "wet-tile" in done.stdout
    [fit] = json.loads(out.read_text())["fits"]
    assert fit["material"] == "wet-tile" and fit["samples"] == 40
    bad = run_cli("--seconds", "0")
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1
    unwritable = run_cli(
        "--seconds", "2", "--material", "laminate", "--out", str(tmp_path / "no" / "f.json")
    )
    assert unwritable.returncode == 2 and "cannot write" in unwritable.stderr
