"""The compiled evidence maximization against scikit-learn's BayesianRidge, and by hand."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.linear_model import BayesianRidge

from skidnav.models.bayesian_ridge import fit_bayesian_ridge


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
