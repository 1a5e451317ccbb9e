"""The compiled evidence maximization against scikit-learn's BayesianRidge, and by hand; its
guards on degenerate data (constant, collinear or zero inputs, zero residuals, one sample, tiny
or huge weights) against scikit-learn where it is well-defined, finite everywhere else."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from sklearn.linear_model import BayesianRidge

from skidnav.models.bayesian_ridge import (
    MAX_MAGNITUDE,
    PRECISION_FLOOR,
    RidgePosterior,
    fit_bayesian_ridge,
)

WHEEL_SPEEDS = np.array([[1.7, 1.7], [-1.7, -1.7], [-1.7, 1.7], [1.7, -1.7]])
"""The commanded (ω_L, ω_R) [rad/s] of the four discrete actions: the kinematic regressions'
inputs."""


@pytest.mark.parametrize("fit_intercept", [False, True])
@pytest.mark.parametrize("weighted", [False, True])
@pytest.mark.parametrize("n_inputs", [1, 2])
def test_matches_scikit_learn(fit_intercept: bool, weighted: bool, n_inputs: int) -> None:
    rng = np.random.default_rng(n_inputs + 2 * weighted + 4 * fit_intercept)
    for n in (3, 40, 700):
        inputs = rng.normal(size=(n, n_inputs)) * rng.uniform(0.1, 2.0)
        target = inputs @ rng.normal(size=n_inputs) + 0.3 + rng.normal(size=n) * 0.05
        weights = rng.uniform(0.1, 1.0, n) if weighted else np.ones(n)
        reference = BayesianRidge(fit_intercept=fit_intercept).fit(inputs, target, weights)
        fit = fit_bayesian_ridge(inputs, target, weights, fit_intercept)
        np.testing.assert_allclose(fit.coef, reference.coef_, rtol=1e-9)
        assert fit.intercept == pytest.approx(reference.intercept_, rel=1e-9, abs=1e-12)
        np.testing.assert_allclose(fit.covariance, reference.sigma_, rtol=1e-9)
        assert fit.noise_precision == pytest.approx(reference.alpha_, rel=1e-9)
        assert fit.weight_precision == pytest.approx(reference.lambda_, rel=1e-9)
        assert fit.iterations == reference.n_iter_
        queries = rng.normal(size=(6, n_inputs))
        _, std = reference.predict(queries, return_std=True)
        np.testing.assert_allclose(fit.predictive_std(queries), std, rtol=1e-9)


def test_one_input_by_hand() -> None:
    """One input, no intercept: at the fixed point, w = Σxy / (Σx² + λ/α) and the covariance
    is 1 / (α Σx² + λ) for the α, λ the fit reports."""
    inputs = np.array([[1.0], [2.0], [-1.0], [0.5]])
    target = np.array([2.1, 3.9, -2.0, 1.05])
    fit = fit_bayesian_ridge(inputs, target, np.ones(4), fit_intercept=False)
    sxx, sxy = float(inputs[:, 0] @ inputs[:, 0]), float(inputs[:, 0] @ target)
    alpha, lam = fit.noise_precision, fit.weight_precision
    assert fit.coef[0] == pytest.approx(sxy / (sxx + lam / alpha), rel=1e-12)
    assert fit.covariance[0, 0] == pytest.approx(1.0 / (alpha * sxx + lam), rel=1e-12)
    assert fit.coef[0] == pytest.approx(1.99, abs=0.02)


def test_weights_count_as_repeated_samples() -> None:
    """A weight of 2 is the same sample given twice (the error and Σ w both count it twice)."""
    inputs = np.array([[1.0, 0.2], [0.3, 1.0], [0.7, -0.4]])
    target = np.array([1.0, 0.5, -0.2])
    weighted = fit_bayesian_ridge(inputs, target, np.array([2.0, 1.0, 1.0]), fit_intercept=True)
    repeated = fit_bayesian_ridge(
        np.vstack([inputs[:1], inputs]), np.append(target[0], target), np.ones(4), True
    )
    np.testing.assert_allclose(weighted.coef, repeated.coef, rtol=1e-10)
    assert weighted.intercept == pytest.approx(repeated.intercept, rel=1e-10)


def test_rejects_mismatched_shapes() -> None:
    with pytest.raises(ValueError, match="expected inputs"):
        fit_bayesian_ridge(np.ones((3, 1)), np.ones(4), np.ones(4), False)


@pytest.mark.parametrize(
    ("inputs", "target", "weights", "message"),
    [
        (np.ones((0, 1)), np.ones(0), np.ones(0), "^expected inputs \\(n, k\\) with n >= 1"),
        (np.full((2, 1), np.nan), np.ones(2), np.ones(2), "^expected finite inputs of magnitude"),
        (np.ones((2, 1)), np.array([1.0, 1e60]), np.ones(2), "^expected finite target"),
        (np.ones((2, 1)), np.ones(2), np.array([1.0, np.inf]), "^expected finite weights"),
        (np.ones((2, 1)), np.ones(2), np.array([1.0, -1.0]), "^expected weights >= 0, not all"),
        (np.ones((2, 1)), np.ones(2), np.zeros(2), "^expected weights >= 0, not all 0"),
    ],
)
def test_rejects_data_outside_its_domain(
    inputs: np.ndarray, target: np.ndarray, weights: np.ndarray, message: str
) -> None:
    with pytest.raises(ValueError, match=message):
        fit_bayesian_ridge(inputs, target, weights, False)


def _scikit_learn(
    inputs: np.ndarray, target: np.ndarray, weights: np.ndarray, fit_intercept: bool
) -> BayesianRidge:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return BayesianRidge(fit_intercept=fit_intercept).fit(inputs, target, weights)


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n_inputs=st.integers(1, 3),
    extra_samples=st.integers(3, 80),
    input_scale=st.floats(0.1, 10.0),
    noise=st.floats(0.01, 1.0),
    fit_intercept=st.booleans(),
    weighted=st.booleans(),
)
def test_random_data_match_scikit_learn(
    seed: int,
    n_inputs: int,
    extra_samples: int,
    input_scale: float,
    noise: float,
    fit_intercept: bool,
    weighted: bool,
) -> None:
    """Well-conditioned inputs and a noisy target: scikit-learn is well-defined, and no guard
    acts."""
    rng = np.random.default_rng(seed)
    n = n_inputs + extra_samples
    inputs = rng.normal(size=(n, n_inputs)) * input_scale
    target = inputs @ rng.normal(size=n_inputs) + rng.normal() + rng.normal(size=n) * noise
    weights = rng.uniform(0.2, 2.0, n) if weighted else np.ones(n)
    reference = _scikit_learn(inputs, target, weights, fit_intercept)
    fit = fit_bayesian_ridge(inputs, target, weights, fit_intercept)
    np.testing.assert_allclose(fit.coef, reference.coef_, rtol=1e-6, atol=1e-9)
    assert fit.intercept == pytest.approx(reference.intercept_, rel=1e-6, abs=1e-9)
    np.testing.assert_allclose(fit.covariance, reference.sigma_, rtol=1e-6, atol=1e-12)
    assert fit.noise_precision == pytest.approx(reference.alpha_, rel=1e-6)
    assert fit.weight_precision == pytest.approx(reference.lambda_, rel=1e-6)


@settings(max_examples=80, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(2, 500),
    actions=st.integers(1, 2),
    collinear=st.booleans(),
    residual_scale=st.floats(-17.0, -1.0),
    noisy=st.booleans(),
)
@example(seed=52194, n=2, actions=1, collinear=False, residual_scale=-4.6640625, noisy=True)
def test_a_region_driven_with_one_or_two_actions_matches_scikit_learn(
    seed: int, n: int, actions: int, collinear: bool, residual_scale: float, noisy: bool
) -> None:
    """The kinematic regressions' degenerate case: a slip region the robot crossed with one
    action, or two collinear ones (forward and back), so XᵀX is singular, and a residual as
    small as rounding noise. scikit-learn (SVD) is well-defined there; the unguarded Cholesky
    factor met a zero pivot (ZeroDivisionError) or a negative one (NaN).

    α to 10⁻³: with XᵀX singular, XᵀX + (λ/α) I has a condition number up to ~10¹² (the
    guard's bound), so the rounding of its Cholesky factor moves γ and the squared error, and
    with them α, by up to ~10¹² × 2.2·10⁻¹⁶ ≈ 2·10⁻⁴ (scikit-learn works from an SVD of X
    instead). The example differs by 1.4·10⁻⁵ after the 2 iterations both make."""
    rng = np.random.default_rng(seed)
    chosen = [0, 1] if collinear and actions == 2 else rng.choice(4, actions, replace=False)
    inputs = WHEEL_SPEEDS[rng.choice(chosen, size=n)]
    slopes = rng.normal(size=2) * 10.0**residual_scale
    target = inputs @ slopes + noisy * rng.normal(size=n) * 10.0**residual_scale
    reference = _scikit_learn(inputs, target, np.ones(n), False)
    fit = fit_bayesian_ridge(inputs, target, np.ones(n), False)
    _assert_finite(fit)
    scale = float(np.max(np.abs(target))) + 1e-300
    np.testing.assert_allclose(inputs @ fit.coef, inputs @ reference.coef_, atol=1e-5 * scale)
    assert fit.noise_precision == pytest.approx(reference.alpha_, rel=1e-3)


def _assert_finite(fit: RidgePosterior) -> None:
    values = [*fit.coef, fit.intercept, *fit.covariance.ravel(), *fit.input_offset]
    assert np.all(np.isfinite(values)), fit
    for precision in (fit.noise_precision, fit.weight_precision):
        assert PRECISION_FLOOR <= precision <= 1.0 / PRECISION_FLOOR
    assert np.all(np.diag(fit.covariance) >= 0.0)


def _degenerate_inputs(rng: np.random.Generator, kind: str, n: int, k: int) -> np.ndarray:
    scale = 10.0 ** rng.uniform(-40, 40)
    if kind == "constant":
        return np.tile(rng.normal(size=k) * scale, (n, 1))
    if kind == "collinear":
        return np.outer(rng.normal(size=n), rng.normal(size=k)) * scale
    if kind == "zero":
        return np.zeros((n, k))
    return rng.normal(size=(n, k)) * scale


def _degenerate_target(rng: np.random.Generator, kind: str, inputs: np.ndarray) -> np.ndarray:
    n, k = inputs.shape
    if kind == "exact":  # zero residuals, slopes from tiny to huge
        target = inputs @ (rng.normal(size=k) * 10.0 ** rng.uniform(-30, 30))
    elif kind == "zero":
        target = np.zeros(n)
    elif kind == "constant":
        target = np.full(n, rng.normal() * 10.0 ** rng.uniform(-40, 40))
    else:
        target = rng.normal(size=n) * 10.0 ** rng.uniform(-40, 40)
    return np.clip(target, -MAX_MAGNITUDE, MAX_MAGNITUDE)


@settings(max_examples=300, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(1, 30),
    n_inputs=st.integers(1, 3),
    input_kind=st.sampled_from(["constant", "collinear", "zero", "random"]),
    target_kind=st.sampled_from(["exact", "zero", "constant", "random"]),
    weight_exponent=st.floats(-100.0, 40.0),
    zero_weights=st.booleans(),
    fit_intercept=st.booleans(),
)
def test_degenerate_data_give_a_finite_fit(
    seed: int,
    n: int,
    n_inputs: int,
    input_kind: str,
    target_kind: str,
    weight_exponent: float,
    zero_weights: bool,
    fit_intercept: bool,
) -> None:
    """Any data in the documented domain, however degenerate: no exception, finite outputs
    (scikit-learn itself divides by zero, or returns NaN, on many of these)."""
    rng = np.random.default_rng(seed)
    inputs = np.clip(
        _degenerate_inputs(rng, input_kind, n, n_inputs), -MAX_MAGNITUDE, MAX_MAGNITUDE
    )
    target = _degenerate_target(rng, target_kind, inputs)
    weights = np.full(n, 10.0**weight_exponent) * rng.uniform(0.5, 1.0, n)
    if zero_weights:
        weights[rng.random(n) < 0.5] = 0.0
        weights[rng.integers(n)] = 10.0**weight_exponent
    fit = fit_bayesian_ridge(inputs, target, weights, fit_intercept)
    _assert_finite(fit)
    assert np.all(np.isfinite(fit.predictive_std(inputs)))


DEGENERATE_CASES = {
    "one sample": ([[1.7, 1.7]], [0.3], [1.0]),
    "one action, rounding noise": (
        [[1.7, 1.7]] * 25,
        [2e-15, -1e-15, 3e-15, 0.0, 1e-15] * 5,
        [1.0] * 25,
    ),
    "forward and back, exact": ([[1.7, 1.7], [-1.7, -1.7]] * 10, [0.034, -0.034] * 10, [1.0] * 20),
    "zero inputs": ([[0.0]] * 4, [1.0, -1.0, 2.0, 0.5], [1.0] * 4),
    "tiny weights": ([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]], [1.0, 2.0, 3.5], [1e-30] * 3),
}
"""Hand-made degenerate regressions for the comparison with the interpreter."""

NO_JIT_SCRIPT = """
import json, sys
import numpy as np
from skidnav.models.bayesian_ridge import fit_bayesian_ridge
cases = json.loads(sys.argv[1])
fits = {}
for name, (inputs, target, weights) in cases.items():
    fit = fit_bayesian_ridge(np.array(inputs), np.array(target), np.array(weights), False)
    fits[name] = [*fit.coef.tolist(), *fit.covariance.ravel().tolist(), fit.noise_precision,
                  fit.weight_precision, fit.iterations]
print(json.dumps(fits))
"""


def test_degenerate_fits_are_the_same_without_the_jit() -> None:
    """The guards (clamps, the pivot floor) give bit-identical fits compiled and interpreted
    (an unguarded negative pivot gave NaN compiled and a ValueError interpreted)."""
    compiled: dict[str, Any] = {}
    for name, (inputs, target, weights) in DEGENERATE_CASES.items():
        fit = fit_bayesian_ridge(np.array(inputs), np.array(target), np.array(weights), False)
        _assert_finite(fit)
        compiled[name] = [
            *fit.coef.tolist(), *fit.covariance.ravel().tolist(), fit.noise_precision,
            fit.weight_precision, fit.iterations,
        ]  # fmt: skip
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    env["PYTHONPATH"] = str(Path(__file__).resolve().parents[2] / "src")
    done = subprocess.run(
        [sys.executable, "-c", NO_JIT_SCRIPT, json.dumps(DEGENERATE_CASES)],
        env=env, capture_output=True, text=True, check=True, timeout=120,
    )  # fmt: skip
    assert json.loads(done.stdout) == compiled
