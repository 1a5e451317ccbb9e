"""The learned kinematic model as the rollouts sample it: posterior mean, posterior factors and
sub-step noise of every slip region, and the compiled twist of one sampled model.

The model is ``dyna-kinematic``'s (:class:`~skidnav.models.kinematic.KinematicModel`: per slip
region, Bayesian ridge regressions of v_x and the yaw rate on the commanded wheel speeds
(ω_L, ω_R), and of v_y on the yaw rate, thesis; MacKay 1992). Each regression's posterior is
Gaussian, mean w and covariance Σ, with noise precision α (Bishop 2006 §3.3). A rollout draws the
model once, the role one member of an ensemble plays in PETS (Chua et al. 2018, trajectory
sampling): standard normals z (5,) per sequence give the slopes w + L z (L the Cholesky factor of
Σ: two for v_x, two for the yaw rate, one for v_y), and each control step adds the regressions'
noise, standard normals n (3,) scaled by 1/√α and by 1/√s for s sub-steps per control step (the
mean of s independent sub-step noises). One z serves every region a sequence crosses. A
prediction at inputs x is then w·x + b + (L z)·(x − x̄), x̄ the inputs' centre of a regression
with an intercept (0 without), which keeps the intercept's posterior mean at the inputs' centre.

Before a region has a fit (no posterior since construction), its slopes are the model's current
coefficients (the nominal robot,
:func:`~skidnav.models.kinematic_regression.nominal_coefficients`, before any fit) with a
diagonal factor of ``prior_spread`` × |nominal slope| and no noise: the stated prior of the
agent. With a model held at given coefficients (``kinematic_model = "true"``) the factors and the
noise are 0.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from skidnav._jit import inline_jit
from skidnav.models.bayesian_ridge import RidgePosterior
from skidnav.models.kinematic import KinematicModel
from skidnav.models.kinematic_regression import N_COEFFICIENTS, nominal_coefficients
from skidnav.robot.params import RobotParams

N_FACTORS = 7
"""Columns of :attr:`SampledDynamics.factors`: the lower Cholesky factors of the slope
covariances, ``[vx_00, vx_10, vx_11, yaw_00, yaw_10, yaw_11, vy_00]``."""
N_DRAWS = 5
"""Standard normals per sequence: two for v_x's slopes, two for the yaw rate's, one for v_y's."""
N_OFFSETS = 5
"""Columns of :attr:`SampledDynamics.offsets`: ``[vx ω_L, vx ω_R, yaw ω_L, yaw ω_R, vy yaw]``."""


class SampledDynamics(NamedTuple):
    """The kinematic model as the rollout kernel samples it, per flat slip region.

    Attributes:
        mean: float64 (n_regions, 8) posterior-mean coefficients
            ``[vx_wl, vx_wr, vx_b, yaw_wl, yaw_wr, yaw_b, vy_yaw, vy_b]``
            (:data:`~skidnav.models.kinematic_regression.N_COEFFICIENTS`).
        factors: float64 (n_regions, 7) Cholesky factors of the slope covariances
            (:data:`N_FACTORS`) [m/rad for v_x, 1 for the yaw rate and v_y's slope in m].
        offsets: float64 (n_regions, 5) the centres x̄ of the regressions' inputs (zeros without
            intercepts) [rad/s; rad/s for v_y's input, the yaw rate].
        noise_std: float64 (n_regions, 3) the noise 1/√α of one sub-step (v_x [m/s],
            v_y [m/s], yaw_rate [rad/s]).
    """

    mean: np.ndarray
    factors: np.ndarray
    offsets: np.ndarray
    noise_std: np.ndarray


def prior_dynamics(model: KinematicModel, prior_spread: float) -> SampledDynamics:
    """The dynamics of a model no region of which is fitted: its coefficients, the prior spread
    ``prior_spread`` × |nominal slope| (relative, ≥ 0) on every slope, no noise."""
    n_regions = model.coefficients.shape[0]
    slopes = np.abs(nominal_coefficients(model.robot))
    diagonal = prior_spread * slopes[[0, 1, 1, 3, 4, 4, 6]]
    diagonal[[1, 4]] = 0.0  # the off-diagonal entries of the two 2 × 2 factors
    return SampledDynamics(
        mean=model.coefficients.copy(),
        factors=np.tile(diagonal, (n_regions, 1)),
        offsets=np.zeros((n_regions, N_OFFSETS)),
        noise_std=np.zeros((n_regions, 3)),
    )


def fixed_dynamics(coefficients: np.ndarray) -> SampledDynamics:
    """Dynamics held at ``coefficients`` (n_regions, 8), without spread or noise."""
    mean = np.array(coefficients, dtype=np.float64)
    n_regions = mean.shape[0]
    return SampledDynamics(
        mean, np.zeros((n_regions, N_FACTORS)), np.zeros((n_regions, N_OFFSETS)),
        np.zeros((n_regions, 3)),
    )  # fmt: skip


def lattice_coefficients(model: KinematicModel, mean: np.ndarray, guard: str) -> np.ndarray:
    """The coefficients (n_regions, 8) the cost-to-go's lattice predicts its full-speed actions
    with: the model's ``mean`` in a region whose fit has seen fast commands, and the prior (the
    datasheet's robot) elsewhere. How fast commands are counted is the ``guard``
    (``MPPIConfig.lattice_guard``):

    * "rings": the region's own fastest speed ring
      (:meth:`~skidnav.models.kinematic.KinematicModel.ring_counts`) holds ``min_samples``
      samples ever fed, or, for a region still on the pooled fit, all regions' fastest rings
      together do; with one ring this cannot tell, and the model's ``mean`` is used everywhere;
    * "window": the region's kept samples hold ``min_samples`` fast commands
      (:meth:`~skidnav.models.kinematic.KinematicModel.fast_counts`), or, for a region still on
      the pooled fit, all regions' kept samples together do, whatever the rings.

    A model that is held (not learned) is the ``mean`` everywhere.

    Why: on a floor whose wheels lose speed below a threshold (the slippery floors' η), slow
    commands barely move the robot, and a linear fit on them alone predicts a full-speed action a
    fraction of its true length (measured on maze world 3: 10 mm/s against 35 mm/s forward,
    0.07 rad/s against 0.58 rad/s turning, after one episode of mostly slow commands near walls;
    on a held-out `slippery` maze, 2.4 mm/s against about 19 mm/s after a window of 82 % slow
    commands). A lattice of such actions never leaves its cells and heading bins, every state
    of the region is unreached, and the plan averages to standing still, which logs more slow
    samples (docs/agents/mppi-kinematic.md, "A pocket the fit cannot leave"). The datasheet is
    the better guess at a speed never commanded."""
    if model.held or (guard == "rings" and model.config.speed_strata == 1):
        return mean.copy()
    needed = model.config.min_samples
    fast = model.ring_counts()[:, -1] if guard == "rings" else model.fast_counts()
    own_fit = model.counts >= needed
    informed = np.where(own_fit, fast >= needed, fast.sum() >= needed)
    prior = nominal_coefficients(model.robot)
    return np.where(informed[:, None], mean, prior[None, :])


def update_dynamics(dynamics: SampledDynamics, model: KinematicModel) -> None:
    """After a refit: the model's coefficients as the mean, and the factors, centres and noise
    of every region that has a posterior (the others keep theirs: the prior's before their
    first fit, and after a load the ones saved), in place."""
    dynamics.mean[...] = model.coefficients
    for region in range(dynamics.mean.shape[0]):
        posterior = model.posterior(region)
        if posterior is None:
            continue
        for output, regression in enumerate(posterior):
            _set_output(dynamics, region, output, regression)


_FACTOR_COLUMNS = ((0, 1, 2), (3, 4, 5), (6,))
_OFFSET_COLUMNS = ((0, 1), (2, 3), (4,))
_NOISE_COLUMN = (0, 2, 1)  # v_x, yaw rate, v_y: the order of a Posterior


def _set_output(
    dynamics: SampledDynamics, region: int, output: int, regression: RidgePosterior | None
) -> None:
    """One regression's factor, input centre and noise (zeros for an exact fit, None)."""
    factor_columns, offset_columns = _FACTOR_COLUMNS[output], _OFFSET_COLUMNS[output]
    if regression is None:
        dynamics.factors[region, list(factor_columns)] = 0.0
        dynamics.offsets[region, list(offset_columns)] = 0.0
        dynamics.noise_std[region, _NOISE_COLUMN[output]] = 0.0
        return
    dynamics.factors[region, list(factor_columns)] = lower_factor(regression.covariance)
    dynamics.offsets[region, list(offset_columns)] = regression.input_offset
    dynamics.noise_std[region, _NOISE_COLUMN[output]] = 1.0 / math.sqrt(regression.noise_precision)


def lower_factor(covariance: np.ndarray) -> np.ndarray:
    """The lower Cholesky factor of a 1 × 1 or 2 × 2 covariance, packed row by row
    (``[l00]`` or ``[l00, l10, l11]``); a pivot that rounding made negative counts as 0.

    >>> lower_factor(np.array([[4.0, 2.0], [2.0, 5.0]])).tolist()
    [2.0, 1.0, 2.0]
    """
    first = math.sqrt(max(float(covariance[0, 0]), 0.0))
    if covariance.shape[0] == 1:
        return np.array([first])
    below = float(covariance[1, 0]) / first if first > 0.0 else 0.0
    second = math.sqrt(max(float(covariance[1, 1]) - below * below, 0.0))
    return np.array([first, below, second])


def true_coefficients_check(coefficients: np.ndarray | None, n_regions: int) -> np.ndarray:
    """``coefficients`` as float64 (n_regions, 8) if it is that and finite; ValueError
    otherwise."""
    table = np.asarray(coefficients, dtype=np.float64) if coefficients is not None else None
    if table is None or table.shape != (n_regions, N_COEFFICIENTS) or not np.isfinite(table).all():
        raise ValueError(
            f"expected true coefficients of {n_regions} × {N_COEFFICIENTS} finite numbers for "
            "kinematic_model 'true'"
        )
    return table.copy()


def nominal_speeds(robot: RobotParams) -> tuple[float, float]:
    """The nominal robot's top forward speed r·Ω [m/s] and top yaw rate r·Ω/c [rad/s] within
    the wheel-speed bound Ω: the cost-to-go's conversion of metres and radians to time."""
    top = robot.wheel_radius * robot.wheel_speed
    return top, top / robot.half_track


def top_speeds(coefficients: np.ndarray, wheel_speed: float) -> tuple[float, float] | None:
    """The fastest forward speed [m/s] (both wheels at ``wheel_speed`` Ω [rad/s]) and turn rate
    [rad/s] (the wheels at ∓Ω) that any region's ``coefficients`` (n_regions, 8) give; None
    unless both are > 0 (a fit that does not drive forward or turn)."""
    forward = (coefficients[:, 0] + coefficients[:, 1]) * wheel_speed + coefficients[:, 2]
    turn = np.abs(coefficients[:, 4] - coefficients[:, 3]) * wheel_speed
    fastest, turning = float(forward.max()), float(turn.max())
    return (fastest, turning) if fastest > 0.0 and turning > 0.0 else None


@inline_jit
def sampled_twist(
    dynamics: SampledDynamics,
    region: int,
    omega_left: float,
    omega_right: float,
    draws: np.ndarray,
    noise: np.ndarray,
    row: int,
    step: int,
    noise_scale: float,
) -> tuple[float, float, float]:
    """Body twist (v_x [m/s], v_y [m/s], yaw_rate [rad/s]) of one sampled model (module doc) in
    ``region`` for the commanded wheel speeds [rad/s].

    Args:
        dynamics: the sampled model's arrays. draws: float64 (n, 5) standard normals of the
            slopes, ``draws[row]`` the rollout's. noise: float64 (n, H, 3) standard normals of
            the noise (v_x, v_y, yaw rate), ``noise[row, step]`` this control step's (read by
            index: a view per sub-step would cost more than the twist). noise_scale:
            1/√(sub-steps per control step), or 0 for no noise.
    """
    m, f, o = dynamics.mean, dynamics.factors, dynamics.offsets
    d_left = f[region, 0] * draws[row, 0]
    d_right = f[region, 1] * draws[row, 0] + f[region, 2] * draws[row, 1]
    v_x = m[region, 0] * omega_left + m[region, 1] * omega_right + m[region, 2]
    v_x += d_left * (omega_left - o[region, 0]) + d_right * (omega_right - o[region, 1])
    d_left = f[region, 3] * draws[row, 2]
    d_right = f[region, 4] * draws[row, 2] + f[region, 5] * draws[row, 3]
    yaw_rate = m[region, 3] * omega_left + m[region, 4] * omega_right + m[region, 5]
    yaw_rate += d_left * (omega_left - o[region, 2]) + d_right * (omega_right - o[region, 3])
    yaw_rate += noise_scale * dynamics.noise_std[region, 2] * noise[row, step, 2]
    v_y = (
        m[region, 6] * yaw_rate
        + m[region, 7]
        + f[region, 6] * draws[row, 4] * (yaw_rate - o[region, 4])
    )
    v_x += noise_scale * dynamics.noise_std[region, 0] * noise[row, step, 0]
    v_y += noise_scale * dynamics.noise_std[region, 1] * noise[row, step, 1]
    return v_x, v_y, yaw_rate
