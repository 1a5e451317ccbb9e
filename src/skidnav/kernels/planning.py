"""Compiled planning loops over the multinomial model (Sutton & Barto (2018) ch. 8).

Each loop applies the one update rule of :mod:`skidnav.kernels.tabular` (``update_toward``) to
targets computed by :func:`skidnav.kernels.multinomial.model_target`, and returns the number of
value updates it made. All draws are ``rng.random()``.
"""

from __future__ import annotations

import math

import numpy as np

from skidnav._jit import jit
from skidnav.kernels.multinomial import (
    EXPECTED,
    MOST_PROBABLE,
    SAMPLE,
    MultinomialArrays,
    entry_target,
    expected_target,
    find_pair,
    first_predecessor,
    model_observe,
    model_target,
    most_probable_entry,
    pair_state_action,
    sample_entry,
    split_key,
)
from skidnav.kernels.priority_queue import HeapArrays, heap_pop, heap_push
from skidnav.kernels.tabular import inline_jit, td_target, update_toward


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
    (s̄, ā) of s whose |TD error| exceeds ``theta``. Returns the number of updates."""
    updates = 0
    n_actions = q.shape[1]
    while updates < n_steps and heap.size[0] > 0:
        key, _ = heap_pop(heap)
        state = key // n_actions
        pair = find_pair(model, state, key % n_actions)
        target = model_target(model, q, pair, mode, gamma, rng.random())
        update_toward(q, state, key % n_actions, target, alpha)
        updates += 1
        _queue_predecessors(q, model, heap, state, theta, gamma, mode, rng)
    return updates


@inline_jit
def _queue_predecessors(
    q: np.ndarray,
    model: MultinomialArrays,
    heap: HeapArrays,
    state: int,
    theta: float,
    gamma: float,
    mode: int,
    rng: np.random.Generator,
) -> None:
    """:func:`queue_pair` for every predecessor pair of ``state`` (a most-probable model draws
    one ``rng.random()`` per predecessor). Same numbers as calling ``queue_pair``, but the model's
    arrays are bound once (see :func:`dyna_planning`) and a unique most-probable outcome is read
    from the cache: binding the 21-array model per predecessor cost more than the update."""
    pair_key, entry_pair, pred_link = model.pair_key, model.entry_pair, model.entry_pred_link
    ties, best_next = model.pair_ties, model.pair_best_next
    best_reward, best_continuation = model.pair_best_reward, model.pair_best_continuation
    n_actions = q.shape[1]
    entry = first_predecessor(model, state)
    while entry >= 0:
        pair = entry_pair[entry]
        if mode != MOST_PROBABLE:
            queue_pair(q, model, heap, pair, theta, gamma, mode, 0.0)
        else:
            uniform = rng.random()
            if ties[pair] == 1:
                target = td_target(
                    q, best_reward[pair], best_next[pair], best_continuation[pair], gamma
                )
            else:
                target = model_target(model, q, pair, MOST_PROBABLE, gamma, uniform)
            key = pair_key[pair]
            pred_state, pred_action = split_key(key, n_actions)
            priority = abs(target - q[pred_state, pred_action])
            if priority > theta:
                heap_push(heap, key, priority)
        entry = pred_link[entry]


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
