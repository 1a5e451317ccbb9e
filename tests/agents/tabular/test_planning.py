"""The planning loops of skidnav.agents.tabular.planning (Dyna-Q, prioritized sweeping) against
their
definitions written from the model's and the queue's parts."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from skidnav.agents.tabular.planning import dyna_planning, prioritized_sweeping
from skidnav.agents.tabular.priority_queue import heap_pop, heap_push, make_heap
from skidnav.models.multinomial import MultinomialModel
from skidnav.models.multinomial_kernels import find_pair
from skidnav.models.multinomial_targets import (
    EXPECTED,
    MOST_PROBABLE,
    SAMPLE,
    expected_model_target,
    model_target,
    model_target_call,
    most_probable_target,
)

N_STATES, N_ACTIONS = 30, 3


def stochastic_model(seed: int) -> MultinomialModel:
    """A model with several outcomes per pair, count ties, rewards and some terminations."""
    rng = np.random.default_rng(seed)
    model = MultinomialModel(N_ACTIONS, capacity=4)
    for _ in range(600):
        s, a = int(rng.integers(N_STATES)), int(rng.integers(N_ACTIONS))
        s2 = (s + a + int(rng.integers(3))) % N_STATES
        model.observe(s, a, float(rng.normal()), s2, bool(s2 == 0 and rng.random() < 0.5))
    return model


def reference_planning(
    q: np.ndarray, model: MultinomialModel, n_steps: int, mode: int, rng: np.random.Generator
) -> None:
    """The planning step written from its parts: draw a pair, ask ``model_target``, update."""
    arrays = model.arrays
    n_pairs = int(arrays.counters[0])
    for _ in range(n_steps):
        pair = int(rng.random() * n_pairs)
        state, action = divmod(int(arrays.pair_key[pair]), N_ACTIONS)
        target = model_target(arrays, q, pair, mode, 0.9, rng.random())
        q[state, action] += 0.2 * (target - q[state, action])


@pytest.mark.parametrize("mode", [MOST_PROBABLE, SAMPLE, EXPECTED])
def test_dyna_planning_equals_model_target_updates(mode: int) -> None:
    model = stochastic_model(seed=mode)
    start = np.random.default_rng(5).normal(size=(N_STATES, N_ACTIONS))
    q_fast, q_ref = start.copy(), start.copy()
    rng_fast, rng_ref = np.random.default_rng(9), np.random.default_rng(9)
    assert dyna_planning(q_fast, model.arrays, 3000, 0.2, 0.9, mode, rng_fast) == 3000
    reference_planning(q_ref, model, 3000, mode, rng_ref)
    np.testing.assert_array_equal(q_fast, q_ref)
    assert not np.array_equal(q_fast, start)
    assert rng_fast.random() == rng_ref.random()  # the same number of draws


def test_dyna_planning_without_pairs_does_nothing() -> None:
    q = np.ones((4, 2))
    rng = np.random.default_rng(0)
    assert dyna_planning(q, MultinomialModel(2).arrays, 10, 0.5, 0.9, MOST_PROBABLE, rng) == 0
    assert rng.random() == np.random.default_rng(0).random()
    np.testing.assert_array_equal(q, 1.0)


@pytest.mark.parametrize("mode", [MOST_PROBABLE, SAMPLE, EXPECTED])
def test_the_compiled_call_and_the_inlined_target_equal_model_target(mode: int) -> None:
    model = stochastic_model(seed=3)
    q = np.random.default_rng(2).normal(size=(N_STATES, N_ACTIONS))
    arrays = model.arrays
    for pair in range(int(arrays.counters[0])):
        for uniform in (0.0, 0.4, 0.99):
            expected = model_target(arrays, q, pair, mode, 0.9, uniform)
            assert model_target_call(arrays, q, pair, mode, 0.9, uniform) == expected
            if mode == MOST_PROBABLE:
                assert most_probable_target(q, arrays, pair, 0.9, uniform) == expected
            if mode == EXPECTED:
                assert expected_model_target(q, arrays, pair, 0.9) == expected


def tie_expectation(arrays: Any, q: np.ndarray, pair: int) -> float:
    """The most-probable target of ``pair`` averaged over its tie draw: the mean of
    ``model_target`` over the uniforms that pick each tied outcome, in list order."""
    n_ties = int(arrays.pair_ties[pair])
    total = 0.0
    for index in range(n_ties):
        total += model_target(arrays, q, pair, MOST_PROBABLE, 0.9, (index + 0.5) / n_ties)
    return total / n_ties


def reference_sweeping(
    q: np.ndarray, model: MultinomialModel, queue: Any, n_steps: int, mode: int, rng: Any
) -> int:
    """Prioritized sweeping from its parts: pop, ``model_target``, update, then each predecessor
    (newest first) queued at |target − q| > θ, its target expected for a sampling model; a
    most-probable model's targets are averaged over its ties (no draw)."""
    arrays, updates = model.arrays, 0
    while updates < n_steps and queue.size[0] > 0:
        key, _ = heap_pop(queue)
        state, action = divmod(key, N_ACTIONS)
        pair = find_pair(arrays, state, action)
        if mode == MOST_PROBABLE:
            target = tie_expectation(arrays, q, pair)
        else:
            target = model_target(arrays, q, pair, mode, 0.9, rng.random())
        q[state, action] += 0.5 * (target - q[state, action])
        updates += 1
        for before, taken in model.predecessors(state):
            pair = find_pair(arrays, before, taken)
            if mode == MOST_PROBABLE:
                target = tie_expectation(arrays, q, pair)
            else:
                target = model_target(arrays, q, pair, EXPECTED, 0.9, 0.0)
            priority = abs(target - q[before, taken])
            if priority > 1e-3:
                heap_push(queue, before * N_ACTIONS + taken, priority)
    return updates


@pytest.mark.parametrize("mode", [MOST_PROBABLE, SAMPLE, EXPECTED])
def test_prioritized_sweeping_equals_its_definition(mode: int) -> None:
    model = stochastic_model(seed=4 + mode)
    start = np.random.default_rng(6).normal(size=(N_STATES, N_ACTIONS))
    tables, queues, generators = [start.copy(), start.copy()], [], []
    for _ in range(2):
        queue = make_heap(N_STATES * N_ACTIONS)
        for key in model.visited_pairs()[::7].tolist():
            heap_push(queue, int(key), 1.0 + key % 5)  # equal priorities: order by heap layout
        queues.append(queue)
        generators.append(np.random.default_rng(8))
    fast = prioritized_sweeping(
        tables[0], model.arrays, queues[0], 400, 1e-3, 0.5, 0.9, mode, generators[0]
    )
    assert fast == reference_sweeping(tables[1], model, queues[1], 400, mode, generators[1])
    assert fast == 400
    np.testing.assert_array_equal(tables[0], tables[1])
    assert not np.array_equal(tables[0], start)
    size = int(queues[0].size[0])
    assert size == int(queues[1].size[0]) > 0
    for name in ("item", "priority"):
        np.testing.assert_array_equal(
            getattr(queues[0], name)[:size], getattr(queues[1], name)[:size]
        )
    assert generators[0].random() == generators[1].random()  # the same number of draws


def test_most_probable_sweeping_draws_nothing_and_its_queue_settles() -> None:
    """Tied pairs get their expected target, so the queue empties (a redrawn tie kept it full)
    at a fixed point of the tie-averaged targets, and the generator is never touched."""
    model = stochastic_model(seed=11)
    arrays = model.arrays
    n_pairs = int(arrays.counters[0])
    assert (arrays.pair_ties[:n_pairs] > 1).any()  # the case at stake
    q, queue, rng = (
        np.zeros((N_STATES, N_ACTIONS)),
        make_heap(N_STATES * N_ACTIONS),
        np.random.default_rng(3),
    )
    for key in model.visited_pairs().tolist():
        heap_push(queue, int(key), 1.0)
    updates = prioritized_sweeping(q, arrays, queue, 10**6, 1e-9, 0.5, 0.9, MOST_PROBABLE, rng)
    assert 0 < updates < 10**6
    assert queue.size[0] == 0
    assert rng.random() == np.random.default_rng(3).random()
    for pair in range(n_pairs):
        state, action = divmod(int(arrays.pair_key[pair]), N_ACTIONS)
        assert abs(tie_expectation(arrays, q, pair) - q[state, action]) < 1e-6
