"""Learned skid-steer kinematics: one Bayesian ridge regression per coarse slip region.

The thesis (Alhawary (2020), ch. 7) learns the ICR model of Kozłowski & Pazderski (2004) online by
Bayesian ridge regression (MacKay 1992; Tipping 2001; :mod:`skidnav.models.bayesian_ridge`, with
scikit-learn ``BayesianRidge``'s conventions), one model per coarse region, and uses it to predict
the outcome of actions at states never visited. Per region three regressions are fitted on the free
sub-steps of the kinematic log:

    v_x      ≈ vx_wl·ω_L + vx_wr·ω_R (+ vx_b)       (truth: r/2, r/2)
    yaw_rate ≈ yaw_wl·ω_L + yaw_wr·ω_R (+ yaw_b)    (truth: −r/2c, r/2c)
    v_y      ≈ vy_yaw·yaw_rate (+ vy_b)             (truth: −x_ICR)

with ω_L, ω_R the *commanded* wheel speeds [rad/s], so wheel-speed loss from slip is absorbed
into the coefficients. Intercepts are off by default (no wheel motion, no body motion).

Shrinkage hierarchy (ours): the pooled model (all regions' samples) regresses the residual of
the nominal robot (:class:`~skidnav.robot.params.RobotParams`, the prior); each region regresses
the residual of the pooled model. The zero-mean Gaussian prior of Bayesian ridge thus shrinks a
region towards the pooled fit and the pooled fit towards the nominal robot; directions the data
do not excite (e.g. v_y in a region where the robot never turned) keep the parent's value.
Regions with fewer than ``min_samples`` samples use the pooled fit outright; with fewer than
``min_samples`` samples in total, the prior.

Refit schedule (ours): :meth:`KinematicModel.maybe_refit` refits when at least
``max(refit_every, refit_growth · n_at_last_refit)`` samples arrived since the last refit, so a
stationary run refits a logarithmic number of times (the default doubles); set ``refit_growth=0``
for drifting slip. Only regions with new samples are refitted (plus the pooled model, fitted on
the newest ``window / n_active_regions`` samples of each active region). Forgetting: sample weights
``forgetting ** age`` (age in samples of the same region, newest 0) and a sliding window of the
last ``window`` samples per region.

Predictive distribution (:meth:`KinematicModel.predict_twist`): each regression's Gaussian
posterior predictive (Bishop 2006 eqs. 3.58–3.59: noise variance plus parameter variance), with the
parent fit held fixed; v_y given the commanded wheels propagates the yaw-rate prediction to first
order. Saved files: :mod:`skidnav.models.kinematic_files`; the fitted regressions are kept
in memory only (not saved), so a loaded model has no predictive spread until its next refit.
"""

from __future__ import annotations

import logging

import numpy as np

from skidnav.errors import CorruptFileError
from skidnav.models.kinematic_config import KinematicModelConfig, window_slots
from skidnav.models.kinematic_moments import (
    RingMoments,
    count_in_stratum,
    feed_rows_stratified,
    newest_moments,
)
from skidnav.models.kinematic_prediction import (
    action_velocities,
    feed_rows,
    predict_action,
    prediction_table,
)
from skidnav.models.kinematic_regression import (
    Posterior,
    fit_coefficients,
    fit_from_moments,
    icr_parameters,
    nominal_coefficients,
    twist_std,
)
from skidnav.robot.kinematics import N_ACTIONS
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization

logger = logging.getLogger(__name__)

FAST_STRATA = 3
"""A command is fast (:meth:`KinematicModel.fast_counts`) in the fastest of this many equal bins
of the wheel speed: its faster wheel at ≥ 2/3 of the top speed, as the fastest ring of
``speed_strata = 3`` keeps."""


class KinematicModel:
    """Per-region Bayesian ridge kinematics with a compiled prediction table.

    Args:
        robot: nominal robot (prior, sub-step timing, integration scheme, arena).
        grid: the state discretization (cells, headings, slip regions).
        config: hyperparameters.

    >>> model = KinematicModel(RobotParams(), Discretization())
    >>> [round(v, 4) for v in model.estimates(0)]
    [0.0225, 0.06, 0.05]
    """

    def __init__(
        self,
        robot: RobotParams,
        grid: Discretization,
        config: KinematicModelConfig | None = None,
    ) -> None:
        self.robot = robot
        self.grid = grid
        self.config = config or KinematicModelConfig()
        n_regions = grid.n_regions
        self.data = np.zeros((n_regions, self.config.window, 5))
        self.counts = np.zeros(n_regions, dtype=np.int64)
        self.fitted_counts = np.zeros(n_regions, dtype=np.int64)
        self.coefficients = np.tile(nominal_coefficients(robot), (n_regions, 1))
        self.velocities = np.zeros((n_regions, N_ACTIONS, 3))
        strata = self.config.speed_strata
        self.stratum_counts = np.zeros((n_regions, strata), dtype=np.int64)
        """Samples ever fed per region and speed stratum (with one stratum: unused, ``counts``
        is the ring's count)."""
        self._moments = RingMoments(self.data.shape, strata, self.config.incremental)
        self.refits = 0
        self._pooled_fitted = 0
        self._posteriors: list[Posterior | None] = [None] * n_regions
        self.held = False
        """True once :meth:`hold` stopped the learning."""
        self.reference: np.ndarray | None = None
        """The velocities handed to :meth:`hold`, if any (they replace the fit's)."""
        self._update_velocities()

    def _update_velocities(self) -> None:
        """The velocity table from the coefficients, or the held reference."""
        action_velocities(self.coefficients, self.robot.wheel_speed, self.velocities)
        if self.reference is not None:
            self.velocities[...] = self.reference

    def hold(self, velocities: np.ndarray | None = None) -> None:
        """Stop learning: :meth:`maybe_refit` never refits again (samples are still kept), so
        the model predicts with its current fit — the prior (the nominal robot) if it never
        refitted — or, given ``velocities``, with those from now on: a reference handed in,
        such as the simulator's true expected velocities
        (:meth:`~skidnav.robot.slip.SlipField.expected_velocities`). The reference replaces
        the velocity table the predictions integrate; the coefficients (:meth:`estimates`,
        :meth:`predict_twist`) stay the fit's.

        Args:
            velocities: float64 (n_regions, n_actions, 3) (v_x [m/s], v_y [m/s],
                yaw_rate [rad/s]), finite; or None.
        """
        if velocities is not None:
            table = np.asarray(velocities, dtype=np.float64)
            if table.shape != self.velocities.shape or not np.isfinite(table).all():
                raise ValueError(
                    f"expected finite velocities of shape {self.velocities.shape}, "
                    f"got shape {table.shape}"
                )
            self.reference = table.copy()
            self._update_velocities()
        self.held = True

    # -- learning --------------------------------------------------------------------------

    def feed(self, log: np.ndarray) -> int:
        """Store kinematic-log rows ``(n, 6)``; returns how many were stored (no refit)."""
        rows = np.ascontiguousarray(log, dtype=np.float64).reshape(-1, 6)
        if self.config.speed_strata == 1:
            return int(feed_rows(self.data, self.counts, rows, self.grid.n_regions))
        return int(
            feed_rows_stratified(
                self.data, self.counts, self.stratum_counts, rows, self.grid.n_regions,
                self.robot.wheel_speed,
            )
        )  # fmt: skip

    def ring_counts(self) -> np.ndarray:
        """Samples ever fed per region and ring, int64 (n_regions, speed_strata)."""
        if self.config.speed_strata == 1:
            return self.counts[:, None]
        return self.stratum_counts

    def fast_counts(self) -> np.ndarray:
        """Kept samples per region (its window, every ring) commanded fast — in the fastest of
        :data:`FAST_STRATA` equal bins of the wheel speed
        (:func:`~skidnav.models.kinematic_moments.stratum_of`) —, int64 (n_regions,): how much
        of what the region's fit sees says anything about a full-speed command."""
        counts = np.zeros(self.grid.n_regions, dtype=np.int64)
        for region in np.flatnonzero(self.counts):
            samples, _ = self._region_samples(int(region))
            counts[region] = count_in_stratum(
                np.ascontiguousarray(samples), self.robot.wheel_speed, FAST_STRATA, FAST_STRATA - 1
            )
        return counts

    @property
    def new_samples(self) -> int:
        """Samples fed since the last refit."""
        return int(self.counts.sum()) - self._pooled_fitted

    def refit_due(self) -> bool:
        """True when the refit schedule (see the module docstring) asks for a refit."""
        needed = max(self.config.refit_every, int(self.config.refit_growth * self._pooled_fitted))
        return self.new_samples >= needed

    def maybe_refit(self) -> bool:
        """Refit if :meth:`refit_due` and the model is not held (:meth:`hold`); returns whether
        it did."""
        if self.held or not self.refit_due():
            return False
        self.refit()
        return True

    def refit(self) -> None:
        """Refit the pooled model and every region with at least ``min_samples`` new samples (or
        none fitted yet), then the velocity table."""
        prior = nominal_coefficients(self.robot)
        if self.config.incremental:
            self._moments.sync(self.data, self.ring_counts(), self.config.forgetting, prior)
        pooled, pooled_posterior = self._fit_pooled(prior)
        fresh = self.counts - self.fitted_counts
        minimum = self.config.min_samples
        for region in range(self.grid.n_regions):
            if self.counts[region] < minimum:
                self.coefficients[region] = pooled
                self._posteriors[region] = pooled_posterior
            elif fresh[region] >= minimum or self.fitted_counts[region] < minimum:
                fit = self._fit_region(region, pooled, prior)
                self.coefficients[region], self._posteriors[region] = fit
                self.fitted_counts[region] = self.counts[region]
        self.refits += 1
        self._pooled_fitted = int(self.counts.sum())
        self._update_velocities()
        logger.debug("kinematic refit %d", self.refits)

    def _fit_region(
        self, region: int, pooled: np.ndarray, prior: np.ndarray
    ) -> tuple[np.ndarray, Posterior]:
        """A region's fit on the residual of the pooled coefficients: from its rings' moments,
        or from its kept samples."""
        if self.config.incremental:
            moments = self._moments.region(region)
            return fit_from_moments(moments, pooled, prior, self.config.fit_intercept)
        x, w = self._region_samples(region)
        return fit_coefficients(x, w, pooled, self.config.fit_intercept)

    def _region_samples(
        self, region: int, share: int | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Kept samples of a region (n, 5) and their forgetting weights (n,), ring by ring
        (the newest ``share`` of each ring, or all)."""
        capacity = self.config.window // self.config.speed_strata
        samples, weights = [], []
        for stratum, count in enumerate(self.ring_counts()[region]):
            slots = stratum * capacity + window_slots(int(count), capacity)
            age = np.arange(slots.size - 1, -1, -1, dtype=np.float64)
            newest = slots.size if share is None else min(share, slots.size)
            samples.append(self.data[region, slots[slots.size - newest :]])
            weights.append(self.config.forgetting ** age[age.size - newest :])
        if len(samples) == 1:
            return samples[0], weights[0]
        return np.concatenate(samples), np.concatenate(weights)

    def _fit_pooled(self, prior: np.ndarray) -> tuple[np.ndarray, Posterior | None]:
        """Fit on the newest ``window / (strata × n_active)`` samples of each active region's
        rings (so a pooled fit costs no more than a regional one)."""
        active = np.flatnonzero(self.counts)
        if int(self.counts.sum()) < self.config.min_samples:
            return prior, None
        capacity = self.config.window // self.config.speed_strata
        share = -(-capacity // active.size)
        if self.config.incremental:
            moments = newest_moments(
                self.data, self.ring_counts(), share, self.config.forgetting, prior
            )
            return fit_from_moments(moments, prior, prior, self.config.fit_intercept)
        parts = [self._region_samples(int(r), share) for r in active]
        x = np.concatenate([p[0] for p in parts])
        w = np.concatenate([p[1] for p in parts])
        return fit_coefficients(x, w, prior, self.config.fit_intercept)

    # -- prediction ------------------------------------------------------------------------

    def predict_twist(
        self, regions: np.ndarray, wheels: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Predictive mean and standard deviation of the body twist (module doc).

        Args:
            regions: flat slip region per query, shape (n,). wheels: commanded (ω_L, ω_R)
                [rad/s], shape (n, 2).

        Returns:
            (mean, std), each shape (n, 3): (v_x [m/s], v_y [m/s], yaw_rate [rad/s]); std NaN
            in a region not fitted since construction or load, 0 for an output fitted exactly.
        """
        regions = np.asarray(regions, dtype=np.int64).ravel()
        wheels = np.asarray(wheels, dtype=np.float64).reshape(-1, 2)
        c = self.coefficients[regions]
        yaw = c[:, 3] * wheels[:, 0] + c[:, 4] * wheels[:, 1] + c[:, 5]
        v_x = c[:, 0] * wheels[:, 0] + c[:, 1] * wheels[:, 1] + c[:, 2]
        mean = np.stack([v_x, c[:, 6] * yaw + c[:, 7], yaw], axis=1)
        std = np.full_like(mean, np.nan)
        for region in np.unique(regions):
            posterior = self._posteriors[int(region)]
            if posterior is not None:
                rows = regions == region
                std[rows] = twist_std(posterior, wheels[rows], yaw[rows], c[rows, 6])
        return mean, std

    def posterior(self, region: int) -> Posterior | None:
        """The fitted regressions of ``region`` (v_x, yaw_rate, v_y; None for an output fitted
        exactly), or None before the region's first refit since construction or load: where
        :meth:`predict_twist`'s spread comes from, for a caller that samples the model."""
        return self._posteriors[region]

    def estimates(self, region: int) -> tuple[float, float, float]:
        """Physical reading of a region's fit: (r [m], c [m], x_ICR [m]).

        r = vx_wl + vx_wr; c = r / (yaw_wr − yaw_wl); x_ICR = −vy_yaw.
        """
        c = self.coefficients[region]
        radius, half_track, x_icr = icr_parameters(c[0:2], c[3:5], c[6])
        return float(radius), float(half_track), float(x_icr)

    def predict(
        self,
        pose: tuple[float, float, float],
        action: int,
        walls: np.ndarray | None = None,
        goals: np.ndarray | None = None,
    ) -> tuple[tuple[float, float, float], int]:
        """Predicted pose after ``action`` from ``pose`` (x [m], y [m], heading [rad]).

        Returns ((x, y, heading), outcome) with the outcome codes of
        :mod:`skidnav.models.kinematic_prediction`.
        """
        walls_, goals_ = self._masks(walls, goals)
        x, y, heading, outcome = predict_action(
            float(pose[0]), float(pose[1]), float(pose[2]), int(action), self.velocities,
            walls_, goals_, self.robot.kernel_constants(), self.grid.grid_shape(), False,
        )  # fmt: skip
        return (float(x), float(y), float(heading)), int(outcome)

    def table(
        self, walls: np.ndarray | None = None, goals: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Predicted next state and outcome of every (state, action) from cell centres.

        Returns:
            ``next_state`` (n_states, n_actions) int32 and ``outcome`` (n_states, n_actions) int8.
        """
        next_state = np.empty((self.grid.n_states, N_ACTIONS), dtype=np.int32)
        outcome = np.empty((self.grid.n_states, N_ACTIONS), dtype=np.int8)
        self.fill_table(next_state, outcome, walls, goals)
        return next_state, outcome

    def fill_table(
        self,
        next_state: np.ndarray,
        outcome: np.ndarray,
        walls: np.ndarray | None = None,
        goals: np.ndarray | None = None,
    ) -> None:
        """As :meth:`table`, writing into preallocated arrays."""
        walls_, goals_ = self._masks(walls, goals)
        prediction_table(
            self.velocities, walls_, goals_, self.robot.kernel_constants(),
            self.grid.grid_shape(), next_state, outcome,
        )  # fmt: skip

    def _masks(
        self, walls: np.ndarray | None, goals: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray]:
        shape = (self.grid.n_x, self.grid.n_y)
        walls_ = np.zeros(shape, dtype=np.bool_) if walls is None else np.asarray(walls, bool)
        goals_ = np.zeros(shape, dtype=np.bool_) if goals is None else np.asarray(goals, bool)
        if walls_.shape != shape or goals_.shape != shape:
            raise ValueError(f"expected walls and goals of shape {shape}, got {walls_.shape}")
        return walls_, goals_

    # -- persistence -----------------------------------------------------------------------

    def state_arrays(self, prefix: str = "kinematic_") -> dict[str, np.ndarray]:
        """The learned state as named arrays (for an agent's .npz)."""
        return {
            f"{prefix}data": self.data,
            f"{prefix}counts": self.counts,
            f"{prefix}fitted_counts": self.fitted_counts,
            f"{prefix}coefficients": self.coefficients,
            f"{prefix}refits": np.array([self.refits, self._pooled_fitted]),
            **(
                {f"{prefix}stratum_counts": self.stratum_counts}
                if self.config.speed_strata > 1
                else {}
            ),
        }

    def load_arrays(self, arrays: dict[str, np.ndarray], prefix: str = "kinematic_") -> None:
        """Restore :meth:`state_arrays` output (shapes are checked)."""
        names: tuple[str, ...] = ("data", "counts", "fitted_counts", "coefficients")
        if self.config.speed_strata > 1:
            names = (*names, "stratum_counts")
        for name in names:
            value = np.asarray(arrays[f"{prefix}{name}"])
            if value.shape != getattr(self, name).shape:
                raise CorruptFileError(f"kinematic model {name}: unexpected shape {value.shape}")
            if not np.isfinite(value).all():
                raise CorruptFileError(f"kinematic model {name}: not finite")
            getattr(self, name)[...] = value
        refits = np.asarray(arrays[f"{prefix}refits"])
        if refits.shape != (2,):
            raise CorruptFileError(f"kinematic model refits: unexpected shape {refits.shape}")
        self.refits, self._pooled_fitted = (int(v) for v in refits)
        self._posteriors = [None] * self.grid.n_regions
        self._moments.reset()
        if (
            (self.fitted_counts < 0).any()
            or (self.fitted_counts > self.counts).any()
            or self.refits < 0
            or not 0 <= self._pooled_fitted <= int(self.counts.sum())
            or (self.config.speed_strata > 1 and (self.stratum_counts.sum(1) != self.counts).any())
            or (self.stratum_counts < 0).any()
        ):
            raise CorruptFileError("kinematic model sample counts are inconsistent")
        self._update_velocities()
