"""The sparse multinomial transition model (skidnav.models.multinomial)."""

from __future__ import annotations

import numpy as np
import pytest

from skidnav.errors import CorruptFileError
from skidnav.models.multinomial import MultinomialModel
from skidnav.models.multinomial_kernels import find_pair
from skidnav.models.multinomial_targets import EXPECTED, MOST_PROBABLE, SAMPLE, model_target


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


def _stochastic_model() -> MultinomialModel:
    rng = np.random.default_rng(4)
    model = MultinomialModel(3, capacity=4)
    for _ in range(3000):
        s, a = int(rng.integers(60)), int(rng.integers(3))
        s2 = (s + a + int(rng.integers(3))) % 60
        model.observe(s, a, float(rng.normal()), s2, bool(s2 == 0 and rng.random() < 0.5))
    return model


def _tampered(model: MultinomialModel, name: str, change: object) -> dict[str, np.ndarray]:
    saved = model.to_arrays()
    values = saved[f"model.{name}"].copy()
    if callable(change):
        change(values)
    else:
        values[...] = change
    saved[f"model.{name}"] = values
    return saved


def _swap_first_two(values: np.ndarray) -> None:
    values[[0, 1]] = values[[1, 0]]


@pytest.mark.parametrize(
    ("name", "change"),
    [
        ("entry_sibling", 0),  # every outcome list loops on entry 0
        ("entry_sibling", lambda v: v.__setitem__(5, 5)),  # a self-loop
        ("entry_sibling", lambda v: v.__setitem__(3, v.size + 2)),  # out of range
        ("entry_sibling", lambda v: v.__setitem__(np.flatnonzero(v >= 0)[0], -1)),  # cut a list
        ("entry_pred_link", 0),
        ("entry_pred_link", lambda v: v.__setitem__(np.flatnonzero(v >= 0)[0], v.size - 1)),
        ("pair_head", _swap_first_two),  # each pair heads the other's list
        ("pair_head", lambda v: v.__setitem__(0, -1)),
        ("target_head", lambda v: v.__setitem__(0, v[1])),
        ("pair_total", lambda v: v.__setitem__(7, v[7] + 1)),  # counts no longer add up
        ("entry_count", lambda v: v.__setitem__(7, 0)),
        ("entry_terminal_count", lambda v: v.__setitem__(2, v[2] + 10**6)),
        ("entry_pair", _swap_first_two),
        ("entry_next_state", lambda v: v.__setitem__(4, v[4] + 1)),  # not its target's state
        ("entry_reward_sum", np.nan),
        ("pair_key", lambda v: v.__setitem__(1, v[0])),  # two slots for one pair
        ("pair_key", lambda v: v.__setitem__(1, -4)),
    ],
)
def test_tampered_arrays_are_rejected(name: str, change: object) -> None:
    model = _stochastic_model()
    with pytest.raises(CorruptFileError, match="inconsistent multinomial model arrays"):
        MultinomialModel.from_arrays(_tampered(model, name, change))


def test_arrays_of_the_wrong_length_or_type_are_rejected() -> None:
    model = _stochastic_model()
    saved = model.to_arrays()
    for name, values in (
        ("model.entry_count", saved["model.entry_count"][:-1]),
        ("model.pair_head", saved["model.pair_head"].astype(np.float64)),
        ("model.target_head", saved["model.target_head"].reshape(1, -1)),
    ):
        with pytest.raises(CorruptFileError, match=name.removeprefix("model.")):
            MultinomialModel.from_arrays({**saved, name: values})


def _most_probable_by_definition(model: MultinomialModel, pair: int, uniform: float) -> int:
    """Walk the outcome list: the int(uniform · n_ties)-th outcome of the largest count."""
    arrays, entries = model.arrays, []
    entry = int(arrays.pair_head[pair])
    while entry >= 0:
        entries.append(entry)
        entry = int(arrays.entry_sibling[entry])
    counts = arrays.entry_count[entries]
    tied = [e for e, count in zip(entries, counts, strict=True) if count == counts.max()]
    return tied[int(uniform * len(tied))]


def test_most_probable_cache_matches_the_definition_live_and_after_loading() -> None:
    model = _stochastic_model()
    loaded = MultinomialModel.from_arrays(model.to_arrays())
    q = np.random.default_rng(0).normal(size=(60, 3))
    n_pairs = model.n_pairs
    assert 0 < int((model.arrays.pair_ties[:n_pairs] > 1).sum()) < n_pairs  # ties and no ties
    for current in (model, loaded):
        arrays = current.arrays
        for pair in range(n_pairs):
            for uniform in (0.0, 0.49, 0.99):
                entry = _most_probable_by_definition(current, pair, uniform)
                count = arrays.entry_count[entry]
                expected = (
                    arrays.entry_reward_sum[entry] / count
                    + 0.9
                    * (1.0 - arrays.entry_terminal_count[entry] / count)
                    * q[arrays.entry_next_state[entry]].max()
                )
                if arrays.entry_terminal_count[entry] == count:
                    expected = arrays.entry_reward_sum[entry] / count
                got = model_target(arrays, q, pair, MOST_PROBABLE, 0.9, uniform)
                assert got == expected, (pair, uniform)
    ties = model.arrays.pair_ties[:n_pairs]
    np.testing.assert_array_equal(loaded.arrays.pair_ties[:n_pairs], ties)
    unique = ties == 1  # with ties the cached outcome may be any of the tied ones
    for name in ("pair_best", "pair_best_next", "pair_best_reward", "pair_best_continuation"):
        np.testing.assert_array_equal(
            getattr(loaded.arrays, name)[:n_pairs][unique],
            getattr(model.arrays, name)[:n_pairs][unique],
            name,
        )
