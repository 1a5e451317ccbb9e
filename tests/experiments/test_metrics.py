"""Per-run metrics on hand-made evaluations: the oracle-relative, fixed-window convergence rule."""

from __future__ import annotations

import numpy as np
import pytest

from skidnav.experiments.metrics import (
    ConvergenceRule,
    convergence_episode,
    evaluation_summary,
    first_window,
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


def test_convergence_is_the_first_pass_from_which_the_share_stays() -> None:
    passed = np.array([0, 1, 1, 0, 1, 1, 1, 1, 1, 1], dtype=bool)
    assert convergence_episode(passed, 3) == (5, True)
    assert convergence_episode(passed, 1) == (5, True)  # level 1: every later evaluation passes
    assert convergence_episode(passed, 3, level=2 / 3) == (2, True)  # one miss in 3 allowed
    assert convergence_episode(passed[:2], 3) == (1, False)  # shorter than the window
    # The last evaluation fails: at level 1 censored at N − W + 1, whatever came before; at a
    # level the whole run keeps (8 of 11 from episode 2 on), converged as before.
    assert convergence_episode(np.append(passed, [0, 0]), 3) == (10, False)
    assert convergence_episode(np.append(passed, [0, 0]), 3, level=2 / 3) == (2, True)


def test_a_run_that_converges_and_then_degrades_is_not_converged() -> None:
    # 200 passing evaluations, then the greedy policy drifts away for good.
    passed = np.concatenate([np.zeros(30), np.ones(200), np.zeros(100)]).astype(bool)
    assert first_window(passed, 10) == 31  # the first-window rule would call it converged
    assert convergence_episode(passed, 10, level=0.9) == (321, False)
    # A policy that keeps failing now and then, at random, stays converged at its level.
    noisy = np.random.default_rng(1).random(5000) > 0.03
    episode, converged = convergence_episode(noisy, 10, level=0.9)
    assert converged and episode < 20
    metrics = run_metrics(
        _episodes(np.where(passed, 20.0, 40.0), np.ones(passed.size)),
        np.zeros((1, 3)),
        False,
        ConvergenceRule(20.0, 0.1, 10, 0.9),
    )
    assert metrics["converged"] == 0.0 and np.isnan(metrics["pass_share_after"])
    assert metrics["first_window_episode"] == 31
    assert metrics["pass_share_after_first_window"] == pytest.approx(200 / 300)
    assert metrics["pass_share_last10"] == 0.0
    # A brief relapse within the level does not undo convergence.
    blip = np.concatenate([np.zeros(30), np.ones(300)]).astype(bool)
    blip[100] = False
    assert convergence_episode(blip, 10, level=0.9) == (31, True)
    assert convergence_episode(blip, 10, level=1.0) == (102, True)


def test_longer_runs_only_reveal_whether_a_policy_stayed() -> None:
    rng = np.random.default_rng(4)
    seen_converged = 0
    for _ in range(200):
        passed = rng.random(80) < rng.uniform(0.5, 0.99)
        level = rng.choice([0.6, 0.8, 1.0])
        episode, converged = convergence_episode(passed, 5, level)
        for horizon in range(5, 80):
            short, short_converged = convergence_episode(passed[:horizon], 5, level)
            if converged and episode + 4 <= horizon:
                assert short_converged and short <= episode  # never later over a shorter run
                seen_converged += 1
            if not short_converged:
                assert short == horizon - 4
        if level == 1.0 and converged:  # every evaluation from e on passes: exact
            assert convergence_episode(passed[: episode + 4], 5, level) == (episode, True)
    assert seen_converged > 100


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
    assert metrics["pass_share_after"] == 1.0
    assert metrics["first_window_episode"] == 7
    assert metrics["pass_share_last10"] == 1.0
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


def test_convergence_can_be_measured_in_cost_against_c_star() -> None:
    episodes = _episodes(np.full(10, 20.0), np.ones(10))
    episodes["greedy_cost"] = np.full(10, 30.0)  # a path as short as L*, but through slip
    by_actions = ConvergenceRule(20.0, 0.1, 3, 0.9)
    by_cost = ConvergenceRule(20.0, 0.1, 3, 0.9, measure="greedy_cost")
    assert run_metrics(episodes, np.zeros((1, 3)), False, by_actions)["converged"] == 1.0
    assert run_metrics(episodes, np.zeros((1, 3)), False, by_cost)["converged"] == 0.0
    assert (
        run_metrics(episodes, np.zeros((1, 3)), False, by_cost._replace(reference=28.0))[
            "converged"
        ]
        == 1.0
    )
