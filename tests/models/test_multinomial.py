"""The sparse multinomial transition model (skidnav.models.multinomial)."""

from __future__ import annotations

import numpy as np
import pytest

from skidnav.errors import CorruptFileError
from skidnav.kernels.multinomial import EXPECTED, MOST_PROBABLE, SAMPLE, find_pair, model_target
from skidnav.models.multinomial import MultinomialModel


def deterministic_mdp(n_states: int, n_actions: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.integers(0, n_states, (n_states, n_actions)), rng.normal(size=(n_states, n_actions))


def test_exact_on_a_deterministic_mdp() -> None:
    next_state, reward = deterministic_mdp(40, 3, seed=0)
    model = MultinomialModel(3, capacity=4)  # small capacity: growth and rehashing happen
    rng = np.random.default_rng(1)
    for _ in range(2000):
        s, a = int(rng.integers(40)), int(rng.integers(3))
        model.observe(s, a, reward[s, a], int(next_state[s, a]), next_state[s, a] == 0)
    assert model.n_pairs == 120 == model.n_outcomes
    for s in range(40):
        for a in range(3):
            out = model.outcomes(s, a)
            assert out.next_states.tolist() == [next_state[s, a]]
            assert out.probabilities.tolist() == [1.0]
            assert out.mean_rewards[0] == pytest.approx(reward[s, a])
            assert out.termination.tolist() == [float(next_state[s, a] == 0)]


def test_stochastic_rows_sum_to_one_and_match_counts() -> None:
    rng = np.random.default_rng(2)
    truth = np.array([0.5, 0.3, 0.2])
    counts = np.zeros(3)
    model = MultinomialModel(2)
    for _ in range(5000):
        outcome = int(rng.choice(3, p=truth))
        counts[outcome] += 1
        model.observe(7, 1, float(outcome), 10 + outcome, False)
    out = model.outcomes(7, 1)
    assert out.probabilities.sum() == pytest.approx(1.0)
    order = np.argsort(out.next_states)
    assert out.counts[order].tolist() == counts.tolist()
    assert np.allclose(out.probabilities[order], truth, atol=0.03)
    assert out.mean_rewards[order].tolist() == [0.0, 1.0, 2.0]
    assert model.count(7, 1) == 5000 and model.count(7, 0) == 0


def test_planning_targets_in_each_mode() -> None:
    model = MultinomialModel(1)
    for _ in range(3):
        model.observe(0, 0, 1.0, 1, False)
    model.observe(0, 0, 5.0, 2, True)
    q = np.array([[0.0], [10.0], [99.0]])
    pair = find_pair(model.arrays, 0, 0)
    rng = np.random.default_rng(0)
    assert model_target(model.arrays, q, pair, MOST_PROBABLE, 0.5, rng.random()) == 1.0 + 0.5 * 10.0
    expected = 0.75 * (1.0 + 5.0) + 0.25 * 5.0
    assert model_target(model.arrays, q, pair, EXPECTED, 0.5, rng.random()) == pytest.approx(
        expected
    )
    samples = [model_target(model.arrays, q, pair, SAMPLE, 0.5, rng.random()) for _ in range(2000)]
    assert set(samples) == {6.0, 5.0}
    assert np.mean(np.array(samples) == 5.0) == pytest.approx(0.25, abs=0.04)


def test_predecessors() -> None:
    model = MultinomialModel(4)
    model.observe(1, 0, 0.0, 5, False)
    model.observe(2, 3, 0.0, 5, False)
    model.observe(2, 3, 0.0, 6, False)
    model.observe(5, 1, 0.0, 5, False)
    assert sorted(model.predecessors(5)) == [(1, 0), (2, 3), (5, 1)]
    assert model.predecessors(6) == [(2, 3)]
    assert model.predecessors(1) == []


def test_memory_grows_with_transitions_not_states() -> None:
    rng = np.random.default_rng(0)
    sizes = []
    for n_states in (360_000, 36_000_000):
        model = MultinomialModel(4)
        states = rng.integers(0, n_states, 20_000)
        for s, s2 in zip(states.tolist(), np.roll(states, 1).tolist(), strict=True):
            model.observe(s, s % 4, -1.0, s2, False)
        sizes.append(model.nbytes)
    assert sizes[0] == sizes[1]
    assert sizes[0] < 300 * 20_000


def test_round_trip_and_corrupt_arrays() -> None:
    model = MultinomialModel(2)
    for s in range(300):
        model.observe(s, s % 2, float(s), (s * 7) % 50, s == 3)
    copy = MultinomialModel.from_arrays(model.to_arrays())
    for s in range(300):
        original, loaded = model.outcomes(s, s % 2), copy.outcomes(s, s % 2)
        assert original.next_states.tolist() == loaded.next_states.tolist()
        assert original.mean_rewards.tolist() == loaded.mean_rewards.tolist()
    assert sorted(copy.predecessors(7)) == sorted(model.predecessors(7))
    broken = model.to_arrays()
    broken["model.entry_sibling"] = broken["model.entry_sibling"] + 10_000
    with pytest.raises(CorruptFileError):
        MultinomialModel.from_arrays(broken)
    del broken["model.pair_key"]
    with pytest.raises(CorruptFileError):
        MultinomialModel.from_arrays(broken)
