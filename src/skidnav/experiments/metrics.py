"""Per-run metrics: convergence, trajectory length, success rate, returns, seconds of driving.

Episodes are numbered from 1. Definitions (also in docs/experiments.md and in every report):

* **Evaluation**: after every training episode the greedy policy is rolled out R times from the
  start, each rollout from a reset with one of R fixed evaluation seeds (the same seeds after
  every episode and for every agent of a world: common random numbers), so one slip-noise
  outlier does not decide.
* **Pass**: the evaluation after episode e passes when every one of its R rollouts reached the goal
  and their mean length [actions] is at most (1 + tol) · L*, L* being the oracle's expected number
  of actions from the start under the true simulator (:mod:`skidnav.experiments.reference.oracle`);
  with ``measure = "greedy_cost"``, their mean cost (minus the reward without the goal bonus) at
  most (1 + tol) · C*, the oracle's least expected cost from the start.
* **Convergence episode** (*converged means it stays converged*): the first passing episode e
  from which the share of passing evaluations stays at least p (``level``) to the end of the
  run: over e … k for every k from e + W − 1 (at least W evaluations of evidence) to N. A run
  that passes for a while and then falls apart is therefore not converged at its first good
  stretch; a run with no such episode up to N − W + 1 is **censored** there, and aggregates
  treat it as censored (Kaplan–Meier), never as converged at the last episode. A policy that
  stays keeps its share as the run goes on, so its convergence episode does not depend on the
  horizon; longer runs can only reveal that a policy did not stay: a run that converged at e
  over N episodes converged at e or earlier over any first N′ ≥ e + W − 1 of them.
* **Pass share after convergence**: share of the evaluations from the convergence episode to
  the end that pass (converged runs only); **after the first good window**: the same from the
  first episode of the first W passes in a row (the earlier, first-window definition, kept as a
  diagnostic of drift); **last 10 %**: share of passing evaluations in the last 10 % of the run.
* **Optimality gap**: the mean greedy length over the last W evaluations (each the mean of its
  rollouts that reached the goal; evaluations where none did are left out) / L* − 1; NaN when
  none of the last W evaluations reached the goal.
* **Optimal trajectory length**: actions and path length [m] (sum of the straight segments
  between consecutive poses) of one more greedy rollout after training, the trajectory drawn in
  the report; NaN when it does not reach the goal.
* **Success rate**: share of training episodes that reach the goal (all, and the last 10 %).
* **Seconds of driving**: what the robot pays for learning. One action lasts the robot's
  ``dt × substeps`` seconds (``RobotParams.action_duration``: 1 s by default, 0.1 s with
  ``control_period = 0.1``, the same on the MuJoCo robot); the driving time of episodes 1 … e is
  Σ length × that duration. The greedy evaluations are measurement and are not counted.
  **To first success**: episodes 1 … e, e the first training episode that reached the goal.
  **To sustained greedy success**: episodes 1 … e, e the first episode whose greedy evaluation
  had at least 90 % of its rollouts reach the goal (:data:`SUSTAINED_SUCCESS`; with 5 rollouts,
  all 5) and every later evaluation too, with at least W evaluations of evidence — the
  convergence rule above (:func:`convergence_episode`) at level 1 on "≥ 90 % reached" instead
  of a pass. Either time is **censored** (NaN, "not reached") when the run never got there.
  A robot has no greedy evaluations: there sustained success is the last episode of the first
  10 consecutive training episodes with at least 9 goals (:func:`window_success_episode`,
  :func:`training_driving_metrics`).
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
        reference: the oracle's optimum from the start of the measure: L* [actions], or C*
            with ``measure = "greedy_cost"`` (> 0).
        tolerance: relative band above L* (e.g. 0.1 = 10 %).
        window: W ≥ 1, the evaluations from the convergence episode on that must already hold
            a share ``level`` of passes (the least evidence of a convergence).
        level: p in (0, 1], the share of passes that must hold from the convergence episode to
            every later episode (1: every evaluation from it on passes).
        measure: the per-episode column compared with ``reference``: ``greedy_length`` (mean
            actions of the rollouts that reached the goal) or ``greedy_cost`` (their mean cost,
            minus the reward without the goal bonus: the objective of the agents' reward).
    """

    reference: float
    tolerance: float
    window: int
    level: float = 1.0
    measure: str = "greedy_length"


def evaluation_summary(
    greedy_lengths: np.ndarray, values: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(mean length of the rollouts that reached the goal [actions], NaN if none; share that
    reached it) per evaluation, each (N,), from lengths int (N, R) with −1 = goal not reached;
    with ``values`` (N, R) (e.g. the rollouts' costs) the mean of those values instead of the
    lengths, over the same rollouts."""
    lengths = np.asarray(greedy_lengths, dtype=np.float64).reshape(len(greedy_lengths), -1)
    measured = lengths if values is None else np.asarray(values, np.float64).reshape(lengths.shape)
    reached = lengths > 0
    counts = reached.sum(axis=1)
    totals = np.where(reached, measured, 0.0).sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(counts > 0, totals / np.maximum(counts, 1), np.nan)
    return mean, counts / lengths.shape[1]


SHARE_MARGIN = 1e-9
"""Rounding margin of share comparisons: 9 of 10 evaluations must count as a share of 0.9."""


def within_tolerance(
    mean_length: np.ndarray, success_share: np.ndarray, rule: ConvergenceRule
) -> np.ndarray:
    """bool (N,): the evaluation passes (module docs): every rollout reached the goal and their
    mean length ≤ (1 + tol) · L*.

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


def first_window(passed: np.ndarray, window: int) -> int:
    """The first 1-based episode e whose evaluations e … e + W − 1 all pass, 0 if none.

    >>> first_window(np.array([0, 1, 1, 0, 1, 1, 1, 0], bool), 3)
    5
    """
    passed = np.asarray(passed, dtype=bool)
    if len(passed) < window:
        return 0
    runs = np.convolve(passed.astype(np.int64), np.ones(window, dtype=np.int64), "valid")
    full = np.flatnonzero(runs == window)
    return int(full[0]) + 1 if full.size else 0


def convergence_episode(passed: np.ndarray, window: int, level: float = 1.0) -> tuple[int, bool]:
    """(episode, converged): the first 1-based passing episode e such that the share of passing
    evaluations over e … k is at least ``level`` for every k from e + W − 1 to the end (module
    docs), or the censoring time N − W + 1 (at least 1) and False.

    >>> convergence_episode(np.array([0, 1, 1, 0, 1, 1, 1, 1], bool), 3)
    (5, True)
    >>> convergence_episode(np.array([1, 1, 1, 1, 1, 0, 0, 1], bool), 3)
    (6, False)
    >>> convergence_episode(np.array([1, 1, 1, 0, 1, 1, 1, 1, 0, 1], bool), 3, level=0.75)
    (1, True)
    """
    passed = np.asarray(passed, dtype=bool)
    n = len(passed)
    censored = max(1, n - window + 1), False
    if n < window:
        return censored
    # share(e … k) ≥ p  ⟺  S[k] ≥ S[e − 1], S the running sum of (pass − p), S[0] = 0.
    running = np.concatenate([[0.0], np.cumsum(passed - level)])
    lowest_after = np.minimum.accumulate(running[::-1])[::-1]  # min over k ≥ j of S[k]
    starts = np.arange(1, n - window + 2)
    stays = lowest_after[starts + window - 1] >= running[starts - 1] - SHARE_MARGIN
    candidates = np.flatnonzero(stays & passed[starts - 1])
    return (int(starts[candidates[0]]), True) if candidates.size else censored


def pass_share_from(passed: np.ndarray, episode: int) -> float:
    """Share of the evaluations from 1-based ``episode`` to the end that pass; NaN for 0 (none).

    >>> pass_share_from(np.array([0, 1, 1, 0], bool), 2)
    0.6666666666666666
    """
    passed = np.asarray(passed, dtype=bool)
    return float(passed[episode - 1 :].mean()) if 1 <= episode <= len(passed) else float("nan")


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


class DrivingClock(NamedTuple):
    """How a run's actions turn into seconds of driving (module docs).

    Attributes:
        action_duration: seconds one action lasts, the robot's ``dt × substeps`` [s] (> 0), or
            NaN for an env without a robot (the seconds columns NaN).
        window: W ≥ 1, the least evaluations of evidence of sustained greedy success (the
            experiment's ``convergence_window``).
    """

    action_duration: float = math.nan
    window: int = 1


def run_metrics(
    episodes: dict[str, np.ndarray],
    greedy_poses: np.ndarray,
    greedy_reached: bool,
    rule: ConvergenceRule | None,
    clock: DrivingClock | None = None,
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
        clock: the action duration and evidence window of the seconds columns
            (:func:`driving_metrics`); None: no robot, the seconds NaN, a window of 1.
    """
    success = episodes["success"].astype(np.float64)
    n = len(success)
    first_success = np.flatnonzero(success > 0)
    nan = float("nan")
    metrics = dict.fromkeys(CONVERGENCE_COLUMNS, nan) | {
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
        metrics.update(convergence_metrics(episodes, rule))
    return metrics | driving_metrics(episodes, clock or DrivingClock())


SUSTAINED_SUCCESS = 0.9
"""Share of an evaluation's rollouts that must reach the goal for sustained greedy success."""

DRIVING_COLUMNS = (
    "action_duration", "driving_seconds",
    "episodes_to_first_success", "seconds_to_first_success",
    "episodes_to_success90", "seconds_to_success90",
)  # fmt: skip
"""The summary columns of :func:`driving_metrics`."""


def driving_seconds(lengths: np.ndarray, episode: float, action_duration: float) -> float:
    """Seconds of driving in episodes 1 … ``episode`` (1-based): the sum of their ``lengths``
    [actions] × ``action_duration`` [s]; NaN for a NaN episode (never reached).

    >>> driving_seconds(np.array([30, 12, 9]), 2, 0.1)
    4.2
    >>> driving_seconds(np.array([30, 12, 9]), float("nan"), 1.0)
    nan
    """
    if not math.isfinite(episode):
        return math.nan
    return float(np.sum(np.asarray(lengths, np.float64)[: int(episode)]) * action_duration)


def sustained_success_episode(greedy_success: np.ndarray, window: int) -> float:
    """The first 1-based episode from whose greedy evaluation on every evaluation had at
    least :data:`SUSTAINED_SUCCESS` of its rollouts reach the goal, with at least ``window``
    evaluations of evidence (:func:`convergence_episode` at level 1); NaN when none.

    >>> sustained_success_episode(np.array([0.0, 1.0, 0.8, 1.0, 0.9, 1.0]), 2)
    4.0
    >>> sustained_success_episode(np.array([0.0, 1.0, 1.0, 1.0, 0.6]), 2)
    nan
    """
    share = np.nan_to_num(np.asarray(greedy_success, np.float64), nan=0.0)
    episode, reached = convergence_episode(share >= SUSTAINED_SUCCESS - SHARE_MARGIN, window)
    return float(episode) if reached else math.nan


SUSTAINED_WINDOW = 10
"""Consecutive training episodes over which sustained success is judged where there are no
greedy evaluations (a robot's episodes: :func:`window_success_episode`)."""


def window_success_episode(success: np.ndarray, window: int = SUSTAINED_WINDOW) -> float:
    """The first 1-based episode that ends ``window`` consecutive episodes of which at least
    :data:`SUSTAINED_SUCCESS` reached the goal (9 of 10 by default); NaN when none (also with
    fewer than ``window`` episodes). Sustained success of a learner judged by its own training
    episodes, exploration included, where there are no greedy evaluations (the robot).

    >>> window_success_episode(np.array([0, 1, 1, 1, 1, 1, 1, 1, 1, 0, 1, 1]))
    11.0
    >>> window_success_episode(np.array([0, 1, 1, 0, 1, 1, 1]), 4)
    nan
    """
    flags = np.asarray(success, dtype=np.float64)
    need = math.ceil(SUSTAINED_SUCCESS * window - SHARE_MARGIN)
    if flags.size < window:
        return math.nan
    ends = np.flatnonzero(np.convolve(flags, np.ones(window), "valid") >= need)
    return float(ends[0] + window) if ends.size else math.nan


def driving_metrics(episodes: dict[str, np.ndarray], clock: DrivingClock) -> dict[str, float]:
    """The seconds-of-driving columns of a run (module docs) from its ``length``, ``success``
    and ``greedy_success`` per episode, shape (N,) each: ``action_duration`` [s],
    ``driving_seconds`` (the whole run), ``episodes_to_first_success`` and
    ``seconds_to_first_success``, ``episodes_to_success90`` and ``seconds_to_success90`` (NaN
    when not reached: censored)."""
    to_success90 = sustained_success_episode(episodes["greedy_success"], clock.window)
    return _driving_columns(episodes, to_success90, float(clock.action_duration))


def training_driving_metrics(
    episodes: dict[str, np.ndarray], action_duration: float, window: int = SUSTAINED_WINDOW
) -> dict[str, float]:
    """The columns of :func:`driving_metrics` for a run without greedy evaluations (a robot's),
    from its ``length`` and ``success`` per episode, shape (N,) each: sustained success is
    :func:`window_success_episode` of the training episodes themselves; ``action_duration``
    [s] per action (NaN: the seconds NaN)."""
    to_success90 = window_success_episode(episodes["success"], window)
    return _driving_columns(episodes, to_success90, float(action_duration))


def _driving_columns(
    episodes: dict[str, np.ndarray], to_success90: float, duration: float
) -> dict[str, float]:
    """:data:`DRIVING_COLUMNS` of a run whose sustained success came at episode
    ``to_success90`` (NaN: never), its actions lasting ``duration`` [s]."""
    lengths = episodes["length"]
    first = np.flatnonzero(np.asarray(episodes["success"]) > 0)
    to_first = float(first[0] + 1) if first.size else math.nan
    return {
        "action_duration": duration,
        "driving_seconds": driving_seconds(lengths, len(lengths), duration),
        "episodes_to_first_success": to_first,
        "seconds_to_first_success": driving_seconds(lengths, to_first, duration),
        "episodes_to_success90": to_success90,
        "seconds_to_success90": driving_seconds(lengths, to_success90, duration),
    }


CONVERGENCE_COLUMNS = (
    "convergence_episode", "convergence_steps", "converged", "pass_share_after",
    "first_window_episode",
    "pass_share_after_first_window", "pass_share_last10", "optimality_gap",
)  # fmt: skip
"""The summary columns of :func:`convergence_metrics` (NaN without a rule)."""


def convergence_metrics(episodes: dict[str, np.ndarray], rule: ConvergenceRule) -> dict[str, float]:
    """The convergence columns of a run (module docs) from its ``rule.measure`` and
    ``greedy_success`` and ``length`` per episode, shape (N,) each: ``convergence_episode`` and
    ``converged`` (1.0 / 0.0), ``convergence_steps`` (real actions taken in episodes 1 … e, the
    convergence or censoring episode: the experience it cost), ``pass_share_after`` (NaN when
    censored), ``first_window_episode`` (NaN when no window passed),
    ``pass_share_after_first_window``, ``pass_share_last10``, ``optimality_gap``."""
    mean, share = episodes[rule.measure], episodes["greedy_success"]
    passed = within_tolerance(mean, share, rule)
    episode, converged = convergence_episode(passed, rule.window, rule.level)
    first = first_window(passed, rule.window)
    return {
        "convergence_episode": float(episode),
        "convergence_steps": float(np.sum(episodes["length"][:episode])),
        "converged": float(converged),
        "pass_share_after": pass_share_from(passed, episode) if converged else math.nan,
        "first_window_episode": float(first) if first else math.nan,
        "pass_share_after_first_window": pass_share_from(passed, first),
        "pass_share_last10": float(last_share(passed).mean()),
        "optimality_gap": optimality_gap(mean[-rule.window :], rule.reference),
    }
