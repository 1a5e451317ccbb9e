"""Compiled kernels of the sparse multinomial transition model (:mod:`skidnav.models.multinomial`).

The model counts real transitions N(s, a, s′) and estimates

    p(s′ | s, a) = N(s, a, s′) / N(s, a),  r̄(s, a, s′) = mean reward,  β(s, a, s′) = share ended

(the thesis's multinomial model; Sutton & Barto (2018) §8.1 for its use in planning).

Planning targets from these arrays: :mod:`skidnav.models.multinomial_targets`.

Storage (:class:`MultinomialArrays`), memory proportional to the number of distinct observed
(s, a) pairs and (s, a, s′) outcomes, never to S²·A:

* **pairs** — one slot per observed (s, a): ``pair_key`` = s · n_actions + a, ``pair_total`` =
  N(s, a), ``pair_head`` = first outcome of the pair (−1 none). Slots are numbered in order of first
  visit, so ``pair_key[:n_pairs]`` is the list of visited pairs. ``pair_table`` is an
  open-addressing hash table (linear probing, size a power of two, load ≤ 1/2) mapping a key to its
  slot.
* **most-probable cache**, per pair, kept up to date by :func:`model_observe` (derived, not saved):
  ``pair_best`` = an outcome with the largest count, ``pair_ties`` = how many outcomes share that
  count, and of that outcome ``pair_best_next`` = s′, ``pair_best_reward`` = r̄ and
  ``pair_best_continuation`` = 1 − β, computed with the same operations as :func:`entry_target`.
  When the most probable outcome is unique (always on a deterministic MDP), the thesis's planning
  reads these four numbers instead of walking the outcome list and dividing (~1.5× more planning
  updates per second); with ties it walks the list as before.
* **outcomes** — one entry per observed (s, a, s′): ``entry_next_state``, ``entry_count``,
  ``entry_reward_sum``, ``entry_terminal_count``, ``entry_pair`` (its pair slot),
  ``entry_sibling`` (next outcome of the same pair, −1 ends) and ``entry_pred_link`` (next outcome
  leading to the same s′, −1 ends).
* **targets** — one slot per state seen as s′: ``target_state``, ``target_head`` (first outcome
  leading to it) and the hash ``target_table``. Following ``target_head`` then ``entry_pred_link``
  lists the predecessors (s, a) of a state (for prioritized sweeping, §8.4).

``counters`` int64 (3,) holds ``[n_pairs, n_entries, n_targets]``. Kernels never grow arrays: the
owner reserves room first (:meth:`skidnav.models.multinomial.MultinomialModel.reserve`); one
observation needs at most one free slot of each kind.

Speed: the helpers marked inline are compiled into the planning loops, and each has **one
exit** (no early ``return``; each array it takes is read last on the one path to its end). numba
then prunes the reference counting of the arrays bound to the helper's parameters, the model's
21 included; with several exits it cannot, and every call paid an atomic increment and decrement
per array — most of the time of the prioritized-sweeping and kinematic planning loops. Slots
and entries read from the arrays are non-negative where they index, and index through
:func:`unsigned_index`: numba wraps a signed index (as for ``a[-1]``) at every access, not an
unsigned one.

"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from skidnav._jit import inline_jit, jit


@inline_jit
def unsigned_index(index: int) -> int:
    """``index`` (non-negative) as ``np.uint64``, for indexing: numba wraps a signed index (as for
    ``a[-1]``) at every access, not an unsigned one. Same value compiled or not; typed ``int``
    for the helpers of :mod:`skidnav.sim.q_values` that take it."""
    return np.uint64(index)  # type: ignore[return-value]


class MultinomialArrays(NamedTuple):
    """The model's arrays (see the module docstring); every array is 1-D."""

    n_actions: int
    counters: np.ndarray
    pair_table: np.ndarray
    pair_key: np.ndarray
    pair_total: np.ndarray
    pair_head: np.ndarray
    pair_best: np.ndarray
    pair_ties: np.ndarray
    pair_best_next: np.ndarray
    pair_best_reward: np.ndarray
    pair_best_continuation: np.ndarray
    entry_next_state: np.ndarray
    entry_count: np.ndarray
    entry_reward_sum: np.ndarray
    entry_terminal_count: np.ndarray
    entry_pair: np.ndarray
    entry_sibling: np.ndarray
    entry_pred_link: np.ndarray
    target_table: np.ndarray
    target_state: np.ndarray
    target_head: np.ndarray


@inline_jit
def hash_slot(key: int, mask: int) -> int:
    """Home slot of a non-negative integer key in a table of ``mask + 1`` slots (no overflow: the
    same numbers interpreted and compiled)."""
    mixed = (key ^ (key >> 17)) & 0x7FFFFFFF
    return (mixed * 73244475 + (key >> 31)) & mask


@inline_jit
def hash_find(table: np.ndarray, keys: np.ndarray, key: int) -> int:
    """Index ``i`` with ``keys[i] == key`` registered in ``table``, or −1 (an empty slot holds
    −1). One exit, as every hot inlined helper here (see the module docstring)."""
    mask = table.shape[0] - 1
    slot = hash_slot(key, mask)
    index = table[unsigned_index(slot)]
    while index >= 0 and keys[unsigned_index(index)] != key:
        slot = (slot + 1) & mask
        index = table[unsigned_index(slot)]
    return index


@jit
def hash_insert(table: np.ndarray, keys: np.ndarray, index: int) -> None:
    """Register ``index`` (whose key ``keys[index]`` is not yet in ``table``)."""
    mask = table.shape[0] - 1
    slot = hash_slot(keys[index], mask)
    while table[slot] >= 0:
        slot = (slot + 1) & mask
    table[slot] = index


@jit
def hash_rebuild(table: np.ndarray, keys: np.ndarray, count: int) -> None:
    """Fill an empty ``table`` (all −1) with indices ``0 .. count − 1``."""
    for index in range(count):
        hash_insert(table, keys, index)


@inline_jit
def find_pair(model: MultinomialArrays, state: int, action: int) -> int:
    """Pair slot of (state, action), or −1 if never observed."""
    return hash_find(model.pair_table, model.pair_key, state * model.n_actions + action)


@jit
def _new_pair(model: MultinomialArrays, key: int) -> int:
    pair = model.counters[0]
    model.counters[0] = pair + 1
    model.pair_key[pair] = key
    model.pair_total[pair] = 0
    model.pair_head[pair] = -1
    model.pair_best[pair] = -1
    model.pair_ties[pair] = 0
    hash_insert(model.pair_table, model.pair_key, pair)
    return pair


@jit
def _target_of(model: MultinomialArrays, next_state: int) -> int:
    target = hash_find(model.target_table, model.target_state, next_state)
    if target < 0:
        target = model.counters[2]
        model.counters[2] = target + 1
        model.target_state[target] = next_state
        model.target_head[target] = -1
        hash_insert(model.target_table, model.target_state, target)
    return target


@jit
def _new_entry(model: MultinomialArrays, pair: int, next_state: int) -> int:
    entry = model.counters[1]
    model.counters[1] = entry + 1
    model.entry_next_state[entry] = next_state
    model.entry_count[entry] = 0
    model.entry_reward_sum[entry] = 0.0
    model.entry_terminal_count[entry] = 0
    model.entry_pair[entry] = pair
    model.entry_sibling[entry] = model.pair_head[pair]
    model.pair_head[pair] = entry
    target = _target_of(model, next_state)
    model.entry_pred_link[entry] = model.target_head[target]
    model.target_head[target] = entry
    return entry


@inline_jit
def observe_pair(
    model: MultinomialArrays,
    state: int,
    action: int,
    reward: float,
    next_state: int,
    terminated: bool,
) -> int:
    """:func:`model_observe` inlined, for a learning step that binds the model once (a compiled
    call with the model's 20 arrays pays an atomic increment and decrement of each, ~0.25 µs).
    One exit; the model is used last on the one path (see the module docstring)."""
    key = state * model.n_actions + action
    pair = hash_find(model.pair_table, model.pair_key, key)
    if pair < 0:
        pair = _new_pair(model, key)
    model.pair_total[pair] += 1
    entry = model.pair_head[pair]
    while entry >= 0 and model.entry_next_state[entry] != next_state:
        entry = model.entry_sibling[entry]
    if entry < 0:
        entry = _new_entry(model, pair, next_state)
    model.entry_count[entry] += 1
    model.entry_reward_sum[entry] += reward
    if terminated:
        model.entry_terminal_count[entry] += 1
    _note_most_probable(model, pair, entry)
    return pair


@jit
def model_observe(
    model: MultinomialArrays,
    state: int,
    action: int,
    reward: float,
    next_state: int,
    terminated: bool,
) -> int:
    """Count one real transition; returns its pair slot. Room must have been reserved."""
    return observe_pair(model, state, action, reward, next_state, terminated)


@inline_jit
def _note_most_probable(model: MultinomialArrays, pair: int, entry: int) -> None:
    """Update the most-probable cache of ``pair`` after one more count of ``entry``: an outcome
    that was the (possibly tied) maximum, or that passes it, is now the only maximum; one that
    reaches it joins the tie."""
    best = model.pair_best[pair]
    count = model.entry_count[entry]
    if best < 0 or best == entry or count > model.entry_count[best]:
        model.pair_best[pair] = entry
        model.pair_ties[pair] = 1
        best = entry
    elif count == model.entry_count[best]:
        model.pair_ties[pair] += 1
    best_count = model.entry_count[best]
    model.pair_best_next[pair] = model.entry_next_state[best]
    model.pair_best_reward[pair] = model.entry_reward_sum[best] / best_count
    model.pair_best_continuation[pair] = 1.0 - model.entry_terminal_count[best] / best_count


@inline_jit
def split_key(key: int, n_actions: int) -> tuple[int, int]:
    """(state, action) of a non-negative pair key ``state · n_actions + action`` (one integer
    division instead of ``//`` and ``%``: ~5 ns less per planning update)."""
    state = key // n_actions
    return state, key - state * n_actions


@inline_jit
def pair_state_action(model: MultinomialArrays, pair: int) -> tuple[int, int]:
    """(state, action) of a pair slot."""
    return split_key(model.pair_key[pair], model.n_actions)


@inline_jit
def first_predecessor(model: MultinomialArrays, state: int) -> int:
    """First outcome entry leading to ``state`` (−1 if none); iterate with ``entry_pred_link`` and
    read the predecessor pair from ``entry_pair``."""
    target = hash_find(model.target_table, model.target_state, state)
    entry = -1
    if target >= 0:
        entry = model.target_head[target]
    return entry
