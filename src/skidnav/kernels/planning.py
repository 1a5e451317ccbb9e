"""Compiled planning loops over the multinomial model (Sutton & Barto (2018) ch. 8).

Each loop applies the one update rule of :mod:`skidnav.kernels.tabular` (``update_toward``) to
targets computed by :func:`skidnav.kernels.multinomial.model_target`, and returns the number of
value updates it made. All draws are ``rng.random()``.
"""

from __future__ import annotations

import math

import numpy as np

from skidnav._jit import inline_jit, jit
from skidnav.kernels.multinomial import (
    EXPECTED,
    MOST_PROBABLE,
    SAMPLE,
    MultinomialArrays,
    entry_target,
    expected_target,
    find_pair,
    hash_find,
    model_observe,
    model_target,
    model_target_call,
    most_probable_entry,
    most_probable_target,
    pair_state_action,
    sample_entry,
    split_key,
    unsigned_index,
)
from skidnav.kernels.priority_queue import HeapArrays, heap_push, pop, push
from skidnav.kernels.tabular import td_target, update_toward


@jit
def dyna_planning(
    q: np.ndarray,
    model: MultinomialArrays,
    n_steps: int,
    alpha: float,
    gamma: float,
    mode: int,
    rng: np.random.Generator,
) -> int:
    """Dyna-Q planning (§8.2): ``n_steps`` times, replay a visited (s, a) pair drawn uniformly
    through the model and update ``q`` (C-contiguous) toward its target. Returns the number of
    updates.

    Same numbers as :func:`skidnav.kernels.multinomial.model_target` + ``update_toward`` per
    step, but the model's arrays are bound once, out of the loop (see ``entry_target``), and the
    updated value is addressed by the pair key in a (n_states · n_actions, 1) view of ``q`` (no
    integer division per update)."""
    n_pairs = model.counters[0]
    if n_pairs == 0:
        return 0
    cells = q.reshape(-1, 1)  # row s·n_actions + a is q[s, a]
    pair_key, head, total = model.pair_key, model.pair_head, model.pair_total
    counts, sums, terminals = model.entry_count, model.entry_reward_sum, model.entry_terminal_count
    next_states, siblings = model.entry_next_state, model.entry_sibling
    if mode != SAMPLE and mode != EXPECTED:  # most-probable (default): its own loop
        best, ties, best_next = model.pair_best, model.pair_ties, model.pair_best_next
        best_reward, best_continuation = model.pair_best_reward, model.pair_best_continuation
        for _ in range(n_steps):
            pair = int(rng.random() * n_pairs)
            uniform = rng.random()
            if ties[pair] == 1:  # the usual case: read the most-probable cache
                target = td_target(
                    q, best_reward[pair], best_next[pair], best_continuation[pair], gamma
                )
            else:
                entry = most_probable_entry(best, ties, head, counts, siblings, pair, uniform)
                target = entry_target(
                    q, counts[entry], sums[entry], terminals[entry], next_states[entry], gamma
                )
            update_toward(cells, pair_key[pair], 0, target, alpha)
        return n_steps
    for _ in range(n_steps):
        pair = int(rng.random() * n_pairs)
        uniform = rng.random()
        if mode == EXPECTED:
            target = expected_target(
                q, head, total, counts, sums, terminals, next_states, siblings, pair, gamma
            )
        else:
            entry = sample_entry(head, total, counts, siblings, pair, uniform)
            target = entry_target(
                q, counts[entry], sums[entry], terminals[entry], next_states[entry], gamma
            )
        update_toward(cells, pair_key[pair], 0, target, alpha)
    return n_steps


@jit
def dyna_plus_planning(
    q: np.ndarray,
    model: MultinomialArrays,
    visited_states: np.ndarray,
    n_visited: int,
    last_tried: np.ndarray,
    now: int,
    kappa: float,
    n_steps: int,
    alpha: float,
    gamma: float,
    mode: int,
    rng: np.random.Generator,
) -> int:
    """Dyna-Q+ planning (§8.3): draw a visited state uniformly, then any action uniformly. A pair
    never tried is modelled as "back to the same state, reward 0" (the book's footnote). The
    target gets the bonus ``kappa · sqrt(now − last_tried[s, a])`` (``last_tried`` int64
    (n_states, n_actions), in real steps). Returns the number of updates."""
    if n_visited == 0:
        return 0
    n_actions = q.shape[1]
    for _ in range(n_steps):
        state = visited_states[int(rng.random() * n_visited)]
        action = int(rng.random() * n_actions)
        pair = find_pair(model, state, action)
        if pair < 0:
            target = td_target(q, 0.0, state, 1.0, gamma)
        else:
            target = model_target(model, q, pair, mode, gamma, rng.random())
        target += kappa * math.sqrt(now - last_tried[state, action])
        update_toward(q, state, action, target, alpha)
    return n_steps


@inline_jit
def queue_pair(
    q: np.ndarray,
    model: MultinomialArrays,
    heap: HeapArrays,
    pair: int,
    theta: float,
    gamma: float,
    mode: int,
    uniform: float,
) -> None:
    """Queue pair slot ``pair`` (as item s·n_actions + a) with priority |target − q[s, a]| if that
    exceeds ``theta``. A ``SAMPLE`` model is asked for its expected target (no noisy priority);
    ``uniform`` ∈ [0, 1) breaks most-probable ties."""
    state, action = pair_state_action(model, pair)
    priority_mode = EXPECTED if mode == SAMPLE else mode
    priority = abs(model_target(model, q, pair, priority_mode, gamma, uniform) - q[state, action])
    if priority > theta:
        heap_push(heap, model.pair_key[pair], priority)


@jit
def prioritized_sweeping(
    q: np.ndarray,
    model: MultinomialArrays,
    heap: HeapArrays,
    n_steps: int,
    theta: float,
    alpha: float,
    gamma: float,
    mode: int,
    rng: np.random.Generator,
) -> int:
    """Prioritized sweeping (§8.4): up to ``n_steps`` times while the queue is not empty, pop the
    pair of highest priority, update it toward its model target, then queue each predecessor
    (s̄, ā) of s whose |TD error| exceeds ``theta`` (a most-probable model draws one
    ``rng.random()`` per predecessor, a sampling one is asked for its expected target). Returns
    the number of updates (popped pairs; the predecessors' priorities are not counted).

    Same numbers as ``heap_pop``, ``model_target``, ``update_toward`` and :func:`queue_pair` per
    predecessor, written out over arrays bound once: an inlined helper that binds an array it
    last uses in a branch (or binds the 21-array model) pays an atomic increment and decrement
    per array at every call, ~75 % of the time before (see :mod:`skidnav.kernels.multinomial`).
    The most-probable target of a pair whose most probable outcome is unique comes from the
    model's cache, as in :func:`dyna_planning` (its tie draw is still made, so that the stream
    is the same); the other modes' come from a compiled call. Pair slots and keys index
    through ``unsigned_index`` (no wrap of negative indices)."""
    priority, item, position, size = heap.priority, heap.item, heap.position, heap.size
    pair_table, pair_key, entry_pair = model.pair_table, model.pair_key, model.entry_pair
    target_table, target_state = model.target_table, model.target_state
    target_head, pred_link = model.target_head, model.entry_pred_link
    ties, best_next = model.pair_ties, model.pair_best_next
    best_reward, best_continuation = model.pair_best_reward, model.pair_best_continuation
    cells = q.reshape(-1, 1)  # row s·n_actions + a is q[s, a]
    n_actions = q.shape[1]
    updates = 0
    while updates < n_steps and size[0] > 0:
        key, _ = pop(priority, item, position, size)
        pair = hash_find(pair_table, pair_key, key)
        index = unsigned_index(pair)
        uniform = rng.random()
        if mode != MOST_PROBABLE:
            target = model_target_call(model, q, pair, mode, gamma, uniform)
        elif ties[index] == 1:  # a unique most probable outcome: read the model's cache
            target = td_target(
                q, best_reward[index], unsigned_index(best_next[index]), best_continuation[index],
                gamma,
            )  # fmt: skip
        else:
            target = most_probable_target(q, model, pair, gamma, uniform)
        update_toward(cells, unsigned_index(key), 0, target, alpha)
        updates += 1
        slot = hash_find(target_table, target_state, split_key(key, n_actions)[0])
        entry = target_head[slot] if slot >= 0 else -1
        while entry >= 0:  # queue the predecessors of the updated state
            pair = entry_pair[entry]
            index = unsigned_index(pair)
            if mode != MOST_PROBABLE:
                target = model_target_call(model, q, pair, EXPECTED, gamma, 0.0)
            else:
                uniform = rng.random()  # drawn for every predecessor, tied or not
                if ties[index] == 1:
                    target = td_target(
                        q, best_reward[index], unsigned_index(best_next[index]),
                        best_continuation[index], gamma,
                    )  # fmt: skip
                else:
                    target = most_probable_target(q, model, pair, gamma, uniform)
            key = pair_key[index]
            value = abs(target - cells[unsigned_index(key), 0])
            if value > theta:
                push(priority, item, position, size, key, value)
            entry = pred_link[entry]
    return updates


@jit
def sweep_step(
    q: np.ndarray,
    model: MultinomialArrays,
    heap: HeapArrays,
    state: int,
    action: int,
    reward: float,
    next_state: int,
    terminated: bool,
    n_steps: int,
    theta: float,
    alpha: float,
    gamma: float,
    mode: int,
    rng: np.random.Generator,
) -> int:
    """Prioritized sweeping's whole learning step from one real transition, in one compiled call
    (a call from Python pays ~20 µs for its arguments, the Generator most): count it in the model
    (the caller has reserved room for one more transition), queue its pair (a most-probable model
    draws one ``rng.random()`` for ties first), then :func:`prioritized_sweeping`. Returns the
    number of value updates."""
    pair = model_observe(model, state, action, reward, next_state, terminated)
    uniform = rng.random() if mode == MOST_PROBABLE else 0.0
    queue_pair(q, model, heap, pair, theta, gamma, mode, uniform)
    return prioritized_sweeping(q, model, heap, n_steps, theta, alpha, gamma, mode, rng)
