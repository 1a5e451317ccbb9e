"""Per-run metrics on hand-made evaluations: the oracle-relative, fixed-window convergence rule."""

from __future__ import annotations

import numpy as np
import pytest

from skidnav.experiments.metrics import (
    ConvergenceRule,
    convergence_episode,
    evaluation_summary,
    moving_average,
    path_length,
    run_metrics,
    within_tolerance,
)


def test_evaluation_summary_means_over_the_rollouts_that_reached_the_goal() -> None:
    lengths = np.array([[10, 12, -1], [-1, -1, -1], [9, 9, 9]])
    mean, share = evaluation_summary(lengths)
    assert mean[0] == 11.0 and np.isnan(mean[1]) and mean[2] == 9.0
    assert share.tolist() == pytest.approx([2 / 3, 0.0, 1.0])


def test_within_tolerance_needs_every_rollout_and_a_short_enough_mean() -> None:
    rule = ConvergenceRule(reference=20.0, tolerance=0.1, window=3)
    mean = np.array([21.0, 22.0, 22.1, 15.0, np.nan])
    share = np.array([1.0, 1.0, 1.0, 0.8, 0.0])
    # 22 = 1.1 · 20 is inside; 22.1 is not; a shorter mean with a failed rollout is not.
    assert within_tolerance(mean, share, rule).tolist() == [True, True, False, False, False]


def test_convergence_needs_a_full_window() -> None:
    within = np.array([0, 1, 1, 0, 1, 1, 1, 1, 0, 0], dtype=bool)
    assert convergence_episode(within, 3) == (5, True)
    assert convergence_episode(within, 4) == (5, True)
    assert convergence_episode(within, 5) == (6, False)  # censored at N − W + 1 = 6
    assert convergence_episode(within, 1) == (2, True)
    assert convergence_episode(within[:2], 3) == (1, False)  # shorter than the window


def test_convergence_does_not_depend_on_the_horizon() -> None:
    rng = np.random.default_rng(4)
    for _ in range(200):
        within = rng.random(60) < rng.uniform(0.3, 0.95)
        episode, converged = convergence_episode(within, 5)
        for horizon in range(5, 60):
            short, short_converged = convergence_episode(within[:horizon], 5)
            if converged and episode + 4 <= horizon:
                assert (short, short_converged) == (episode, True)
            else:  # not yet seen: censored where the short run could no longer confirm it
                assert (short, short_converged) == (horizon - 4, False)


def _episodes(greedy_length: np.ndarray, greedy_success: np.ndarray) -> dict[str, np.ndarray]:
    n = len(greedy_length)
    return {
        "return": np.arange(n, dtype=float),
        "length": np.full(n, 30),
        "success": np.array([0, 0, 1, 1, 1, 1, 1, 1, 1, 1], dtype=bool),
        "collisions": np.ones(n, dtype=int),
        "planning_updates": np.full(n, 5),
        "wall_time": np.full(n, 0.5),
        "greedy_length": greedy_length,
        "greedy_success": greedy_success,
    }


def test_run_metrics_values() -> None:
    greedy = np.array([np.nan, 50, 40, 21, 22, 30, 21, 20, 19, 20])
    share = np.array([0.0] + [1.0] * 9)
    poses = np.array([[0, 0, 0], [1.0, 0, 0]])
    metrics = run_metrics(_episodes(greedy, share), poses, True, ConvergenceRule(20.0, 0.1, 3))
    assert metrics["convergence_episode"] == 7  # 21, 20, 19 from episode 7; 30 broke the first
    assert metrics["converged"] == 1.0
    assert metrics["optimality_gap"] == pytest.approx((20 + 19 + 20) / 3 / 20 - 1)  # last W = 3
    assert metrics["first_success_episode"] == 3
    assert metrics["success_rate"] == pytest.approx(0.8)
    assert metrics["success_rate_last10"] == 1.0
    assert metrics["final_length_actions"] == 1  # the final rollout: 2 poses, 1 action
    assert metrics["final_length_m"] == 1.0
    assert metrics["planning_updates"] == 50
    assert metrics["mean_return_last10"] == 9.0
    failed = run_metrics(_episodes(greedy, share), poses, False, ConvergenceRule(20.0, 0.1, 3))
    assert np.isnan(failed["final_length_m"]) and np.isnan(failed["final_length_actions"])


def test_a_policy_that_never_gets_close_to_the_oracle_is_censored() -> None:
    greedy, share = np.full(10, 30.0), np.ones(10)  # reaches the goal, 50 % longer than L*
    metrics = run_metrics(
        _episodes(greedy, share), np.zeros((1, 3)), False, ConvergenceRule(20.0, 0.1, 3)
    )
    assert (metrics["convergence_episode"], metrics["converged"]) == (8, 0.0)
    assert metrics["optimality_gap"] == pytest.approx(0.5)
    no_oracle = run_metrics(_episodes(greedy, share), np.zeros((1, 3)), False, None)
    assert np.isnan(no_oracle["convergence_episode"]) and np.isnan(no_oracle["converged"])


def test_path_length_and_moving_average() -> None:
    poses = np.array([[0, 0, 0], [0.3, 0.4, 0], [0.3, 0.4, 1.0], [0.3, 0.0, 0]])
    assert path_length(poses) == pytest.approx(0.9)
    assert path_length(poses[:1]) == 0.0
    assert moving_average(np.array([1.0, 2, 3, 4]), 2) == pytest.approx([1, 1.5, 2.5, 3.5])
