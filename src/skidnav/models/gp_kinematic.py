"""Learned skid-steer kinematics by Gaussian-process regression, one set of GPs per slip region.

The alternative to the Bayesian-ridge model (:mod:`skidnav.models.kinematic`) named by the thesis's
future work (Alhawary (2020), §7.1): per coarse slip region, three independent GP regressions
(Rasmussen & Williams 2006, ch. 2, Algorithm 2.1) map the *commanded* wheel speeds
(ω_L, ω_R) [rad/s] to each output of the body twist v_x [m/s], v_y [m/s] and yaw_rate [rad/s],
learned from the free sub-steps of the kinematic log (columns
:data:`~skidnav.sim.navigation.LOG_COLUMNS`).

Kernel (per output, hyperparameters by maximizing the log marginal likelihood, R&W §5.4.1):

    k(x, x') = σ_f² · exp(−‖x − x'‖² / 2ℓ²) + σ_n² · δ(x, x')

a squared-exponential (RBF) kernel plus white noise (R&W eqs. 2.31 and 4.9; scikit-learn
``ConstantKernel * RBF + WhiteKernel``), on targets normalized to zero mean and unit variance.
Why not the linear (dot-product) kernel: with it the GP *is* Bayesian linear regression
(R&W §2.1, the weight-space view), i.e. the ridge model again with other hyperparameters; the
RBF kernel instead lets each commanded wheel-speed pair have its own mean twist (any smooth
function of the commands: slip that differs between driving forward, reversing and turning,
wheel speeds clipped at zero), which a linear model cannot represent. The price: no linear
extrapolation to commands never seen (the mean there reverts to the training mean, the interval
widens to the prior's), and v_y is learned from the commands directly rather than through the
yaw rate (x_ICR is not identified).

Window (ours): as the ridge model, a ring buffer of the last ``window`` samples per region
(:func:`~skidnav.models.kinematic_prediction.feed_rows`), so an exact GP fit costs
O(window³) time and O(window²) memory per output and optimizer step; ``window`` is at most
:data:`MAX_WINDOW`. Regions with fewer than ``min_samples`` samples use a pooled GP fitted on
the newest ``window / n_active_regions`` samples of every active region (so the pooled fit is
bounded by the same window). No forgetting weights: a GP has no per-sample weights, only the
window forgets.
"""

from __future__ import annotations

import logging
import time
import warnings
from dataclasses import dataclass

import numpy as np
from sklearn.exceptions import ConvergenceWarning
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel, Kernel, WhiteKernel

from skidnav.models.kinematic_config import window_slots
from skidnav.models.kinematic_prediction import feed_rows

logger = logging.getLogger(__name__)

MAX_WINDOW = 2000
"""Most samples kept per region: one fit then factorizes at most a 2000 × 2000 kernel matrix."""
N_OUTPUTS = 3
"""Outputs per region: (v_x, v_y, yaw_rate), the order of the log and of :meth:`predict`."""
_OUTPUT_COLUMNS = (2, 3, 4)  # v_x, v_y, yaw_rate in the (window, 5) sample buffers

RegionFit = tuple[GaussianProcessRegressor, ...]
"""The fitted GPs of one region, one per output."""


@dataclass(frozen=True)
class GaussianProcessConfig:
    """Hyperparameters of the GP kinematic model.

    Attributes:
        window: samples kept per region (sliding window) [sub-steps], ≤ :data:`MAX_WINDOW`.
        min_samples: samples a region (or the pool) needs before its own fit is used.
        refit_every: new samples (free sub-steps) between two refits of :meth:`maybe_refit`.
        length_scale: initial RBF length scale ℓ [rad/s] (optimized within
            [length_scale / 20, length_scale · 50]).
    """

    window: int = 500
    min_samples: int = 20
    refit_every: int = 500
    length_scale: float = 1.7

    def __post_init__(self) -> None:
        for name in ("window", "min_samples", "refit_every"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 1):
                raise ValueError(f"expected {name} to be an integer >= 1, got {value!r}")
        if self.window > MAX_WINDOW:
            raise ValueError(f"expected window <= {MAX_WINDOW}, got {self.window}")
        if not (np.isfinite(self.length_scale) and self.length_scale > 0):
            raise ValueError(f"expected length_scale > 0 rad/s, got {self.length_scale}")


class GaussianProcessKinematicModel:
    """Per-region GP kinematics: the mean body twist and its predictive spread.

    Args:
        n_regions: flat slip regions (:attr:`Discretization.n_regions`).
        config: hyperparameters.

    >>> model = GaussianProcessKinematicModel(2)
    >>> wheels = np.array([[1.7, 1.7], [-1.7, 1.7]] * 50)
    >>> twist = np.stack([0.02 * wheels.sum(1), np.zeros(100), 0.2 * np.diff(wheels)[:, 0]], 1)
    >>> rows = np.column_stack([np.zeros(100), wheels, twist])
    >>> model.feed(rows), model.refit()
    (100, None)
    >>> mean, std = model.predict(np.array([0]), np.array([[1.7, 1.7]]))
    >>> [round(float(v), 3) for v in mean[0]], bool(np.all(std[0] < 1e-3))
    ([0.068, 0.0, 0.0], True)
    """

    def __init__(self, n_regions: int, config: GaussianProcessConfig | None = None) -> None:
        if not (isinstance(n_regions, int) and n_regions >= 1):
            raise ValueError(f"expected n_regions to be an integer >= 1, got {n_regions!r}")
        self.config = config or GaussianProcessConfig()
        self.n_regions = n_regions
        self.data = np.zeros((n_regions, self.config.window, 5))
        self.counts = np.zeros(n_regions, dtype=np.int64)
        self.fitted_counts = np.zeros(n_regions, dtype=np.int64)
        self.fits: list[RegionFit | None] = [None] * n_regions
        self.pooled: RegionFit | None = None
        self.refits = 0
        self.fit_seconds = 0.0
        """Wall time spent in :meth:`refit` so far [s]."""
        self._fitted_total = 0

    # -- learning --------------------------------------------------------------------------

    def feed(self, log: np.ndarray) -> int:
        """Store kinematic-log rows ``(n, 6)``; returns how many were stored (no refit)."""
        rows = np.ascontiguousarray(log, dtype=np.float64).reshape(-1, 6)
        return int(feed_rows(self.data, self.counts, rows, self.n_regions))

    @property
    def new_samples(self) -> int:
        """Samples fed since the last refit."""
        return int(self.counts.sum()) - self._fitted_total

    def refit_due(self) -> bool:
        """True once ``refit_every`` samples arrived since the last refit."""
        return self.new_samples >= self.config.refit_every

    def maybe_refit(self) -> bool:
        """Refit if :meth:`refit_due`; returns whether it did."""
        if not self.refit_due():
            return False
        self.refit()
        return True

    def refit(self) -> None:
        """Refit the pooled GPs and those of every region with at least ``min_samples`` samples
        and ``min_samples`` new ones (or none fitted yet)."""
        start = time.perf_counter()
        minimum = self.config.min_samples
        self.pooled = self._fit_pooled()
        fresh = self.counts - self.fitted_counts
        for region in np.flatnonzero(self.counts >= minimum):
            if fresh[region] >= minimum or self.fits[region] is None:
                self.fits[region] = _fit_region(self.region_samples(int(region)), self.config)
                self.fitted_counts[region] = self.counts[region]
        self.refits += 1
        self._fitted_total = int(self.counts.sum())
        self.fit_seconds += time.perf_counter() - start
        logger.debug("GP kinematic refit %d", self.refits)

    def region_samples(self, region: int) -> np.ndarray:
        """Kept samples of a region, oldest first, shape (min(count, window), 5)."""
        slots = window_slots(int(self.counts[region]), self.config.window)
        samples: np.ndarray = self.data[region, slots]
        return samples

    def _fit_pooled(self) -> RegionFit | None:
        """GPs on the newest ``window / n_active`` samples of each active region."""
        active = np.flatnonzero(self.counts)
        if int(self.counts.sum()) < self.config.min_samples:
            return None
        share = -(-self.config.window // active.size)
        samples = np.concatenate([self.region_samples(int(r))[-share:] for r in active])
        return _fit_region(samples, self.config)

    # -- prediction ------------------------------------------------------------------------

    def predict(self, regions: np.ndarray, wheels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Predictive mean and standard deviation of the body twist (of a new observation:
        the white-noise variance included).

        Args:
            regions: flat slip region per query, shape (n,). wheels: commanded (ω_L, ω_R)
                [rad/s], shape (n, 2).

        Returns:
            (mean, std), each shape (n, 3): (v_x [m/s], v_y [m/s], yaw_rate [rad/s]); NaN
            where neither the region nor the pool has been fitted.
        """
        regions = np.asarray(regions, dtype=np.int64).ravel()
        wheels = np.asarray(wheels, dtype=np.float64).reshape(-1, 2)
        if regions.size != wheels.shape[0]:
            raise ValueError(f"expected one region per query, got {regions.size} for {len(wheels)}")
        if regions.size and not (regions.min() >= 0 and regions.max() < self.n_regions):
            raise ValueError(f"expected regions in [0, {self.n_regions}), got {regions.max()}")
        mean = np.full((regions.size, N_OUTPUTS), np.nan)
        std = np.full_like(mean, np.nan)
        for region in np.unique(regions):
            fit = self.fits[int(region)] or self.pooled
            if fit is not None:
                rows = regions == region
                for output, process in enumerate(fit):
                    mean[rows, output], std[rows, output] = process.predict(
                        wheels[rows], return_std=True
                    )
        return mean, std


def gp_kernel(length_scale: float) -> Kernel:
    """σ_f² · RBF(ℓ) + σ_n² (module doc) on normalized targets, ℓ starting at ``length_scale``."""
    signal = ConstantKernel(1.0, (1e-4, 1e2))
    rbf = RBF(length_scale, (length_scale / 20.0, length_scale * 50.0))
    return signal * rbf + WhiteKernel(0.1, (1e-8, 1e1))


def _fit_region(samples: np.ndarray, config: GaussianProcessConfig) -> RegionFit:
    """One fitted GP per output on ``samples`` (n, 5); deterministic (no optimizer restarts)."""
    wheels = samples[:, 0:2]
    fits = []
    for column in _OUTPUT_COLUMNS:
        process = GaussianProcessRegressor(gp_kernel(config.length_scale), normalize_y=True)
        with warnings.catch_warnings():
            # A hyperparameter at its bound (e.g. noise-free data) is expected, not an error.
            warnings.simplefilter("ignore", ConvergenceWarning)
            process.fit(wheels, samples[:, column])
        fits.append(process)
    return tuple(fits)
