"""Per-run metrics (SPEC §5): convergence, trajectory length, success rate, returns.

Episodes are numbered from 1. Definitions (also in docs/experiments.md and in every report):

* **Convergence episode** (primary): with L_e the greedy policy's trajectory length [actions]
  evaluated after training episode e and L_N its final value, the smallest e such that
  |L_t − L_N| ≤ tol · L_N for every t ≥ e (tol default 10 %). A greedy evaluation that does not
  reach the goal is never within the band. A run whose final greedy policy does not reach the goal
  has no final value: it is *not converged* and counts as N (censored at the end of training).
* **Convergence episode, training view**: the same rule on the moving average (window
  ``max(1, round(N / 20))`` episodes) of the training episodes' lengths, so exploration is
  included.
* **Convergence episode, robust view**: the same rule on the trailing median (window
  ``max(1, round(N / 20))`` evaluations, a failed evaluation counting as infinitely long) of the
  greedy lengths, so one isolated bad evaluation late in training does not reset convergence.
* **Optimal trajectory length**: actions and path length [m] (sum of the straight segments
  between consecutive poses) of one more greedy rollout after training, the trajectory drawn in
  the report; NaN when it does not reach the goal.
* **Success rate**: share of training episodes that reach the goal (all, and the last 10 %).
"""

from __future__ import annotations

import math

import numpy as np

LAST_SHARE = 0.10
"""Share of the final episodes used for the "last 10 %" metrics."""


def stable_from(values: np.ndarray, valid: np.ndarray, tolerance: float) -> int:
    """1-based first episode from which every valid value stays within ``tolerance`` (relative)
    of the last value; ``len(values)`` when the last value is invalid.

    >>> stable_from(np.array([50., 30, 22, 21, 20, 20]), np.ones(6, bool), 0.1)
    3
    >>> stable_from(np.array([20., 40, 20]), np.array([True, False, True]), 0.1)
    3
    """
    n = len(values)
    if n == 0:
        return 0
    if not valid[-1]:
        return n
    final = values[-1]
    inside = valid & (np.abs(values - final) <= tolerance * abs(final))
    outside = np.flatnonzero(~inside)
    return 1 if outside.size == 0 else int(outside[-1]) + 2


def convergence_episode(
    greedy_lengths: np.ndarray, greedy_success: np.ndarray, tolerance: float
) -> int:
    """Primary convergence episode (1-based) from the greedy evaluations, see module docs.

    Args:
        greedy_lengths: greedy trajectory length after each episode [actions], shape (N,).
        greedy_success: whether that greedy trajectory reached the goal, shape (N,).
        tolerance: relative band, e.g. 0.1.
    """
    lengths = np.asarray(greedy_lengths, dtype=np.float64)
    return stable_from(lengths, np.asarray(greedy_success, dtype=bool), tolerance)


def moving_average(values: np.ndarray, window: int) -> np.ndarray:
    """Trailing moving average (shorter window at the start), shape like ``values``."""
    values = np.asarray(values, dtype=np.float64)
    sums = np.cumsum(np.concatenate([[0.0], values]))
    ends = np.arange(1, len(values) + 1)
    starts = np.maximum(ends - window, 0)
    return np.asarray((sums[ends] - sums[starts]) / (ends - starts))


def trailing_median(values: np.ndarray, window: int) -> np.ndarray:
    """Median of the last ``window`` values at each position (fewer at the start); NaN counts as
    +inf. Shape like ``values``."""
    values = np.where(np.isnan(values), np.inf, np.asarray(values, dtype=np.float64))
    return np.array(
        [np.median(values[max(0, end - window + 1) : end + 1]) for end in range(len(values))]
    )


def robust_convergence_episode(greedy_lengths: np.ndarray, tolerance: float) -> int:
    """Robust-view convergence episode (1-based) on the trailing median of the greedy lengths
    (failed evaluations are NaN)."""
    lengths = np.asarray(greedy_lengths, dtype=np.float64)
    smoothed = trailing_median(lengths, max(1, round(len(lengths) / 20)))
    return stable_from(smoothed, np.isfinite(smoothed), tolerance)


def training_convergence_episode(lengths: np.ndarray, tolerance: float) -> int:
    """Training-view convergence episode (1-based) on the moving-average episode length."""
    lengths = np.asarray(lengths, dtype=np.float64)
    window = max(1, round(len(lengths) / 20))
    smoothed = moving_average(lengths, window)
    return stable_from(smoothed, np.ones(len(lengths), dtype=bool), tolerance)


def path_length(poses: np.ndarray) -> float:
    """Length [m] of the polyline through the (x, y) of ``poses``, shape (T, ≥ 2)."""
    poses = np.asarray(poses, dtype=np.float64)
    if len(poses) < 2:
        return 0.0
    return float(np.hypot(*np.diff(poses[:, :2], axis=0).T).sum())


def last_share(values: np.ndarray) -> np.ndarray:
    """The last 10 % of ``values`` (at least one)."""
    count = max(1, math.ceil(LAST_SHARE * len(values)))
    return np.asarray(values[-count:])


def run_metrics(
    episodes: dict[str, np.ndarray],
    greedy_poses: np.ndarray,
    greedy_reached: bool,
    tolerance: float,
) -> dict[str, float]:
    """Every per-run metric, as one flat dict of floats.

    Args:
        episodes: per-episode arrays ``return``, ``length``, ``success``, ``collisions``,
            ``planning_updates``, ``wall_time``, ``greedy_length``, ``greedy_success``, each
            shape (N,).
        greedy_poses: the final greedy trajectory, shape (T, 3) [m, m, rad].
        greedy_reached: whether that trajectory reached the goal.
        tolerance: convergence tolerance (relative).
    """
    success = episodes["success"].astype(np.float64)
    greedy_success = episodes["greedy_success"].astype(bool)
    n = len(success)
    converged = bool(greedy_success[-1])
    first_success = np.flatnonzero(success > 0)
    nan = float("nan")
    return {
        "convergence_episode": float(
            convergence_episode(episodes["greedy_length"], greedy_success, tolerance)
        ),
        "converged": float(converged),
        "convergence_episode_robust": float(
            robust_convergence_episode(
                np.where(greedy_success, episodes["greedy_length"], np.nan), tolerance
            )
        ),
        "convergence_episode_training": float(
            training_convergence_episode(episodes["length"], tolerance)
        ),
        "first_success_episode": float(first_success[0] + 1) if first_success.size else float(n),
        "final_length_actions": float(len(greedy_poses) - 1) if greedy_reached else nan,
        "final_length_m": path_length(greedy_poses) if greedy_reached else nan,
        "success_rate": float(success.mean()),
        "success_rate_last10": float(last_share(success).mean()),
        "mean_return": float(episodes["return"].mean()),
        "mean_return_last10": float(last_share(episodes["return"]).mean()),
        "mean_length": float(episodes["length"].mean()),
        "collisions_per_episode": float(episodes["collisions"].mean()),
        "planning_updates": float(episodes["planning_updates"].sum()),
        "wall_time": float(episodes["wall_time"].sum()),
    }
