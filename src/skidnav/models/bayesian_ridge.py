"""Bayesian ridge regression by evidence maximization, compiled, for the few inputs of the
kinematic regressions.

The model (MacKay 1992, "Bayesian interpolation"; Tipping 2001; Bishop 2006 §3.5.2): targets
y = Xw + ε with Gaussian noise of precision α (per unit sample weight) and a zero-mean Gaussian
prior on w of precision λ, both hyperparameters given Gamma(10⁻⁶, 10⁻⁶) hyperpriors. Starting
from α = 1 / var(y), λ = 1, each iteration

1. computes the posterior mean w = (XᵀX + (λ/α) I)⁻¹ Xᵀy and the weighted squared error E,
2. the number of well-determined parameters γ = Σᵢ α eᵢ / (λ + α eᵢ) over the eigenvalues eᵢ
   of XᵀX (Bishop eq. 3.91), computed as k − (λ/α) · trace((XᵀX + (λ/α) I)⁻¹),
3. re-estimates λ = (γ + 2·10⁻⁶) / (|w|² + 2·10⁻⁶) and α = (Σ weights − γ + 2·10⁻⁶) /
   (E + 2·10⁻⁶) (eqs. 3.92, 3.95 with the hyperpriors' terms),

until the posterior mean moves by less than ``tol`` in L1 norm (at most ``max_iter`` times),
then recomputes w and the posterior covariance Σ = (α XᵀX + λ I)⁻¹ with the final α, λ. These
are the conventions of scikit-learn's ``BayesianRidge`` (whose names α, λ are used here), and its
results are matched in the tests. Sample weights scale each sample's squared error; with an
intercept the inputs and targets are centred on their weighted means first.

Degenerate data (guards, ours; none of them acts on data scikit-learn fits well, so the results
still match it there). The kinematic regressions meet them: a slip region the robot only drove
straight through gives constant or collinear inputs (one action's wheel speeds, or forward and
back), so XᵀX is singular; a residual of rounding noise gives α ≈ 1/var ≈ 10¹⁶, so λ/α falls
below the rounding of XᵀX's entries and its Cholesky factor meets a zero or negative pivot (a
division by zero, or a NaN). Hence:

* λ/α is at least :data:`SHIFT_FLOOR` × the largest diagonal entry of XᵀX (XᵀX + (λ/α) I then
  has a condition number of at most ~10¹², and its factor is accurate), and each pivot of the
  factor at least λ/α (a bound of exact arithmetic: every pivot is at least the smallest
  eigenvalue of the matrix);
* γ is kept in [0, k] (its exact range is [0, rank XᵀX]) and Σ weights − γ at least 0 (fewer
  samples, by weight, than well-determined parameters: tiny weights, or one sample);
* α and λ are kept in [:data:`PRECISION_FLOOR`, 1 / :data:`PRECISION_FLOOR`] (a squared error or
  a |w|² that overflows would make them 0, and λ/α a division by zero).

With inputs, targets and weights of magnitude at most :data:`MAX_MAGNITUDE` (checked) the fit is
then finite for any data: zero residuals, constant or all-zero inputs, one sample, tiny or huge
weights (tested against scikit-learn with hypothesis).

Where the time goes: the kinematic model refits 3 regressions per slip region; through
scikit-learn most of a refit was input validation (21 regions: ~0.3 s per refit, about half of
dyna-kinematic's trainer time at 1000 planning steps). Here the data enter once as the k × k
Gram matrix and the k-vector Xᵀy (k ≤ 2 in skidnav), and each iteration costs O(n·k) for E.
Every sum is a plain loop (no BLAS or LAPACK, whose orders of summation differ between the
libraries numba and NumPy call), so the fit is the same bit for bit with and without the JIT.

>>> x = np.array([[1.0], [2.0], [3.0], [4.0]])
>>> fit = fit_bayesian_ridge(x, 2.0 * x[:, 0] + np.array([0.01, -0.01, 0.01, -0.01]),
...                          np.ones(4), False)
>>> round(float(fit.coef[0]), 3), float(fit.intercept)
(1.999, 0.0)
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from skidnav._jit import jit

HYPERPRIOR = 1e-6
"""Shape and rate of the Gamma hyperpriors on α and λ."""
SHIFT_FLOOR = 1e-12
"""Least λ/α, relative to the largest diagonal entry of XᵀX (module docstring)."""
PRECISION_FLOOR = 1e-100
"""Least α and λ; 1 / PRECISION_FLOOR is the greatest (module docstring)."""
MAX_MAGNITUDE = 1e50
"""Greatest magnitude of an input, a target or a weight: the sums of their squares stay finite."""


class RidgePosterior(NamedTuple):
    """A fitted regression.

    Attributes:
        coef: float64 (k,) posterior mean of the slopes.
        intercept: the intercept (0 without one).
        covariance: float64 (k, k) posterior covariance Σ of the slopes.
        noise_precision: α, per unit sample weight.
        weight_precision: λ.
        input_offset: float64 (k,) the weighted input means the inputs were centred on (zeros
            without an intercept).
        iterations: evidence iterations made.
    """

    coef: np.ndarray
    intercept: float
    covariance: np.ndarray
    noise_precision: float
    weight_precision: float
    input_offset: np.ndarray
    iterations: int

    def predictive_std(self, inputs: np.ndarray) -> np.ndarray:
        """Standard deviation of the posterior predictive at ``inputs`` (n, k): the noise
        1/α plus the parameter variance xᵀΣx of the centred inputs (Bishop eq. 3.59)."""
        centred = np.asarray(inputs, dtype=np.float64) - self.input_offset
        spread = np.einsum("ij,jk,ik->i", centred, self.covariance, centred)
        return np.asarray(np.sqrt(spread + 1.0 / self.noise_precision))


@jit
def _clamped(precision: float) -> float:
    """``precision`` within [PRECISION_FLOOR, 1 / PRECISION_FLOOR] (a NaN: the floor)."""
    if not precision >= PRECISION_FLOOR:
        return PRECISION_FLOOR
    return min(precision, 1.0 / PRECISION_FLOOR)


@jit
def _shift(lam: float, alpha: float, largest: float) -> float:
    """λ/α, at least SHIFT_FLOOR × ``largest`` (the largest diagonal entry of XᵀX)."""
    return max(lam / alpha, SHIFT_FLOOR * largest)


@jit
def _cholesky(gram: np.ndarray, shift: float) -> np.ndarray:
    """The lower Cholesky factor L of gram + shift · I (gram a symmetric positive semi-definite
    k × k matrix, shift > 0). Each pivot is at least ``shift``, as in exact arithmetic, so none
    is zero or negative after rounding."""
    k = gram.shape[0]
    factor = np.zeros((k, k))
    for i in range(k):
        for j in range(i + 1):
            value = gram[i, j] + (shift if i == j else 0.0)
            for m in range(j):
                value -= factor[i, m] * factor[j, m]
            if i == j:
                factor[i, i] = math.sqrt(value if value >= shift else shift)
            else:
                factor[i, j] = value / factor[j, j]
    return factor


@jit
def _inverse_shifted(gram: np.ndarray, shift: float) -> np.ndarray:
    """(gram + shift · I)⁻¹ by the Cholesky factor L (:func:`_cholesky`) and forward
    substitution ((LLᵀ)⁻¹ = L⁻ᵀL⁻¹). Plain loops, not LAPACK or BLAS: their summation orders
    differ between libraries, and the results must be the same compiled and interpreted."""
    k = gram.shape[0]
    factor = _cholesky(gram, shift)
    lower_inverse = np.zeros((k, k))
    for column in range(k):
        for i in range(column, k):
            value = 1.0 if i == column else 0.0
            for m in range(column, i):
                value -= factor[i, m] * lower_inverse[m, column]
            lower_inverse[i, column] = value / factor[i, i]
    inverse = np.zeros((k, k))
    for i in range(k):
        for j in range(k):
            total = 0.0
            for m in range(max(i, j), k):
                total += lower_inverse[m, i] * lower_inverse[m, j]
            inverse[i, j] = total
    return inverse


@jit
def _times(matrix: np.ndarray, vector: np.ndarray) -> np.ndarray:
    """matrix (k, k) · vector (k,) in plain loops (see :func:`_inverse_shifted`)."""
    out = np.zeros(matrix.shape[0])
    for i in range(matrix.shape[0]):
        for j in range(matrix.shape[1]):
            out[i] += matrix[i, j] * vector[j]
    return out


@jit
def _gram(inputs: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(XᵀX (k, k), Xᵀy (k,)) of ``inputs`` X (n, k) and ``target`` y (n,)."""
    n, k = inputs.shape
    gram = np.zeros((k, k))
    projected = np.zeros(k)
    for row in range(n):
        for i in range(k):
            projected[i] += inputs[row, i] * target[row]
            for j in range(k):
                gram[i, j] += inputs[row, i] * inputs[row, j]
    return gram, projected


@jit
def _squared_error(inputs: np.ndarray, target: np.ndarray, coef: np.ndarray) -> float:
    """E = |y − Xw|² of ``inputs`` X (n, k), ``target`` y (n,) and ``coef`` w (k,)."""
    error = 0.0
    for row in range(inputs.shape[0]):
        residual = target[row]
        for column in range(inputs.shape[1]):
            residual -= inputs[row, column] * coef[column]
        error += residual * residual
    return error


@jit
def _precisions(
    inverse: np.ndarray, shift: float, coef: np.ndarray, error: float, weight_sum: float
) -> tuple[float, float]:
    """The re-estimated (λ, α) of step 3 of the module docstring, from A⁻¹ (k, k) of
    A = XᵀX + ``shift`` · I, the posterior mean (k,) and its squared error, guarded."""
    k = inverse.shape[0]
    trace, norm = 0.0, 0.0
    for i in range(k):
        trace += inverse[i, i]
        norm += coef[i] * coef[i]
    gamma = min(max(k - shift * trace, 0.0), float(k))
    lam = _clamped((gamma + 2.0 * HYPERPRIOR) / (norm + 2.0 * HYPERPRIOR))
    free = max(weight_sum - gamma, 0.0)
    return lam, _clamped((free + 2.0 * HYPERPRIOR) / (error + 2.0 * HYPERPRIOR))


@jit
def _moment_error(
    gram: np.ndarray, projected: np.ndarray, target_ss: float, coef: np.ndarray
) -> float:
    """E = yᵀy − 2wᵀXᵀy + wᵀXᵀXw from the moments (XᵀX, Xᵀy, yᵀy), at least 0 (rounding
    can make the difference of nearly equal sums negative)."""
    error = target_ss
    for i in range(coef.shape[0]):
        error -= 2.0 * coef[i] * projected[i]
        for j in range(coef.shape[0]):
            error += coef[i] * gram[i, j] * coef[j]
    return max(error, 0.0)


@jit
def _evidence_iterations(
    inputs: np.ndarray,
    target: np.ndarray,
    weight_sum: float,
    target_variance: float,
    max_iter: int,
    tol: float,
) -> tuple[np.ndarray, np.ndarray, float, float, int]:
    """The evidence loop of the module docstring on prepared data: ``inputs`` (n, k) and
    ``target`` (n,) already centred if need be and multiplied by √w; ``weight_sum`` = Σ w.
    Returns (coef (k,), covariance (k, k), α, λ, iterations) of :func:`_evidence_loop`."""
    gram, projected = _gram(inputs, target)
    return _evidence_loop(
        gram, projected, 0.0, inputs, target, weight_sum, target_variance, max_iter, tol
    )


@jit
def _evidence_loop(
    gram: np.ndarray,
    projected: np.ndarray,
    target_ss: float,
    inputs: np.ndarray,
    target: np.ndarray,
    weight_sum: float,
    target_variance: float,
    max_iter: int,
    tol: float,
) -> tuple[np.ndarray, np.ndarray, float, float, int]:
    """The evidence loop on the Gram matrix ``gram`` (k, k) and ``projected`` = Xᵀy (k,):
    the squared error E from the data ``inputs`` (n, k), ``target`` (n,) when n > 0, else from
    the moments with ``target_ss`` = yᵀy (:func:`_moment_error`). With A = XᵀX + (λ/α) I:
    w = A⁻¹Xᵀy, γ = k − (λ/α) · trace(A⁻¹) (the eigenvalue sum of the module docstring),
    Σ = A⁻¹ / α, each guarded as the module docstring says. Returns (coef (k,), covariance
    (k, k), α, λ, iterations)."""
    k = gram.shape[0]
    largest = 0.0
    for i in range(k):
        largest = max(largest, gram[i, i])
    alpha = _clamped(1.0 / (target_variance + np.finfo(np.float64).eps))
    lam = 1.0
    previous = np.zeros(k)
    iterations = max_iter
    for iteration in range(max_iter):
        shift = _shift(lam, alpha, largest)
        inverse = _inverse_shifted(gram, shift)
        coef = _times(inverse, projected)
        if inputs.shape[0] > 0:
            error = _squared_error(inputs, target, coef)
        else:
            error = _moment_error(gram, projected, target_ss, coef)
        lam, alpha = _precisions(inverse, shift, coef, error, weight_sum)
        moved = 0.0
        for i in range(k):
            moved += abs(previous[i] - coef[i])
        if iteration != 0 and moved < tol:
            iterations = iteration + 1
            break
        previous[:] = coef
    inverse = _inverse_shifted(gram, _shift(lam, alpha, largest))
    return _times(inverse, projected), inverse / alpha, alpha, lam, iterations


def fit_bayesian_ridge(
    inputs: np.ndarray,
    target: np.ndarray,
    weights: np.ndarray,
    fit_intercept: bool,
    max_iter: int = 300,
    tol: float = 1e-3,
) -> RidgePosterior:
    """Fit y ≈ inputs · coef (+ intercept) by evidence maximization (module docstring).

    Args:
        inputs: float64 (n, k), n ≥ 1. target: float64 (n,). weights: (n,), ≥ 0, not all 0.
            All finite and of magnitude at most :data:`MAX_MAGNITUDE`.
        fit_intercept: centre on the weighted means and fit an intercept.
        max_iter, tol: the evidence loop's limit and its L1 tolerance on the posterior mean.

    Raises:
        ValueError: for arrays of other shapes or values.
    """
    inputs = np.asarray(inputs, dtype=np.float64)
    target = np.asarray(target, dtype=np.float64)
    weights = np.asarray(weights, dtype=np.float64)
    _check_data(inputs, target, weights)
    weight_sum = float(weights.sum())
    target_mean = float(np.average(target, weights=weights))
    target_variance = float(np.average((target - target_mean) ** 2, weights=weights))
    if fit_intercept:
        offset = np.average(inputs, axis=0, weights=weights)
        inputs, target = inputs - offset, target - target_mean
    else:
        offset = np.zeros(inputs.shape[1])
    root = np.sqrt(weights)
    coef, covariance, alpha, lam, iterations = _evidence_iterations(
        inputs * root[:, None], target * root, weight_sum, target_variance, max_iter, tol
    )
    intercept = target_mean - float(offset @ coef) if fit_intercept else 0.0
    return RidgePosterior(coef, intercept, covariance, float(alpha), float(lam), offset, iterations)


def fit_bayesian_ridge_moments(
    moments: np.ndarray,
    fit_intercept: bool,
    max_iter: int = 300,
    tol: float = 1e-3,
) -> RidgePosterior:
    """:func:`fit_bayesian_ridge` from the weighted moments of the data instead of the data:
    equal to it up to floating-point rounding (the squared error E comes from
    yᵀy − 2wᵀXᵀy + wᵀXᵀXw rather than from a pass over the samples), at a cost that does not
    grow with the number of samples.

    Args:
        moments: float64 (k + 2, k + 2), Σᵢ wᵢ zᵢ zᵢᵀ over the samples with
            zᵢ = (xᵢ (k,), 1, yᵢ): the weighted Gram matrix of the inputs, a column of ones and
            the target; its entry (k, k) (Σ w) must be > 0.
        fit_intercept, max_iter, tol: as :func:`fit_bayesian_ridge`.
    """
    k = moments.shape[0] - 2
    weight_sum = float(moments[k, k])
    if not weight_sum > 0.0:
        raise ValueError(f"expected a positive weight sum, got {weight_sum:g}")
    gram, projected = moments[:k, :k], moments[:k, k + 1]
    input_sum, target_sum, target_ss = moments[:k, k], moments[k, k + 1], moments[k + 1, k + 1]
    target_mean = float(target_sum) / weight_sum
    target_variance = max(float(target_ss) / weight_sum - target_mean * target_mean, 0.0)
    if fit_intercept:
        offset = input_sum / weight_sum
        gram = gram - np.outer(input_sum, offset)
        projected = projected - input_sum * target_mean
        target_ss = max(float(target_ss) - target_sum * target_mean, 0.0)
    else:
        offset = np.zeros(k)
    empty = np.zeros((0, k))
    coef, covariance, alpha, lam, iterations = _evidence_loop(
        np.ascontiguousarray(gram), np.ascontiguousarray(projected), float(target_ss),
        empty, np.zeros(0), weight_sum, target_variance, max_iter, tol,
    )  # fmt: skip
    intercept = target_mean - float(offset @ coef) if fit_intercept else 0.0
    return RidgePosterior(coef, intercept, covariance, float(alpha), float(lam), offset, iterations)


def _check_data(inputs: np.ndarray, target: np.ndarray, weights: np.ndarray) -> None:
    """ValueError unless the arrays are as :func:`fit_bayesian_ridge` requires."""
    if (
        inputs.ndim != 2
        or len(inputs) == 0
        or target.shape != (len(inputs),)
        or weights.shape != target.shape
    ):
        raise ValueError(
            f"expected inputs (n, k) with n >= 1, target (n,) and weights (n,), got "
            f"{inputs.shape}, {target.shape} and {weights.shape}"
        )
    for name, values in (("inputs", inputs), ("target", target), ("weights", weights)):
        if not np.all(np.abs(values) <= MAX_MAGNITUDE):  # NaN fails too
            raise ValueError(
                f"expected finite {name} of magnitude at most {MAX_MAGNITUDE:g}, got "
                f"{values.min():g} .. {values.max():g}"
            )
    if not (np.all(weights >= 0.0) and weights.sum() > 0.0):
        raise ValueError(
            f"expected weights >= 0, not all 0, got {weights.min():g} .. {weights.max():g}"
        )
