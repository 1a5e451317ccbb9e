"""Per-run metrics on hand-made curves."""

from __future__ import annotations

import numpy as np
import pytest

from skidnav.experiments.metrics import (
    convergence_episode,
    moving_average,
    path_length,
    run_metrics,
    training_convergence_episode,
)


def test_convergence_episode_hand_made_curves() -> None:
    ok = np.ones(8, dtype=bool)
    # Within 10 % of the final 20 (18..22) from episode 4 on.
    curve = np.array([90, 60, 30, 22, 19, 21, 20, 20], dtype=float)
    assert convergence_episode(curve, ok, 0.10) == 4
    # A later excursion resets convergence.
    curve = np.array([90, 20, 20, 40, 20, 20, 20, 20], dtype=float)
    assert convergence_episode(curve, ok, 0.10) == 5
    # A wider tolerance (±20) accepts the excursion to 40 but not the first 90.
    assert convergence_episode(curve, ok, 1.0) == 2
    # Constant from the start.
    assert convergence_episode(np.full(5, 14.0), np.ones(5, bool), 0.1) == 1


def test_failed_evaluations_never_count_as_converged() -> None:
    curve = np.array([np.nan, 20, np.nan, 20, 20], dtype=float)
    reached = ~np.isnan(curve)
    assert convergence_episode(curve, reached, 0.1) == 4
    # Final evaluation failed: not converged, censored at N.
    reached_last_failed = np.array([True, True, True, True, False])
    assert convergence_episode(np.full(5, 20.0), reached_last_failed, 0.1) == 5


def test_training_view_uses_moving_average() -> None:
    lengths = np.concatenate([np.full(20, 100.0), np.full(40, 30.0)])
    # window = round(60/20) = 3: the average reaches 30 exactly at episode 23.
    assert training_convergence_episode(lengths, 0.1) == 23
    assert moving_average(np.array([1.0, 2, 3, 4]), 2) == pytest.approx([1, 1.5, 2.5, 3.5])


def test_path_length() -> None:
    poses = np.array([[0, 0, 0], [0.3, 0.4, 0], [0.3, 0.4, 1.0], [0.3, 0.0, 0]])
    assert path_length(poses) == pytest.approx(0.9)
    assert path_length(poses[:1]) == 0.0


def test_run_metrics_values() -> None:
    n = 10
    episodes = {
        "return": np.arange(n, dtype=float),
        "length": np.full(n, 30),
        "success": np.array([0, 0, 1, 1, 1, 1, 1, 1, 1, 1], dtype=bool),
        "collisions": np.ones(n, dtype=int),
        "planning_updates": np.full(n, 5),
        "wall_time": np.full(n, 0.5),
        "greedy_length": np.array([np.nan, 50, 40, 30, 31, 30, 29, 30, 30, 30]),
        "greedy_success": np.array([False] + [True] * 9),
    }
    poses = np.array([[0, 0, 0], [1.0, 0, 0]])
    metrics = run_metrics(episodes, poses, True, 0.1)
    assert metrics["convergence_episode"] == 4
    assert metrics["converged"] == 1.0
    assert metrics["first_success_episode"] == 3
    assert metrics["success_rate"] == pytest.approx(0.8)
    assert metrics["success_rate_last10"] == 1.0
    assert metrics["final_length_actions"] == 1  # the final rollout: 2 poses, 1 action
    assert metrics["final_length_m"] == 1.0
    assert metrics["planning_updates"] == 50
    assert metrics["mean_return_last10"] == 9.0
    failed = run_metrics(episodes, poses, False, 0.1)
    assert np.isnan(failed["final_length_m"]) and np.isnan(failed["final_length_actions"])


def test_robust_view_ignores_an_isolated_late_blip() -> None:
    from skidnav.experiments.metrics import robust_convergence_episode, trailing_median

    curve = np.array([np.nan] * 5 + [10.0] * 30 + [np.nan] + [10.0] * 3 + [16.0] + [10.0] * 20)
    reached = ~np.isnan(curve)
    assert convergence_episode(curve, reached, 0.1) == 41  # strict: the blips reset it
    # window round(60 / 20) = 3: the median is 10 from episode 7 on.
    assert robust_convergence_episode(curve, 0.1) == 7
    assert trailing_median(np.array([1.0, np.nan, 3.0]), 2).tolist() == [1.0, np.inf, np.inf]
