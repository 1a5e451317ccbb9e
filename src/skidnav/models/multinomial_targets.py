"""Compiled planning targets of the sparse multinomial transition model
(:mod:`skidnav.models.multinomial_kernels` holds its arrays and how it counts).

Planning modes (``mode`` argument): :data:`MOST_PROBABLE` (thesis default: the outcome with the
largest count, ties broken uniformly), :data:`SAMPLE` (s′ drawn from p(·|s, a)) and
:data:`EXPECTED` (the expectation over all outcomes). Prioritized sweeping takes the expectation
over the tie draw instead of drawing it (:func:`tied_mean_target`). In every mode the bootstrap
is weighted by the continuation 1 − β(s, a, s′), exact for deterministic termination.

Randomness: helpers take a uniform draw ``uniform`` ∈ [0, 1) from the caller instead of the
Generator. (Passing a Generator into a compiled helper that draws from it costs ~0.3 µs a call in
numba 0.68; the planning loops therefore draw in their own body and pass the number down.)
"""

from __future__ import annotations

import numpy as np

from skidnav._jit import inline_jit, jit
from skidnav.models.multinomial_kernels import MultinomialArrays, unsigned_index
from skidnav.sim.q_values import td_target

MOST_PROBABLE = 0
SAMPLE = 1
EXPECTED = 2
PLANNING_MODES = {"most-probable": MOST_PROBABLE, "sample": SAMPLE, "expected": EXPECTED}
"""Planning-mode names (as in configs) → the integer codes the kernels take."""


@inline_jit
def entry_target(
    q: np.ndarray,
    count: int,
    reward_sum: float,
    terminal_count: int,
    next_state: int,
    gamma: float,
) -> float:
    """TD target of one outcome from its statistics: ``r̄ + γ · (1 − β) · max_a q[s′, a]`` with
    ``r̄ = reward_sum / count`` and ``β = terminal_count / count``. Takes scalars, not the model's
    arrays: an array bound to an inlined helper's parameter is reference-counted at every call
    unless numba prunes it, which in the planning loops cost more than the update itself."""
    reward = reward_sum / count
    continuation = 1.0 - terminal_count / count
    return td_target(q, reward, next_state, continuation, gamma)


@inline_jit
def _nth_with_count(
    pair_head: np.ndarray,
    entry_count: np.ndarray,
    entry_sibling: np.ndarray,
    pair: int,
    count: int,
    index: int,
) -> int:
    """The ``index``-th (0-based) outcome of ``pair`` whose count is ``count`` (−1 if none)."""
    entry = pair_head[unsigned_index(pair)]
    while entry >= 0 and (entry_count[unsigned_index(entry)] != count or index > 0):
        if entry_count[unsigned_index(entry)] == count:
            index -= 1
        entry = entry_sibling[unsigned_index(entry)]
    return entry


@inline_jit
def most_probable_entry(
    pair_best: np.ndarray,
    pair_ties: np.ndarray,
    pair_head: np.ndarray,
    entry_count: np.ndarray,
    entry_sibling: np.ndarray,
    pair: int,
    uniform: float,
) -> int:
    """The outcome of ``pair`` with the largest count; ties broken uniformly by ``uniform``, a
    draw in [0, 1) made by the caller (the ``int(uniform · n_ties)``-th tied outcome in list
    order)."""
    # One path (no shortcut for a unique maximum, whose index is 0): see the module docstring.
    index = int(uniform * pair_ties[unsigned_index(pair)])
    count = entry_count[unsigned_index(pair_best[unsigned_index(pair)])]
    return _nth_with_count(pair_head, entry_count, entry_sibling, pair, count, index)


@inline_jit
def most_probable_target(
    q: np.ndarray,
    model: MultinomialArrays,
    pair: int,
    gamma: float,
    uniform: float,
) -> float:
    """TD target of the most probable outcome of ``pair`` (ties broken by ``uniform``), from the
    chosen outcome's statistics (the same numbers as the cache). One path, every use of the
    model's arrays on it, so that the model bound to it costs no reference counting in the
    planning loops (see the module docstring)."""
    entry = most_probable_entry(
        model.pair_best, model.pair_ties, model.pair_head, model.entry_count, model.entry_sibling,
        pair, uniform,
    )  # fmt: skip
    at = unsigned_index(entry)
    return entry_target(
        q, model.entry_count[at], model.entry_reward_sum[at], model.entry_terminal_count[at],
        unsigned_index(model.entry_next_state[at]), gamma,
    )  # fmt: skip


@inline_jit
def tied_mean_target(
    q: np.ndarray,
    pair_head: np.ndarray,
    entry_count: np.ndarray,
    entry_reward_sum: np.ndarray,
    entry_terminal_count: np.ndarray,
    entry_next_state: np.ndarray,
    entry_sibling: np.ndarray,
    pair: int,
    best_count: int,
    n_ties: int,
    gamma: float,
) -> float:
    """Mean of the outcome targets over the ``n_ties`` outcomes of ``pair`` whose count is the
    largest, ``best_count``: the expectation of the most-probable target over its uniform tie
    draw (summed in the order of the pair's outcome list, then divided by ``n_ties``)."""
    value = 0.0
    entry = pair_head[unsigned_index(pair)]
    while entry >= 0:
        at = unsigned_index(entry)
        if entry_count[at] == best_count:
            value += entry_target(
                q, best_count, entry_reward_sum[at], entry_terminal_count[at],
                unsigned_index(entry_next_state[at]), gamma,
            )  # fmt: skip
        entry = entry_sibling[at]
    return value / n_ties


@inline_jit
def sample_entry(
    pair_head: np.ndarray,
    pair_total: np.ndarray,
    entry_count: np.ndarray,
    entry_sibling: np.ndarray,
    pair: int,
    uniform: float,
) -> int:
    """An outcome of ``pair`` drawn with probability N(s, a, s′)/N(s, a) by ``uniform`` ∈ [0, 1)."""
    threshold = int(uniform * pair_total[pair]) - entry_count[pair_head[pair]]
    entry = pair_head[pair]
    while threshold >= 0 and entry_sibling[entry] >= 0:
        entry = entry_sibling[entry]
        threshold -= entry_count[entry]
    return entry


@inline_jit
def expected_target(
    q: np.ndarray,
    pair_head: np.ndarray,
    pair_total: np.ndarray,
    entry_count: np.ndarray,
    entry_reward_sum: np.ndarray,
    entry_terminal_count: np.ndarray,
    entry_next_state: np.ndarray,
    entry_sibling: np.ndarray,
    pair: int,
    gamma: float,
) -> float:
    """``Σ_s′ p(s′|s, a) · outcome target`` over every observed outcome of ``pair``, summed in the
    order of the pair's outcome list."""
    total = pair_total[pair]
    value = 0.0
    entry = pair_head[pair]
    while entry >= 0:
        count = entry_count[entry]
        outcome = entry_target(
            q, count, entry_reward_sum[entry], entry_terminal_count[entry],
            entry_next_state[entry], gamma,
        )  # fmt: skip
        value += count / total * outcome
        entry = entry_sibling[entry]
    return value


@inline_jit
def expected_model_target(
    q: np.ndarray, model: MultinomialArrays, pair: int, gamma: float
) -> float:
    """:func:`expected_target` of ``pair`` read from the model's arrays: one path, every use of
    the model's arrays on it, so that the model bound to it costs no reference counting in the
    planning loops, as :func:`most_probable_target`. Through the compiled call
    :func:`model_target_call` an expected update of
    :func:`skidnav.agents.kinematic_planning.combined_planning` cost 120–160 ns more, against
    ~7 ns for the target itself (trajectory-prioritized on the obstacles arena,
    docs/agents/fast-training.md)."""
    return expected_target(
        q, model.pair_head, model.pair_total, model.entry_count, model.entry_reward_sum,
        model.entry_terminal_count, model.entry_next_state, model.entry_sibling, pair, gamma,
    )  # fmt: skip


@inline_jit
def model_target(
    model: MultinomialArrays,
    q: np.ndarray,
    pair: int,
    mode: int,
    gamma: float,
    uniform: float,
) -> float:
    """Planning target of an observed pair slot under ``mode`` (MOST_PROBABLE, SAMPLE, EXPECTED).

    ``uniform`` is one ``rng.random()`` drawn by the caller: it picks the outcome (SAMPLE) or
    breaks ties (MOST_PROBABLE); EXPECTED ignores it. ``SAMPLE`` and ``MOST_PROBABLE`` give
    ``r̄ + γ · (1 − β) · max_a q[s′, a]`` of the chosen outcome; ``EXPECTED`` gives
    ``Σ_s′ p(s′|s, a)`` times that, summed in the order of the pair's outcome list.
    """
    if mode == EXPECTED:
        target = expected_target(
            q, model.pair_head, model.pair_total, model.entry_count, model.entry_reward_sum,
            model.entry_terminal_count, model.entry_next_state, model.entry_sibling, pair, gamma,
        )  # fmt: skip
    elif mode != SAMPLE:
        target = most_probable_target(q, model, pair, gamma, uniform)
    else:
        entry = sample_entry(
            model.pair_head, model.pair_total, model.entry_count, model.entry_sibling, pair,
            uniform,
        )  # fmt: skip
        target = entry_target(
            q, model.entry_count[entry], model.entry_reward_sum[entry],
            model.entry_terminal_count[entry], model.entry_next_state[entry], gamma,
        )  # fmt: skip
    return target


@jit
def model_target_call(
    model: MultinomialArrays,
    q: np.ndarray,
    pair: int,
    mode: int,
    gamma: float,
    uniform: float,
) -> float:
    """:func:`model_target` as a compiled call, not inlined: for the rare paths of the planning
    loops (a call pays for its arguments only when it is made, an inlined copy on every pass)."""
    return model_target(model, q, pair, mode, gamma, uniform)
