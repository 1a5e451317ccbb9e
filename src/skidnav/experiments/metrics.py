"""Per-run metrics (SPEC §5): convergence, trajectory length, success rate, returns.

Episodes are numbered from 1. Definitions (also in docs/experiments.md and in every report):

* **Evaluation**: after every training episode the greedy policy is rolled out R times from the
  start, each rollout from a reset with one of R fixed evaluation seeds (the same seeds after
  every episode and for every agent of a world: common random numbers), so one slip-noise
  outlier does not decide.
* **Within tolerance** after episode e: every one of the R rollouts reached the goal and their
  mean length [actions] is at most (1 + tol) · L*, L* being the oracle's expected number of
  actions from the start under the true simulator (:mod:`skidnav.experiments.oracle`).
* **Convergence episode**: the first episode e such that the evaluations after episodes
  e, e + 1, …, e + W − 1 are all within tolerance (a window of fixed length W, not a share of the
  run). It depends only on the first e + W − 1 episodes, so the same run stopped at N or at 2N
  episodes has the same convergence episode once it converged before N − W + 1. A run with no
  such window is **censored** at N − W + 1 (it did not converge at any episode up to there);
  aggregates treat it as censored (Kaplan–Meier), never as converged at the last episode.
* **Optimality gap**: the mean greedy length over the last W evaluations (each the mean of its
  rollouts that reached the goal; evaluations where none did are left out) / L* − 1; NaN when
  none of the last W evaluations reached the goal.
* **Optimal trajectory length**: actions and path length [m] (sum of the straight segments
  between consecutive poses) of one more greedy rollout after training, the trajectory drawn in
  the report; NaN when it does not reach the goal.
* **Success rate**: share of training episodes that reach the goal (all, and the last 10 %).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

LAST_SHARE = 0.10
"""Share of the final episodes used for the "last 10 %" metrics."""


class ConvergenceRule(NamedTuple):
    """How convergence is judged (module docs).

    Attributes:
        reference: L*, the oracle's expected actions from the start [actions] (> 0).
        tolerance: relative band above L* (e.g. 0.1 = 10 %).
        window: consecutive evaluations that must all be within tolerance, W ≥ 1.
    """

    reference: float
    tolerance: float
    window: int


def evaluation_summary(greedy_lengths: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(mean length of the rollouts that reached the goal [actions], NaN if none; share that
    reached it) per evaluation, each (N,), from lengths int (N, R) with −1 = goal not reached."""
    lengths = np.asarray(greedy_lengths, dtype=np.float64).reshape(len(greedy_lengths), -1)
    reached = lengths > 0
    counts = reached.sum(axis=1)
    totals = np.where(reached, lengths, 0.0).sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(counts > 0, totals / np.maximum(counts, 1), np.nan)
    return mean, counts / lengths.shape[1]


def within_tolerance(
    mean_length: np.ndarray, success_share: np.ndarray, rule: ConvergenceRule
) -> np.ndarray:
    """bool (N,): every rollout reached the goal and the mean length ≤ (1 + tol) · L*.

    >>> rule = ConvergenceRule(reference=10.0, tolerance=0.1, window=2)
    >>> within_tolerance(np.array([9.0, 11.0, 12.0, 10.0]), np.array([1, 1, 1, 0.8]), rule)
    array([ True,  True, False, False])
    """
    limit = (1.0 + rule.tolerance) * rule.reference
    with np.errstate(invalid="ignore"):
        return np.asarray((success_share >= 1.0) & (mean_length <= limit))


def optimality_gap(mean_lengths: np.ndarray, reference: float) -> float:
    """Mean of the finite ``mean_lengths`` [actions] / ``reference`` − 1; NaN if none is finite.

    >>> round(optimality_gap(np.array([10.0, np.nan, 12.0]), 10.0), 6)
    0.1
    """
    finite = np.asarray(mean_lengths, dtype=np.float64)
    finite = finite[np.isfinite(finite)]
    return float(finite.mean() / reference - 1.0) if finite.size else float("nan")


def convergence_episode(within: np.ndarray, window: int) -> tuple[int, bool]:
    """(episode, converged): the first 1-based episode e whose evaluations e … e + W − 1 are all
    within tolerance, or the censoring time N − W + 1 (at least 1) and False.

    >>> convergence_episode(np.array([0, 1, 1, 0, 1, 1, 1, 0], bool), 3)
    (5, True)
    >>> convergence_episode(np.array([0, 1, 1, 0, 1, 1, 0, 0], bool), 3)
    (6, False)
    """
    within = np.asarray(within, dtype=bool)
    n = len(within)
    if n >= window:
        runs = np.convolve(within.astype(np.int64), np.ones(window, dtype=np.int64), "valid")
        full = np.flatnonzero(runs == window)
        if full.size:
            return int(full[0]) + 1, True
    return max(1, n - window + 1), False


def moving_average(values: np.ndarray, window: int) -> np.ndarray:
    """Trailing moving average (shorter window at the start), shape like ``values``."""
    values = np.asarray(values, dtype=np.float64)
    sums = np.cumsum(np.concatenate([[0.0], values]))
    ends = np.arange(1, len(values) + 1)
    starts = np.maximum(ends - window, 0)
    return np.asarray((sums[ends] - sums[starts]) / (ends - starts))


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
    rule: ConvergenceRule | None,
) -> dict[str, float]:
    """Every per-run metric, as one flat dict of floats.

    Args:
        episodes: per-episode arrays ``return``, ``length``, ``success``, ``collisions``,
            ``planning_updates``, ``wall_time``, ``greedy_length`` (mean over the evaluation's
            rollouts that reached the goal, NaN if none), ``greedy_success`` (share of them that
            did), each shape (N,).
        greedy_poses: the final greedy trajectory, shape (T, 3) [m, m, rad].
        greedy_reached: whether that trajectory reached the goal.
        rule: the convergence rule, or None when no oracle exists (convergence metrics NaN).
    """
    success = episodes["success"].astype(np.float64)
    n = len(success)
    first_success = np.flatnonzero(success > 0)
    nan = float("nan")
    metrics = {
        "convergence_episode": nan, "converged": nan, "optimality_gap": nan,
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
    }  # fmt: skip
    if rule is not None and n > 0 and math.isfinite(rule.reference):
        mean, share = episodes["greedy_length"], episodes["greedy_success"]
        episode, converged = convergence_episode(within_tolerance(mean, share, rule), rule.window)
        metrics["convergence_episode"] = float(episode)
        metrics["converged"] = float(converged)
        metrics["optimality_gap"] = optimality_gap(mean[-rule.window :], rule.reference)
    return metrics
