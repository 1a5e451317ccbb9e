"""Sparse multinomial transition model learned from counts (Alhawary (2020), ch. 7).

From real transitions the model keeps N(s, a, s′), and estimates

* p(s′ | s, a) = N(s, a, s′) / N(s, a) — each observed row sums to 1;
* r̄(s, a, s′), the mean reward of that outcome;
* β(s, a, s′), the share of those transitions that terminated the episode.

It is exact on a deterministic MDP after one visit per pair. Memory grows with the number of
distinct observed pairs and outcomes (growable arrays and open-addressing hash tables, see
:mod:`skidnav.models.multinomial_kernels`), never with S²·A. The predecessor relation ("which (s, a)
have led to s′") is kept too, for prioritized sweeping (Sutton & Barto (2018) §8.4).

The arrays live in :attr:`MultinomialModel.arrays` (a :class:`MultinomialArrays` named tuple) so
compiled planners can read and update them directly; call :meth:`MultinomialModel.reserve` with the
number of transitions about to be added before a compiled loop observes them.

>>> import numpy as np
>>> model = MultinomialModel(n_actions=2)
>>> model.observe(0, 1, -1.0, 3, False)  # returns the pair slot
0
>>> _ = model.observe(0, 1, -1.0, 3, False)
>>> _ = model.observe(0, 1, 10.0, 4, True)
>>> outcomes = model.outcomes(0, 1)
>>> outcomes.next_states.tolist(), outcomes.probabilities.round(3).tolist()
([4, 3], [0.333, 0.667])
>>> outcomes.mean_rewards.tolist(), outcomes.termination.tolist()
([10.0, -1.0], [1.0, 0.0])
>>> model.predecessors(4)
[(0, 1)]
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from skidnav.errors import CorruptFileError
from skidnav.models.multinomial_kernels import (
    MultinomialArrays,
    find_pair,
    first_predecessor,
    hash_rebuild,
    model_observe,
    split_key,
)

_INITIAL_CAPACITY = 256
_PAIR_FIELDS = ("pair_key", "pair_total", "pair_head")
_ENTRY_FIELDS = (
    "entry_next_state",
    "entry_count",
    "entry_reward_sum",
    "entry_terminal_count",
    "entry_pair",
    "entry_sibling",
    "entry_pred_link",
)
_TARGET_FIELDS = ("target_state", "target_head")
_CACHE_FIELDS = (
    "pair_best",
    "pair_ties",
    "pair_best_next",
    "pair_best_reward",
    "pair_best_continuation",
)
"""Per-pair most-probable cache: grown with the pairs, never saved (rebuilt on load)."""


class Outcomes(NamedTuple):
    """The learned distribution of one (s, a): arrays of shape (n_outcomes,), newest first."""

    next_states: np.ndarray
    """Observed next states s′ (int64)."""
    counts: np.ndarray
    """N(s, a, s′) (int64)."""
    probabilities: np.ndarray
    """p(s′ | s, a) (float64), sums to 1."""
    mean_rewards: np.ndarray
    """r̄(s, a, s′) (float64)."""
    termination: np.ndarray
    """β(s, a, s′): share of the transitions that terminated (float64 in [0, 1])."""


def _empty_arrays(n_actions: int, capacity: int) -> MultinomialArrays:
    def ints(size: int, fill: int = 0) -> np.ndarray:
        return np.full(size, fill, dtype=np.int64)

    return MultinomialArrays(
        n_actions=n_actions,
        counters=ints(3),
        pair_table=ints(2 * capacity, -1),
        pair_key=ints(capacity),
        pair_total=ints(capacity),
        pair_head=ints(capacity),
        pair_best=ints(capacity),
        pair_ties=ints(capacity),
        pair_best_next=ints(capacity),
        pair_best_reward=np.zeros(capacity, dtype=np.float64),
        pair_best_continuation=np.zeros(capacity, dtype=np.float64),
        entry_next_state=ints(capacity),
        entry_count=ints(capacity),
        entry_reward_sum=np.zeros(capacity, dtype=np.float64),
        entry_terminal_count=ints(capacity),
        entry_pair=ints(capacity),
        entry_sibling=ints(capacity),
        entry_pred_link=ints(capacity),
        target_table=ints(2 * capacity, -1),
        target_state=ints(capacity),
        target_head=ints(capacity),
    )


def _grown(array: np.ndarray, capacity: int) -> np.ndarray:
    bigger = np.zeros(capacity, dtype=array.dtype)
    bigger[: array.shape[0]] = array
    return bigger


def _capacity_for(needed: int, current: int) -> int:
    capacity = current
    while capacity < needed:
        capacity *= 2
    return capacity


class MultinomialModel:
    """Counts of real transitions over ``n_actions`` actions (states are any int ≥ 0)."""

    def __init__(self, n_actions: int, capacity: int = _INITIAL_CAPACITY) -> None:
        if n_actions < 1:
            raise ValueError(f"expected n_actions >= 1, got {n_actions}")
        if capacity < 1 or capacity & (capacity - 1):
            raise ValueError(f"expected a power-of-two capacity, got {capacity}")
        self.arrays = _empty_arrays(n_actions, capacity)

    @property
    def n_actions(self) -> int:
        """Number of actions."""
        return self.arrays.n_actions

    @property
    def n_pairs(self) -> int:
        """Distinct (s, a) pairs observed."""
        return int(self.arrays.counters[0])

    @property
    def n_outcomes(self) -> int:
        """Distinct (s, a, s′) transitions observed."""
        return int(self.arrays.counters[1])

    @property
    def nbytes(self) -> int:
        """Bytes held by the model's arrays."""
        return sum(array.nbytes for array in self.arrays[1:])

    def visited_pairs(self) -> np.ndarray:
        """Flat keys ``s · n_actions + a`` of the observed pairs, in order of first visit."""
        return self.arrays.pair_key[: self.n_pairs].copy()

    def reserve(self, n_transitions: int) -> None:
        """Make room for ``n_transitions`` more observations (grows arrays by doubling)."""
        arrays = self.arrays
        need = arrays.counters + n_transitions
        pairs = _capacity_for(int(need[0]), arrays.pair_key.shape[0])
        entries = _capacity_for(int(need[1]), arrays.entry_count.shape[0])
        targets = _capacity_for(int(need[2]), arrays.target_state.shape[0])
        changes: dict[str, np.ndarray] = {}
        if pairs > arrays.pair_key.shape[0]:
            grown = _PAIR_FIELDS + _CACHE_FIELDS
            changes.update({name: _grown(getattr(arrays, name), pairs) for name in grown})
            changes["pair_table"] = np.full(2 * pairs, -1, dtype=np.int64)
            hash_rebuild(changes["pair_table"], changes["pair_key"], int(arrays.counters[0]))
        if entries > arrays.entry_count.shape[0]:
            changes.update({name: _grown(getattr(arrays, name), entries) for name in _ENTRY_FIELDS})
        if targets > arrays.target_state.shape[0]:
            changes.update(
                {name: _grown(getattr(arrays, name), targets) for name in _TARGET_FIELDS}
            )
            changes["target_table"] = np.full(2 * targets, -1, dtype=np.int64)
            hash_rebuild(changes["target_table"], changes["target_state"], int(arrays.counters[2]))
        if changes:
            self.arrays = arrays._replace(**changes)  # type: ignore[arg-type]

    def prepare(self, state: int, action: int, next_state: int) -> None:
        """Check a transition and make room for it, before a compiled kernel counts it
        (:func:`skidnav.models.multinomial_kernels.model_observe`); ValueError if it is invalid."""
        if not 0 <= action < self.n_actions or state < 0 or next_state < 0:
            raise ValueError(f"expected a valid transition, got ({state}, {action}, {next_state})")
        self.reserve(1)

    def observe(
        self, state: int, action: int, reward: float, next_state: int, terminated: bool
    ) -> int:
        """Count one real transition (s, a, r, s′, terminated); returns its pair slot."""
        self.prepare(state, action, next_state)
        return int(
            model_observe(self.arrays, state, action, float(reward), next_state, bool(terminated))
        )

    def count(self, state: int, action: int) -> int:
        """N(s, a): how many times the pair was observed."""
        pair = find_pair(self.arrays, state, action)
        return 0 if pair < 0 else int(self.arrays.pair_total[pair])

    def outcomes(self, state: int, action: int) -> Outcomes:
        """The learned distribution of (s, a); empty arrays if never observed."""
        arrays = self.arrays
        pair = find_pair(arrays, state, action)
        entries: list[int] = []
        entry = -1 if pair < 0 else int(arrays.pair_head[pair])
        while entry >= 0:
            entries.append(entry)
            entry = int(arrays.entry_sibling[entry])
        index = np.array(entries, dtype=np.int64)
        counts = arrays.entry_count[index]
        total = max(int(counts.sum()), 1)
        return Outcomes(
            next_states=arrays.entry_next_state[index],
            counts=counts,
            probabilities=counts / total,
            mean_rewards=arrays.entry_reward_sum[index] / np.maximum(counts, 1),
            termination=arrays.entry_terminal_count[index] / np.maximum(counts, 1),
        )

    def predecessors(self, state: int) -> list[tuple[int, int]]:
        """Every observed (s, a) that has led to ``state``, newest first."""
        arrays = self.arrays
        result: list[tuple[int, int]] = []
        entry = int(first_predecessor(arrays, state))
        while entry >= 0:
            key = int(arrays.pair_key[arrays.entry_pair[entry]])
            result.append(split_key(key, self.n_actions))
            entry = int(arrays.entry_pred_link[entry])
        return result

    def to_arrays(self, prefix: str = "model.") -> dict[str, np.ndarray]:
        """The arrays to save, trimmed to their used length (hash tables are rebuilt on load)."""
        arrays = self.arrays
        n_pairs, n_entries, n_targets = (int(value) for value in arrays.counters)
        saved = {f"{prefix}n_actions": np.array([arrays.n_actions], dtype=np.int64)}
        for names, used in ((_PAIR_FIELDS, n_pairs), (_ENTRY_FIELDS, n_entries)):
            saved.update({prefix + name: getattr(arrays, name)[:used] for name in names})
        saved.update({prefix + name: getattr(arrays, name)[:n_targets] for name in _TARGET_FIELDS})
        return saved

    @classmethod
    def from_arrays(cls, saved: dict[str, np.ndarray], prefix: str = "model.") -> MultinomialModel:
        """Rebuild a model from :meth:`to_arrays`; CorruptFileError if inconsistent (checked in
        O(n_entries): a model that loads can be planned with and observed without risk)."""
        try:
            n_actions = int(saved[f"{prefix}n_actions"][0])
            used = [
                np.asarray(saved[prefix + names[0]]).shape[0]
                for names in (_PAIR_FIELDS, _ENTRY_FIELDS, _TARGET_FIELDS)
            ]
            model = cls(n_actions, _capacity_for(max(*used, 1), _INITIAL_CAPACITY))
            model.arrays.counters[:] = used
            for names, n_used in zip(
                (_PAIR_FIELDS, _ENTRY_FIELDS, _TARGET_FIELDS), used, strict=True
            ):
                for name in names:
                    _copy_saved(getattr(model.arrays, name), saved[prefix + name], name, n_used)
            _check_links(model.arrays, used)
        except KeyError as error:
            raise CorruptFileError(f"missing model array {error.args[0]!r}") from None
        except (IndexError, ValueError, TypeError) as error:
            raise CorruptFileError(f"inconsistent multinomial model arrays ({error})") from None
        _rebuild_cache(model.arrays, used[0], used[1])
        hash_rebuild(model.arrays.pair_table, model.arrays.pair_key, used[0])
        hash_rebuild(model.arrays.target_table, model.arrays.target_state, used[2])
        return model


def _copy_saved(target: np.ndarray, values: np.ndarray, name: str, n_used: int) -> None:
    """Copy a saved array into the first ``n_used`` slots of ``target`` (same dtype, 1-D)."""
    values = np.asarray(values)
    if values.shape != (n_used,) or values.dtype != target.dtype:
        expected = f"{target.dtype} of shape ({n_used},)"
        raise ValueError(f"{name}: expected {expected}, got {values.dtype} {values.shape}")
    target[:n_used] = values


def _check(condition: bool | np.bool_, problem: str) -> None:
    if not condition:
        raise ValueError(problem)


def _check_links(arrays: MultinomialArrays, used: list[int]) -> None:
    """Raise ValueError unless the saved arrays form a model :func:`model_observe` could have built.

    Outcomes are appended, and each new outcome links to the previous head of its lists, so every
    link points to an *older* entry: requiring that rules out cycles without walking. Requiring
    also that every entry is linked to exactly once (from its pair's head or a sibling of the same
    pair) makes the outcome lists partition the entries, each list holding exactly the outcomes
    of its pair, so the counts of a pair's list add up to ``pair_total`` when the per-pair sums
    do. The same holds for the predecessor lists of the targets. O(n_pairs + n_entries).
    """
    n_pairs, n_entries, n_targets = used
    keys, total, head = (arrays.pair_key[:n_pairs], arrays.pair_total[:n_pairs],
                         arrays.pair_head[:n_pairs])  # fmt: skip
    count, terminal = arrays.entry_count[:n_entries], arrays.entry_terminal_count[:n_entries]
    owner, next_state = arrays.entry_pair[:n_entries], arrays.entry_next_state[:n_entries]
    sibling, pred_link = arrays.entry_sibling[:n_entries], arrays.entry_pred_link[:n_entries]
    state, target_head = arrays.target_state[:n_targets], arrays.target_head[:n_targets]
    _check(np.all(keys >= 0) and _distinct(keys), "pair keys not distinct >= 0")
    _check(np.all(state >= 0) and _distinct(state), "target states not distinct >= 0")
    _check(np.all(count >= 1), "empty outcome")
    _check(np.all((terminal >= 0) & (terminal <= count)), "terminal count outside [0, count]")
    _check(np.isfinite(arrays.entry_reward_sum[:n_entries]).all(), "non-finite reward sum")
    _check(np.all((owner >= 0) & (owner < n_pairs)), "outcome of an unknown pair")
    entries = np.arange(n_entries)
    for heads, links, name in ((head, sibling, "outcome"), (target_head, pred_link, "predecessor")):
        _check(np.all((heads >= 0) & (heads < n_entries)), f"{name} list head out of range")
        _check(np.all((links >= -1) & (links < entries)), f"{name} link out of range or cyclic")
        linked = np.concatenate([heads, links[links >= 0]])
        _check(
            np.array_equal(np.bincount(linked, minlength=n_entries), np.ones(n_entries, np.int64)),
            f"{name} lists do not cover every outcome once",
        )
    linked = sibling >= 0
    _check(
        np.array_equal(owner[head], np.arange(n_pairs))
        and np.array_equal(owner[sibling[linked]], owner[linked]),
        "outcome list mixes pairs",
    )
    linked = pred_link >= 0
    _check(
        np.array_equal(next_state[target_head], state)
        and np.array_equal(next_state[pred_link[linked]], next_state[linked]),
        "predecessor list mixes states",
    )
    sums = np.bincount(owner, weights=count, minlength=n_pairs)  # exact below 2⁵³
    _check(np.array_equal(sums, total), "outcome counts do not add up to pair_total")


def _distinct(values: np.ndarray) -> bool:
    """True if no value repeats (a sort: ``np.unique`` is ~50× slower on 10⁶ int64 in NumPy 2.4)."""
    return bool(np.all(np.diff(np.sort(values)) != 0))


def _rebuild_cache(arrays: MultinomialArrays, n_pairs: int, n_entries: int) -> None:
    """Recompute the most-probable cache (see :mod:`skidnav.models.multinomial_kernels`) of checked
    arrays, with the same operations as ``model_observe``."""
    owner, count = arrays.entry_pair[:n_entries], arrays.entry_count[:n_entries]
    largest = np.zeros(n_pairs, dtype=np.int64)
    np.maximum.at(largest, owner, count)
    is_max = count == largest[owner]
    arrays.pair_ties[:n_pairs] = np.bincount(owner[is_max], minlength=n_pairs)
    arrays.pair_best[owner[is_max]] = np.flatnonzero(is_max)
    best = arrays.pair_best[:n_pairs]
    best_count = arrays.entry_count[best]
    arrays.pair_best_next[:n_pairs] = arrays.entry_next_state[best]
    arrays.pair_best_reward[:n_pairs] = arrays.entry_reward_sum[best] / best_count
    arrays.pair_best_continuation[:n_pairs] = 1.0 - arrays.entry_terminal_count[best] / best_count
