"""The one TD update and ε-greedy rule (skidnav.sim.q_values)."""

from __future__ import annotations

import numpy as np
import pytest

from skidnav.sim.q_values import (
    epsilon_at,
    epsilon_greedy,
    greedy_first,
    random_argmax,
    td_target,
    td_update,
)


def test_td_update_matches_hand_computation() -> None:
    q = np.zeros((3, 2))
    q[2] = [0.4, -1.0]
    q[1, 0] = 0.2
    # target = -1 + 0.9 * 0.4 = -0.64; error = -0.64 - 0.2 = -0.84; new = 0.2 + 0.5 * -0.84
    error = td_update(q, 1, 0, -1.0, 2, False, 0.5, 0.9)
    assert error == pytest.approx(-0.84)
    assert q[1, 0] == pytest.approx(-0.22)
    assert q[2].tolist() == [0.4, -1.0]  # only (s, a) changes


def test_terminated_does_not_bootstrap_but_truncated_does() -> None:
    q_terminated = np.zeros((2, 2))
    q_terminated[1] = [5.0, 7.0]
    q_truncated = q_terminated.copy()
    td_update(q_terminated, 0, 1, 1.0, 1, True, 1.0, 0.5)
    # A truncated step is not a termination: the agent passes terminated=False.
    td_update(q_truncated, 0, 1, 1.0, 1, False, 1.0, 0.5)
    assert q_terminated[0, 1] == 1.0
    assert q_truncated[0, 1] == 1.0 + 0.5 * 7.0


def test_fractional_continuation_weights_the_bootstrap() -> None:
    q = np.array([[0.0], [4.0]])
    assert td_target(q, 1.0, 1, 0.25, 0.5) == pytest.approx(1.0 + 0.5 * 0.25 * 4.0)
    q[1] = np.nan  # a terminal row is never read
    assert td_target(q, 1.0, 1, 0.0, 0.5) == 1.0


def test_random_argmax_breaks_ties_uniformly() -> None:
    q = np.array([[1.0, 3.0, 3.0, 2.0, 3.0]])
    rng = np.random.default_rng(0)
    picks = np.array([random_argmax(q, 0, rng) for _ in range(3000)])
    counts = np.bincount(picks, minlength=5)
    assert counts[0] == counts[3] == 0
    assert np.all(np.abs(counts[[1, 2, 4]] - 1000) < 120)
    assert greedy_first(q, 0) == 1


def test_random_argmax_without_tie_draws_nothing() -> None:
    q = np.array([[0.0, 1.0]])
    rng = np.random.default_rng(3)
    before = rng.bit_generator.state
    assert random_argmax(q, 0, rng) == 1
    assert rng.bit_generator.state == before


def test_epsilon_greedy_explores_at_rate_epsilon() -> None:
    q = np.array([[0.0, 1.0, 0.0, 0.0]])
    rng = np.random.default_rng(1)
    actions = np.array([epsilon_greedy(q, 0, 0.2, rng) for _ in range(4000)])
    # Greedy with prob 0.8 + 0.2/4; every other action 0.05.
    assert np.mean(actions == 1) == pytest.approx(0.85, abs=0.025)
    assert np.mean(actions == 3) == pytest.approx(0.05, abs=0.015)
    assert all(epsilon_greedy(q, 0, 0.0, rng) == 1 for _ in range(50))


def test_epsilon_schedule_decays_to_its_floor() -> None:
    values = [epsilon_at(k, 1.0, 0.5, 0.1) for k in range(6)]
    assert values == [1.0, 0.5, 0.25, 0.125, 0.1, 0.1]
