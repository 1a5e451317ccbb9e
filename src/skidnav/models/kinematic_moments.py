"""Compiled kernels of the learned kinematic model's sample rings: feeding samples into rings
stratified by commanded wheel speed, and keeping the weighted moments of every ring up to date
sample by sample, so that a refit (:meth:`~skidnav.models.kinematic.KinematicModel.refit`)
does not rebuild them from the raw window.

Rings: a region's buffer ``data[region]`` (window, 5) is split into ``n_strata`` rings of
``capacity = window // n_strata`` slots; ring s holds, oldest first from
``(count − kept) % capacity``, the last ``kept = min(count, capacity)`` samples whose commanded
speed ``max(|ω_L|, |ω_R|) / wheel_speed`` falls in the s-th of ``n_strata`` equal bins of
[0, 1] (speeds beyond 1 in the last). One stratum is the plain sliding window of
:mod:`skidnav.models.kinematic_prediction`. A sample's forgetting weight is
``forgetting ** age``, its age counted in samples of the same ring (newest 0).

Moments: per ring the 7 × 7 matrix Σ wᵢ zᵢ zᵢᵀ of the kept samples, with

    z = (ω_L, ω_R, 1, yaw_rate, v_x − v̂_x, v_y − v̂_y, yaw_rate − ŷaw_rate)

(:data:`MOMENT_COLUMNS`; the hats are the prior's predictions, so the residual columns of a floor
equal to the prior are exactly zero). Every regression of the model on the residual of any
parent's coefficients is a linear map of these columns, so its Gram matrix, Xᵀy and yᵀy are
linear maps of the moments (:func:`skidnav.models.kinematic_regression.fit_from_moments`).
Kept up to date by :func:`sync_moments`: the samples that left the window are subtracted (their
values read from a shadow copy of the buffer taken at the last update, since the ring has
overwritten them), the rest decays by ``forgetting ** fresh`` and the fresh samples are added.
A ring is rebuilt from its window every :data:`REBUILD_WINDOWS` windows of samples, so the
rounding of the subtractions never accumulates (amortized cost: O(1) per sample).
"""

from __future__ import annotations

import numpy as np

from skidnav._jit import jit

MOMENT_COLUMNS = ("omega_left", "omega_right", "one", "yaw_rate", "v_x_residual",
                  "v_y_residual", "yaw_rate_residual")  # fmt: skip
"""The columns z of the moments (module docstring)."""
N_MOMENTS = len(MOMENT_COLUMNS)
REBUILD_WINDOWS = 4
"""A ring's moments are rebuilt from its window after this many windows of incremental updates."""


@jit
def stratum_of(omega_left: float, omega_right: float, wheel_speed: float, n_strata: int) -> int:
    """The speed stratum of a command: the bin of ``max(|ω_L|, |ω_R|) / wheel_speed`` among
    ``n_strata`` equal bins of [0, 1], speeds beyond 1 in the last."""
    speed = max(abs(omega_left), abs(omega_right)) / wheel_speed
    return min(int(speed * n_strata), n_strata - 1)


@jit
def count_in_stratum(samples: np.ndarray, wheel_speed: float, n_strata: int, stratum: int) -> int:
    """Rows of ``samples`` (n, ≥ 2; the commanded ω_L, ω_R [rad/s] first: a region's kept
    samples) whose command falls in speed ``stratum`` of ``n_strata`` (:func:`stratum_of`)."""
    count = 0
    for row in range(samples.shape[0]):
        if stratum_of(samples[row, 0], samples[row, 1], wheel_speed, n_strata) == stratum:
            count += 1
    return count


@jit
def feed_rows_stratified(
    data: np.ndarray,
    counts: np.ndarray,
    ring_counts: np.ndarray,
    rows: np.ndarray,
    n_regions: int,
    wheel_speed: float,
) -> int:
    """Append kinematic-log rows to the rings of their region and speed stratum.

    Args:
        data: (n_regions, window, 5) float64 buffers, updated in place.
        counts: (n_regions,) int64 samples ever fed per region, updated in place.
        ring_counts: (n_regions, n_strata) int64 samples ever fed per ring, updated in place.
        rows: (n, 6) float64 kinematic log ``[region, ω_L cmd, ω_R cmd, v_x, v_y, yaw_rate]``.
        n_regions: rows with a region outside [0, n_regions) are skipped.
        wheel_speed: the full wheel speed [rad/s] the strata divide.

    Returns:
        The number of rows stored.
    """
    n_strata = ring_counts.shape[1]
    capacity = data.shape[1] // n_strata
    stored = 0
    for k in range(rows.shape[0]):
        region = int(rows[k, 0])
        if region < 0 or region >= n_regions:
            continue
        stratum = stratum_of(rows[k, 1], rows[k, 2], wheel_speed, n_strata)
        slot = stratum * capacity + ring_counts[region, stratum] % capacity
        for column in range(5):
            data[region, slot, column] = rows[k, column + 1]
        ring_counts[region, stratum] += 1
        counts[region] += 1
        stored += 1
    return stored


@jit
def _moment_vector(sample: np.ndarray, prior: np.ndarray, z: np.ndarray) -> None:
    """z (7,) of one sample (ω_L, ω_R, v_x, v_y, yaw_rate) and the prior's coefficients (8,)."""
    omega_left, omega_right, yaw_rate = sample[0], sample[1], sample[4]
    z[0] = omega_left
    z[1] = omega_right
    z[2] = 1.0
    z[3] = yaw_rate
    z[4] = sample[2] - prior[0] * omega_left - prior[1] * omega_right - prior[2]
    z[5] = sample[3] - prior[6] * yaw_rate - prior[7]
    z[6] = yaw_rate - prior[3] * omega_left - prior[4] * omega_right - prior[5]


@jit
def _add_sample(moments: np.ndarray, z: np.ndarray, weight: float) -> None:
    """moments (7, 7) += weight · z zᵀ."""
    for i in range(N_MOMENTS):
        for j in range(N_MOMENTS):
            moments[i, j] += weight * z[i] * z[j]


@jit
def _rebuild_ring(
    buffer: np.ndarray, count: int, capacity: int, forgetting: float, prior: np.ndarray,
    moments: np.ndarray,
) -> None:  # fmt: skip
    """moments (7, 7) of the kept samples of one ring, ``buffer`` its (capacity, 5) slots."""
    moments[:, :] = 0.0
    z = np.empty(N_MOMENTS)
    kept = min(count, capacity)
    for j in range(kept):
        _moment_vector(buffer[(count - kept + j) % capacity], prior, z)
        _add_sample(moments, z, forgetting ** (kept - 1 - j))


@jit
def _update_ring(
    buffer: np.ndarray, shadow: np.ndarray, old: int, count: int, capacity: int,
    forgetting: float, prior: np.ndarray, moments: np.ndarray,
) -> None:  # fmt: skip
    """Bring one ring's moments from ``old`` to ``count`` samples (fewer than ``capacity``
    fresh): subtract the evicted samples (read from ``shadow``), decay, add the fresh ones."""
    z = np.empty(N_MOMENTS)
    fresh = count - old
    kept_old = min(old, capacity)
    evicted = max(kept_old + fresh - capacity, 0)
    for j in range(evicted):
        _moment_vector(shadow[(old - kept_old + j) % capacity], prior, z)
        _add_sample(moments, z, -(forgetting ** (kept_old - 1 - j)))
    if forgetting != 1.0:
        decay = forgetting**fresh
        for i in range(N_MOMENTS):
            for m in range(N_MOMENTS):
                moments[i, m] *= decay
    for j in range(fresh):
        _moment_vector(buffer[(old + j) % capacity], prior, z)
        _add_sample(moments, z, forgetting ** (fresh - 1 - j))


@jit
def sync_moments(
    data: np.ndarray,
    ring_counts: np.ndarray,
    synced: np.ndarray,
    since_rebuild: np.ndarray,
    shadow: np.ndarray,
    moments: np.ndarray,
    forgetting: float,
    prior: np.ndarray,
) -> None:
    """Bring every ring's moments up to date with the samples fed since the last call.

    Args:
        data: (n_regions, window, 5) the sample buffers (read).
        ring_counts: (n_regions, n_strata) int64 samples ever fed per ring (read).
        synced: (n_regions, n_strata) int64 samples the moments include, updated.
        since_rebuild: (n_regions, n_strata) int64 samples added since a ring's last rebuild,
            updated.
        shadow: (n_regions, window, 5) the buffers as of the last call, updated.
        moments: (n_regions, n_strata, 7, 7) per ring, updated.
        forgetting: per-sample weight decay in (0, 1].
        prior: (8,) the prior's coefficients the residual columns are taken against.
    """
    n_regions, n_strata = ring_counts.shape
    capacity = data.shape[1] // n_strata
    for region in range(n_regions):
        for stratum in range(n_strata):
            count, old = ring_counts[region, stratum], synced[region, stratum]
            fresh = count - old
            if fresh == 0:
                continue
            start = stratum * capacity
            buffer = data[region, start : start + capacity]
            ring_moments = moments[region, stratum]
            if fresh >= capacity or since_rebuild[region, stratum] + fresh > (
                REBUILD_WINDOWS * capacity
            ):
                _rebuild_ring(buffer, count, capacity, forgetting, prior, ring_moments)
                since_rebuild[region, stratum] = 0
            else:
                old_buffer = shadow[region, start : start + capacity]
                _update_ring(
                    buffer, old_buffer, old, count, capacity, forgetting, prior, ring_moments
                )
                since_rebuild[region, stratum] += fresh
            for j in range(min(fresh, capacity)):
                slot = start + (count - 1 - j) % capacity
                shadow[region, slot, :] = data[region, slot, :]
            synced[region, stratum] = count


@jit
def newest_moments(
    data: np.ndarray,
    ring_counts: np.ndarray,
    share: int,
    forgetting: float,
    prior: np.ndarray,
) -> np.ndarray:
    """(7, 7) moments of the newest ``share`` kept samples of every ring (at their ring's
    forgetting weights): what the pooled model is fitted on."""
    n_regions, n_strata = ring_counts.shape
    capacity = data.shape[1] // n_strata
    total = np.zeros((N_MOMENTS, N_MOMENTS))
    z = np.empty(N_MOMENTS)
    for region in range(n_regions):
        for stratum in range(n_strata):
            count = ring_counts[region, stratum]
            kept = min(count, capacity)
            start = stratum * capacity
            for j in range(kept - min(share, kept), kept):
                _moment_vector(data[region, start + (count - kept + j) % capacity], prior, z)
                _add_sample(total, z, forgetting ** (kept - 1 - j))
    return total


class RingMoments:
    """The moments of every ring (:mod:`skidnav.models.kinematic_moments`) and what keeps them
    up to date: the samples they include, a shadow copy of the buffers; empty when not
    ``incremental``."""

    def __init__(self, data_shape: tuple[int, ...], strata: int, incremental: bool) -> None:
        n_regions = data_shape[0]
        shape = data_shape if incremental else (n_regions, 0, 5)
        self.shadow = np.zeros(shape)
        rings = (n_regions, strata) if incremental else (n_regions, 0)
        self.moments = np.zeros((*rings, N_MOMENTS, N_MOMENTS))
        self.synced = np.zeros(rings, dtype=np.int64)
        self.since_rebuild = np.zeros(rings, dtype=np.int64)

    def reset(self) -> None:
        """Forget everything included: the next :meth:`sync` rebuilds from the windows."""
        self.moments[...] = 0.0
        self.synced[...] = 0
        self.since_rebuild[...] = 0

    def sync(
        self, data: np.ndarray, ring_counts: np.ndarray, forgetting: float, prior: np.ndarray
    ) -> None:
        """Include the samples fed since the last call
        (:func:`~skidnav.models.kinematic_moments.sync_moments`)."""
        sync_moments(
            data, ring_counts, self.synced, self.since_rebuild, self.shadow, self.moments,
            forgetting, prior,
        )  # fmt: skip

    def region(self, region: int) -> np.ndarray:
        """(7, 7) moments of a region's kept samples (its rings together)."""
        return np.asarray(self.moments[region].sum(axis=0))
