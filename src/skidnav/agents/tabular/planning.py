"""Compiled planning loops over the multinomial model (Sutton & Barto (2018) ch. 8).

Each loop applies the one update rule of :mod:`skidnav.sim.q_values` (``update_toward``) to targets
computed by :func:`skidnav.models.multinomial_targets.model_target`, and returns the number of value
updates it made. All draws are ``rng.random()``. Prioritized sweeping of a most-probable model
averages a tie over its tied outcomes instead of drawing it (:func:`sweep`).
"""

from __future__ import annotations

import math

import numpy as np

from skidnav._jit import inline_jit, jit
from skidnav.agents.tabular.priority_queue import HeapArrays, heap_pop, heap_push, pop, push
from skidnav.models.multinomial_kernels import (
    MultinomialArrays,
    find_pair,
    first_predecessor,
    hash_find,
    model_observe,
    observe_pair,
    pair_state_action,
    split_key,
    unsigned_index,
)
from skidnav.models.multinomial_targets import (
    EXPECTED,
    MOST_PROBABLE,
    SAMPLE,
    entry_target,
    expected_target,
    model_target,
    most_probable_entry,
    sample_entry,
    tied_mean_target,
)
from skidnav.sim.q_values import td_target, update_toward


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

    Same numbers as :func:`skidnav.models.multinomial_targets.model_target` + ``update_toward`` per
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
def sweep(
    q: np.ndarray,
    model: MultinomialArrays,
    heap: HeapArrays,
    first: int,
    n_steps: int,
    theta: float,
    alpha: float,
    gamma: float,
) -> int:
    """Prioritized sweeping (§8.4) of a most-probable model, inlined: if pair slot ``first`` ≥ 0,
    queue it (as item s·n_actions + a) with priority |target − q[s, a]| if that exceeds
    ``theta``; then up to ``n_steps`` times while the queue is not empty, pop the pair of highest
    priority, update it toward its target, and queue each predecessor (s̄, ā) of s whose |TD
    error| exceeds ``theta``. Returns the number of updates (popped pairs).

    A target is the most probable outcome's, and for a pair whose most probable outcome is tied
    the mean over the tied outcomes (:func:`tied_mean_target`): the expectation over the uniform
    tie draw, as §8.4 uses expected updates in a stochastic environment. Nothing is drawn, and a
    tied pair's priority falls below θ like any other's (with a redrawn tie it did not, and the
    queue cycled over the tied pairs while the others waited).

    One loop body computes every target, a queued pair's for its update and a predecessor's for its
    priority, over arrays bound once and with one exit: an inlined helper that binds an array it
    last uses in a branch (or binds the 21-array model) pays an atomic increment and decrement per
    array at every call (see :mod:`skidnav.models.multinomial_kernels`). On the obstacles arena a
    quarter of the predecessors are tied; their target as a compiled call on the model cost ~0.3 µs
    each, half of the sweep's time. Pair slots and keys index through ``unsigned_index`` (no wrap of
    negative indices)."""
    priority, item, position, size = heap.priority, heap.item, heap.position, heap.size
    pair_table, pair_key, entry_pair = model.pair_table, model.pair_key, model.entry_pair
    target_table, target_state = model.target_table, model.target_state
    target_head, pred_link = model.target_head, model.entry_pred_link
    ties, best_next, pair_best = model.pair_ties, model.pair_best_next, model.pair_best
    best_reward, best_continuation = model.pair_best_reward, model.pair_best_continuation
    pair_head, entry_count, entry_sibling = model.pair_head, model.entry_count, model.entry_sibling
    reward_sum, terminal_count = model.entry_reward_sum, model.entry_terminal_count
    next_state = model.entry_next_state
    cells = q.reshape(-1, 1)  # row s·n_actions + a is q[s, a]
    n_actions = q.shape[1]
    # `pair` is the slot whose target comes next: a queued pair just popped (`popped`), to update,
    # or the real pair / a predecessor (the outcome `entry` of the pair), to queue by priority
    entry, updates, key = -1, 0, 0
    pair, popped = first, False
    if pair < 0 and n_steps > 0 and size[0] > 0:
        key, _ = pop(priority, item, position, size)
        pair, popped = hash_find(pair_table, pair_key, key), True
    while pair >= 0:
        index = unsigned_index(pair)
        n_ties = ties[index]
        if n_ties == 1:  # a unique most probable outcome: the model's cache
            target = td_target(
                q, best_reward[index], unsigned_index(best_next[index]),
                best_continuation[index], gamma,
            )  # fmt: skip
        else:
            target = tied_mean_target(
                q, pair_head, entry_count, reward_sum, terminal_count, next_state,
                entry_sibling, index, entry_count[unsigned_index(pair_best[index])], n_ties,
                gamma,
            )  # fmt: skip
        if popped:
            update_toward(cells, unsigned_index(key), 0, target, alpha)
            updates += 1
            slot = hash_find(target_table, target_state, split_key(key, n_actions)[0])
            entry = target_head[unsigned_index(slot)] if slot >= 0 else -1
        else:
            key = pair_key[index]
            value = abs(target - cells[unsigned_index(key), 0])
            if value > theta:
                push(priority, item, position, size, key, value)
            entry = pred_link[unsigned_index(entry)] if entry >= 0 else -1
        if entry >= 0:  # the next predecessor of the last updated state
            pair, popped = entry_pair[unsigned_index(entry)], False
        elif updates < n_steps and size[0] > 0:  # pop the next pair to update
            key, _ = pop(priority, item, position, size)
            pair, popped = hash_find(pair_table, pair_key, key), True
        else:
            pair = -1
    return updates


@jit
def sweep_sampled(
    q: np.ndarray,
    model: MultinomialArrays,
    heap: HeapArrays,
    first: int,
    n_steps: int,
    theta: float,
    alpha: float,
    gamma: float,
    mode: int,
    rng: np.random.Generator,
) -> int:
    """:func:`sweep` of a ``SAMPLE`` or ``EXPECTED`` model: every priority from the expected
    target (no sampling noise in the queue order), each update from ``mode``'s target with one
    ``rng.random()`` drawn for it (unused by ``EXPECTED``)."""
    pair, entry, updates = first, -1, 0
    more = True
    while more:
        if pair >= 0:
            state, action = pair_state_action(model, pair)
            value = abs(model_target(model, q, pair, EXPECTED, gamma, 0.0) - q[state, action])
            if value > theta:
                heap_push(heap, model.pair_key[pair], value)
        entry = model.entry_pred_link[entry] if entry >= 0 else -1
        while entry < 0 and updates < n_steps and heap.size[0] > 0:
            key, _ = heap_pop(heap)
            state, action = split_key(key, model.n_actions)
            pair = find_pair(model, state, action)
            target = model_target(model, q, pair, mode, gamma, rng.random())
            update_toward(q, state, action, target, alpha)
            updates += 1
            entry = first_predecessor(model, state)
        more = entry >= 0
        pair = model.entry_pair[entry] if more else -1
    return updates


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
    """Prioritized sweeping's planning (§8.4) on the queue as it is (:func:`sweep`,
    :func:`sweep_sampled`). Returns the number of value updates."""
    if mode == MOST_PROBABLE:
        updates = sweep(q, model, heap, -1, n_steps, theta, alpha, gamma)
    else:
        updates = sweep_sampled(q, model, heap, -1, n_steps, theta, alpha, gamma, mode, rng)
    return updates


@inline_jit
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
) -> int:
    """Prioritized sweeping's whole learning step from one real transition, for a most-probable
    model, inlined into the agent's compiled learning step: count it in the model (the caller has
    reserved room for one more transition), then :func:`sweep` from its pair (queued first).
    Inlined, with every parameter used on its one path: a compiled call with the model pays
    ~0.25–0.45 µs of reference counting, ~1.3 µs of the step before. Returns the number of value
    updates."""
    pair = observe_pair(model, state, action, reward, next_state, terminated)
    return sweep(q, model, heap, pair, n_steps, theta, alpha, gamma)


@jit
def sampled_sweep_step(
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
    """:func:`sweep_step` for a ``SAMPLE`` or ``EXPECTED`` model (:func:`sweep_sampled`)."""
    pair = model_observe(model, state, action, reward, next_state, terminated)
    return sweep_sampled(q, model, heap, pair, n_steps, theta, alpha, gamma, mode, rng)
