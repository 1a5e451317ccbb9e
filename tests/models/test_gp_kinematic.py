"""The Gaussian-process kinematic model (and the ridge model's predictive interval): calibration
on a known linear model with Gaussian noise, mean recovery, the window bound. The comparison of
the two models: tests/studies/test_kinematic_models.py."""

from __future__ import annotations

import numpy as np
import pytest

from skidnav.models.gp_kinematic import (
    MAX_WINDOW,
    GaussianProcessConfig,
    GaussianProcessKinematicModel,
)
from skidnav.models.kinematic import KinematicModel
from skidnav.models.kinematic_config import KinematicModelConfig
from skidnav.robot.params import RobotParams
from skidnav.studies.kinematic_models.trial import Z_LEVEL
from skidnav.world.discretization import Discretization

REGION = 3
NOISE = np.array([0.002, 0.001, 0.02])
"""Gaussian noise of v_x [m/s], of v_y given the observed yaw rate [m/s], of yaw_rate [rad/s]."""
X_ICR = 0.03


def _linear_log(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Log rows (n, 6) in :data:`REGION` of a robot with a known linear twist plus Gaussian
    noise, and the noise-free mean twist (n, 3); wheel speeds uniform in [−1.7, 1.7] rad/s."""
    wheels = rng.uniform(-1.7, 1.7, size=(n, 2))
    v_x = 0.011 * wheels[:, 0] + 0.0105 * wheels[:, 1]
    yaw = -0.17 * wheels[:, 0] + 0.16 * wheels[:, 1]
    noise = rng.standard_normal((n, 3)) * NOISE
    observed_yaw = yaw + noise[:, 2]
    twist = np.column_stack([v_x + noise[:, 0], -X_ICR * observed_yaw + noise[:, 1], observed_yaw])
    mean = np.column_stack([v_x, -X_ICR * yaw, yaw])
    return np.column_stack([np.full(n, REGION), wheels, twist]), mean


def _coverage(mean: np.ndarray, std: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Fraction of ``truth`` inside the central 90 % interval, per output, shape (3,)."""
    return np.mean(np.abs(truth - mean) <= Z_LEVEL * std, axis=0)


@pytest.fixture(scope="module")
def data() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """300 training rows, then 1,000 held-out rows with their noise-free means."""
    rng = np.random.default_rng(11)
    train, _ = _linear_log(rng, 300)
    test, test_mean = _linear_log(rng, 1000)
    return train, test, test_mean


@pytest.fixture(scope="module")
def gp(data: tuple[np.ndarray, np.ndarray, np.ndarray]) -> GaussianProcessKinematicModel:
    model = GaussianProcessKinematicModel(49, GaussianProcessConfig(window=300))
    assert model.feed(data[0]) == 300
    model.refit()
    return model


# 1,000 points: a calibrated 90 % interval's coverage has a standard error of 0.0095, so
# [0.85, 0.95] is ±5 of them; an interval 1.5 times too narrow covers 0.73, 1.5 times too
# wide 0.99, and both fail.
def test_gp_90_percent_interval_covers_90_percent_of_held_out_points(
    gp: GaussianProcessKinematicModel, data: tuple[np.ndarray, np.ndarray, np.ndarray]
) -> None:
    _, test, _ = data
    mean, std = gp.predict(test[:, 0].astype(np.int64), test[:, 1:3])
    coverage = _coverage(mean, std, test[:, 3:6])
    assert np.all((coverage >= 0.85) & (coverage <= 0.95)), coverage


def test_gp_recovers_the_mean_twist(
    gp: GaussianProcessKinematicModel, data: tuple[np.ndarray, np.ndarray, np.ndarray]
) -> None:
    _, test, test_mean = data
    mean, std = gp.predict(test[:, 0].astype(np.int64), test[:, 1:3])
    error = np.sqrt(np.mean((mean - test_mean) ** 2, axis=0))
    noise_given_wheels = np.array([NOISE[0], np.hypot(NOISE[1], X_ICR * NOISE[2]), NOISE[2]])
    assert np.all(error < 0.3 * noise_given_wheels), error / noise_given_wheels
    assert np.allclose(np.median(std, axis=0), noise_given_wheels, rtol=0.15)


def test_ridge_predictive_interval_is_calibrated_too(
    data: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> None:
    train, test, test_mean = data
    model = KinematicModel(RobotParams(), Discretization(), KinematicModelConfig(window=300))
    model.feed(train)
    mean, std = model.predict_twist(test[:, 0].astype(np.int64), test[:, 1:3])
    assert np.isnan(std).all()  # nothing fitted yet: the prior states no spread
    model.refit()
    mean, std = model.predict_twist(test[:, 0].astype(np.int64), test[:, 1:3])
    coverage = _coverage(mean, std, test[:, 3:6])
    assert np.all((coverage >= 0.85) & (coverage <= 0.95)), coverage
    assert np.all(np.abs(mean - test_mean).max(axis=0) < NOISE), np.abs(mean - test_mean).max(0)


def test_each_fit_sees_at_most_the_window() -> None:
    window = 40
    model = GaussianProcessKinematicModel(49, GaussianProcessConfig(window=window))
    rows, _ = _linear_log(np.random.default_rng(2), 500)
    other = rows[:30].copy()
    other[:, 0] = REGION + 1
    model.feed(rows)
    model.feed(other)
    assert np.array_equal(model.region_samples(REGION), rows[-window:, 1:])
    model.refit()
    fitted = model.fits[REGION]
    assert fitted is not None and model.pooled is not None
    assert all(process.X_train_.shape[0] == window for process in fitted)
    assert model.pooled[0].X_train_.shape[0] <= window + 1  # ceil(window / 2) per active region
    mean, std = model.predict(np.array([0]), np.array([[1.7, 1.7]]))  # unseen region: the pool
    assert np.isfinite(mean).all() and np.isfinite(std).all()


def test_config_and_queries_are_validated() -> None:
    with pytest.raises(ValueError, match="window"):
        GaussianProcessConfig(window=MAX_WINDOW + 1)
    with pytest.raises(ValueError, match="length_scale"):
        GaussianProcessConfig(length_scale=0.0)
    model = GaussianProcessKinematicModel(4)
    with pytest.raises(ValueError, match="regions in"):
        model.predict(np.array([4]), np.zeros((1, 2)))
    mean, std = model.predict(np.array([1]), np.zeros((1, 2)))
    assert np.isnan(mean).all() and np.isnan(std).all()  # nothing fitted
