"""The regressions of one slip region of the learned kinematic model
(:mod:`skidnav.models.kinematic`): the nominal prior, the fit of the three regressions on the
residual of a parent's coefficients, their physical (ICR) reading and their predictive spread.

Coefficients, shape (8,): ``[vx_wl, vx_wr, vx_b, yaw_wl, yaw_wr, yaw_b, vy_yaw, vy_b]``, with

    v_x      ≈ vx_wl·ω_L + vx_wr·ω_R (+ vx_b)
    yaw_rate ≈ yaw_wl·ω_L + yaw_wr·ω_R (+ yaw_b)
    v_y      ≈ vy_yaw·yaw_rate (+ vy_b)
"""

from __future__ import annotations

import numpy as np

from skidnav.models.bayesian_ridge import (
    RidgePosterior,
    fit_bayesian_ridge,
    fit_bayesian_ridge_moments,
)
from skidnav.robot.params import RobotParams

N_COEFFICIENTS = 8
"""Columns of :attr:`~skidnav.models.kinematic.KinematicModel.coefficients`:
``[vx_wl, vx_wr, vx_b, yaw_wl, yaw_wr, yaw_b, vy_yaw, vy_b]``."""
Posterior = tuple[RidgePosterior | None, RidgePosterior | None, RidgePosterior | None]
"""The fitted regressions of a region (v_x, yaw_rate, v_y); None where nothing was fitted."""


def nominal_coefficients(robot: RobotParams) -> np.ndarray:
    """The prior: coefficients of the nominal (slip-free) robot, shape (8,)."""
    half = robot.wheel_radius / 2.0
    turn = robot.wheel_radius / (2.0 * robot.half_track)
    return np.array([half, half, 0.0, -turn, turn, 0.0, -robot.x_icr, 0.0])


def icr_parameters(
    vx_coefficients: np.ndarray, yaw_coefficients: np.ndarray, vy_slope: np.ndarray | float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ICR model's reading of the thesis's three regressions (v_x and yaw rate on
    (ω_L, ω_R), v_y on the yaw rate): effective wheel radius r = β_L + β_R [m], effective half
    track c = r / (γ_R − γ_L) [m], x_ICR = −s [m] (Kozłowski & Pazderski 2004). Used by the
    learned model (:meth:`~skidnav.models.kinematic.KinematicModel.estimates`) and the floor
    calibration (:mod:`skidnav.physics.calibration`).

    Args:
        vx_coefficients: (β_L, β_R) of v_x on (ω_L, ω_R) [m/rad], shape (..., 2).
        yaw_coefficients: (γ_L, γ_R) of the yaw rate on (ω_L, ω_R) [1], shape (..., 2).
        vy_slope: s of v_y on the yaw rate [m], shape (...) (a scalar for one fit).

    Returns:
        (r, c, x_ICR), each of shape (...): one set per fit or per posterior draw.

    >>> r, c, x_icr = icr_parameters(np.array([0.01125, 0.01125]),
    ...                              np.array([-0.1875, 0.1875]), -0.05)
    >>> round(float(r), 4), round(float(c), 4), round(float(x_icr), 4)
    (0.0225, 0.06, 0.05)
    """
    beta, gamma = np.asarray(vx_coefficients), np.asarray(yaw_coefficients)
    radius = beta.sum(axis=-1)
    return radius, radius / (gamma[..., 1] - gamma[..., 0]), -np.asarray(vy_slope)


def fit_coefficients(
    samples: np.ndarray, weights: np.ndarray, base: np.ndarray, fit_intercept: bool
) -> tuple[np.ndarray, Posterior]:
    """Fit the three regressions on the residual of ``base`` coefficients (8,).

    Args:
        samples: free sub-steps (ω_L [rad/s], ω_R [rad/s], v_x [m/s], v_y [m/s],
            yaw_rate [rad/s]), shape (n, 5).
        weights: forgetting weight of each sample, shape (n,).
        base: the parent's coefficients, shape (8,) (columns of :data:`N_COEFFICIENTS`).
        fit_intercept: fit the intercepts vx_b, yaw_b, vy_b.

    Returns:
        The coefficients (8,) and the fitted regressions (v_x, yaw_rate, v_y).
    """
    wheels = samples[:, 0:2]
    v_x, v_y, yaw_rate = samples[:, 2], samples[:, 3], samples[:, 4]
    out = base.copy()
    out[0:3], vx_fit = _ridge(wheels, v_x, weights, base[0:3], fit_intercept)
    out[3:6], yaw_fit = _ridge(wheels, yaw_rate, weights, base[3:6], fit_intercept)
    out[6:8], vy_fit = _ridge(yaw_rate[:, None], v_y, weights, base[6:8], fit_intercept)
    return out, (vx_fit, yaw_fit, vy_fit)


EXACT_RESIDUAL = 1e-15
"""A residual of at most this (in the output's unit) is rounding: nothing to fit."""


def _ridge(
    inputs: np.ndarray,
    target: np.ndarray,
    weights: np.ndarray,
    base: np.ndarray,
    fit_intercept: bool,
) -> tuple[np.ndarray, RidgePosterior | None]:
    """Bayesian ridge on ``target − base·[inputs, 1]``; returns base + (coef, intercept) and
    the regression (None when the residual is zero: nothing to fit)."""
    slopes, intercept = base[:-1], base[-1]
    residual = target - inputs @ slopes - intercept
    if not np.any(np.abs(residual) > EXACT_RESIDUAL):
        return base.copy(), None
    regression = fit_bayesian_ridge(inputs, residual, weights, fit_intercept)
    coefficients: np.ndarray = base + np.append(regression.coef, regression.intercept)
    return coefficients, regression


_MOMENT_REGRESSIONS = (((0, 1), 4, slice(0, 3)), ((0, 1), 6, slice(3, 6)), ((3,), 5, slice(6, 8)))
"""Per regression (v_x, yaw_rate, v_y): its input columns and target column among
:data:`~skidnav.models.kinematic_moments.MOMENT_COLUMNS`, and its coefficients."""


def fit_from_moments(
    moments: np.ndarray, base: np.ndarray, prior: np.ndarray, fit_intercept: bool
) -> tuple[np.ndarray, Posterior]:
    """:func:`fit_coefficients` from the moments of the samples
    (:mod:`skidnav.models.kinematic_moments`, taken against ``prior``) instead of the samples:
    the same fit up to floating-point rounding, at a cost independent of their number.

    Args:
        moments: float64 (7, 7), Σ w z zᵀ over the samples (columns
            :data:`~skidnav.models.kinematic_moments.MOMENT_COLUMNS`).
        base: the parent's coefficients (8,). prior: the coefficients the moments' residual
            columns are taken against (8,). fit_intercept: fit the intercepts.

    Returns:
        The coefficients (8,) and the fitted regressions (v_x, yaw_rate, v_y). A regression
        counts as exact (None) when its residual's weighted mean square is at most
        :data:`EXACT_RESIDUAL`², where :func:`fit_coefficients` asks every residual to be at
        most :data:`EXACT_RESIDUAL` (the same verdict on a floor equal to the parent, up to
        the rounding of the moments).
    """
    out = base.copy()
    fits: list[RidgePosterior | None] = []
    for inputs, target, coefficients in _MOMENT_REGRESSIONS:
        k = len(inputs)
        columns = [*inputs, 2, target]
        # (x, 1, y − prior) ↦ (x, 1, y − base): the residual of the parent, a linear map
        to_residual = np.eye(k + 2)
        to_residual[k + 1, : k + 1] = -(base[coefficients] - prior[coefficients])
        residual = to_residual @ moments[np.ix_(columns, columns)] @ to_residual.T
        if not residual[k + 1, k + 1] > EXACT_RESIDUAL**2 * residual[k, k]:
            fits.append(None)
            continue
        regression = fit_bayesian_ridge_moments(residual, fit_intercept)
        out[coefficients] = base[coefficients] + np.append(regression.coef, regression.intercept)
        fits.append(regression)
    return out, (fits[0], fits[1], fits[2])


def _spread(regression: RidgePosterior | None, inputs: np.ndarray) -> np.ndarray:
    """Posterior predictive standard deviation of one regression at ``inputs`` (n, k)."""
    if regression is None:
        return np.zeros(len(inputs))
    return regression.predictive_std(inputs)


def twist_std(
    posterior: Posterior, wheels: np.ndarray, yaw: np.ndarray, vy_yaw: np.ndarray
) -> np.ndarray:
    """(n, 3) standard deviations of (v_x, v_y, yaw_rate): v_y's adds vy_yaw² · var(yaw_rate)."""
    vx_fit, yaw_fit, vy_fit = posterior
    yaw_std = _spread(yaw_fit, wheels)
    vy_std = np.hypot(_spread(vy_fit, yaw[:, None]), vy_yaw * yaw_std)
    return np.stack([_spread(vx_fit, wheels), vy_std, yaw_std], axis=1)
