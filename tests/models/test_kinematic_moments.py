"""The learned kinematic model's speed strata (slow samples must not crowd the fast ones out of
the window) and its incremental refits (the same fit as the rebuild from the window, faster)."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest

from skidnav._jit import jit_disabled
from skidnav.models.kinematic import KinematicModel
from skidnav.models.kinematic_config import KinematicModelConfig
from skidnav.models.kinematic_files import load_model, save_model
from skidnav.models.kinematic_moments import stratum_of
from skidnav.robot.kinematics import apply_slip, body_velocities
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization
from tests.benchmark_scripts import benchmark
from tests.speed_support import assert_ratio_above

ROBOT, GRID = RobotParams(), Discretization()
REGION, ETA = 24, 0.3  # the slippery preset's ordinary floor: up to 0.3 rad/s lost per wheel
FULL_SPEED_TRUTH = ROBOT.wheel_radius * (ROBOT.wheel_speed - ETA / 2.0)  # 34.9 mm/s


def _slipping_log(n: int, fast_every: int, seed: int) -> np.ndarray:
    """Rows of one region of the slip simulator's floor (each wheel slowed by U(0, η), never
    past 0): slow commands |ω| ≤ 0.25 rad/s, and every ``fast_every``-th full speed ahead or
    back."""
    rng = np.random.default_rng(seed)
    rows = np.zeros((n, 6))
    for k in range(n):
        if k % fast_every == fast_every - 1:
            omega_left = omega_right = ROBOT.wheel_speed * rng.choice([-1.0, 1.0])
        else:
            omega_left, omega_right = rng.uniform(-0.25, 0.25, size=2)
        left = apply_slip(omega_left, rng.uniform(0.0, ETA))
        right = apply_slip(omega_right, rng.uniform(0.0, ETA))
        twist = body_velocities(left, right, ROBOT.x_icr, ROBOT.wheel_radius, ROBOT.half_track)
        rows[k] = (REGION, omega_left, omega_right, *twist)
    return rows


def _stuck_in_front_of_a_wall() -> np.ndarray:
    """300 samples with a third at full speed, then 700 slow ones (more than a window)."""
    return np.concatenate([_slipping_log(300, 3, seed=1), _slipping_log(700, 10**9, seed=2)])


def _full_speed_prediction(config: KinematicModelConfig) -> tuple[float, float]:
    model = KinematicModel(ROBOT, GRID, config)
    model.feed(_stuck_in_front_of_a_wall())
    model.refit()
    wheels = np.array([[ROBOT.wheel_speed, ROBOT.wheel_speed]])
    mean, std = model.predict_twist(np.array([REGION]), wheels)
    return float(mean[0, 0]), float(std[0, 0])


@pytest.mark.parametrize("fit_intercept", [False, True])
def test_slow_commands_crowd_the_fast_ones_out_of_a_plain_window(fit_intercept: bool) -> None:
    mean, std = _full_speed_prediction(KinematicModelConfig(fit_intercept=fit_intercept))
    assert mean < 0.5 * FULL_SPEED_TRUTH  # it believes the robot can hardly move
    assert FULL_SPEED_TRUTH - mean > 5.0 * std  # and is sure of it


@pytest.mark.parametrize("strata", [2, 3])
def test_speed_strata_keep_the_fast_samples_and_the_full_speed_right(strata: int) -> None:
    mean, std = _full_speed_prediction(KinematicModelConfig(speed_strata=strata))
    assert mean == pytest.approx(FULL_SPEED_TRUTH, rel=0.03)
    assert abs(FULL_SPEED_TRUTH - mean) < 3.0 * std


def test_a_stratum_is_the_bin_of_the_faster_wheel() -> None:
    assert [stratum_of(w, 0.1, 1.7, 3) for w in (0.0, 0.6, -1.2, 1.7, 2.5)] == [0, 1, 2, 2, 2]


CONFIGS = {
    "default": {},
    "forgetting, small window": {"forgetting": 0.98, "window": 60},
    "strata, forgetting": {"speed_strata": 3, "forgetting": 0.995, "window": 90},
    "intercept": {"fit_intercept": True, "window": 50},
}


def _random_drive(n: int, seed: int) -> np.ndarray:
    """Rows over 5 regions, continuous random commands, a different true geometry per region,
    noisy outputs."""
    rng = np.random.default_rng(seed)
    rows = np.zeros((n, 6))
    for k in range(n):
        region = int(rng.integers(20, 25))
        omega_left, omega_right = rng.uniform(-1.7, 1.7, size=2)
        twist = body_velocities(
            omega_left, omega_right, 0.01 * region, 0.001 * region, 0.0025 * region
        )
        rows[k] = (region, omega_left, omega_right, *(twist + rng.normal(0.0, 1e-3, 3)))
    return rows


@pytest.mark.parametrize("name", list(CONFIGS))
def test_incremental_refits_equal_the_rebuild_from_the_window(name: str) -> None:
    models = [
        KinematicModel(ROBOT, GRID, KinematicModelConfig(incremental=incremental, **CONFIGS[name]))
        for incremental in (True, False)
    ]
    log = _random_drive(3000, seed=5)
    regions, wheels = log[:200, 0], log[:200, 1:3]
    # uneven batches: some regions get more than a window between refits, some a few samples
    # (the rebuild after REBUILD_WINDOWS windows of updates is crossed too)
    bounds = [0, 7, 40, 400, 430, 1600, 1620, 3000]
    for start, stop in itertools.pairwise(bounds):
        for model in models:
            model.feed(log[start:stop])
            model.refit()
        np.testing.assert_allclose(models[0].coefficients, models[1].coefficients, rtol=1e-9)
        (mean, std), (mean_full, std_full) = (m.predict_twist(regions, wheels) for m in models)
        np.testing.assert_allclose(mean, mean_full, rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(std, std_full, rtol=1e-7)
    assert models[0].refits == 7 and not np.array_equal(
        models[0].coefficients[20], models[0].coefficients[24]
    )


def test_a_loaded_model_rebuilds_its_moments_and_keeps_its_strata(tmp_path: Path) -> None:
    config = KinematicModelConfig(speed_strata=3, window=90)
    model = KinematicModel(ROBOT, GRID, config)
    log = _random_drive(1500, seed=6)
    model.feed(log[:1000])
    model.refit()
    save_model(model, tmp_path / "model")
    loaded = load_model(tmp_path / "model")
    np.testing.assert_array_equal(loaded.stratum_counts, model.stratum_counts)
    for each in (model, loaded):
        each.feed(log[1000:])
        each.refit()
    np.testing.assert_allclose(loaded.coefficients, model.coefficients, rtol=1e-9)


def test_a_perfect_prior_gives_an_exact_fit_without_spread() -> None:
    model = KinematicModel(ROBOT, GRID)
    rows = _slipping_log(200, 2, seed=3)
    rows[:, 3:6] = [
        body_velocities(left, right, ROBOT.x_icr, ROBOT.wheel_radius, ROBOT.half_track)
        for left, right in rows[:, 1:3]
    ]
    model.feed(rows)
    model.refit()
    assert model.posterior(REGION) == (None, None, None)
    np.testing.assert_array_equal(model.coefficients[REGION], model.coefficients[0])


FLOOR = 2.0  # measured 4.7× on the 2-core machine with other work running


@pytest.mark.skipif(jit_disabled(), reason="nothing is compiled with NUMBA_DISABLE_JIT=1")
def test_an_incremental_refit_stays_faster_than_the_rebuild() -> None:
    """A ratio against the rebuild measured in the same process (make bench's entry,
    tests/speed_support.py)."""
    refit_rates = benchmark("bench_kinematic_refit").refit_rates
    assert_ratio_above(lambda: refit_rates(True), FLOOR, "incremental refit against the rebuild")
