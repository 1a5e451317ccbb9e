"""Compiled updates of the linear agents over binary (tile-coded) features.

Conventions
-----------
``w`` holds the weights, float64 of shape ``(n_actions, n_features)``; a state is given by its
active features ``tiles`` (int64, shape (n_tilings,), :mod:`skidnav.agents.linear.tile_coding`), so
``q(s, a) = Σ_i w[a, tiles[i]]``. ``step`` is the step size already divided by the number of
active features (α / n_tilings, Sutton & Barto (2018) §9.5.4), so one update moves ``q(s, a)``
by ``α · δ``. As in :mod:`skidnav.sim.q_values`, a transition bootstraps unless it
**terminated** (a truncated one still bootstraps). ``values`` is a scratch float64 array of
shape (1, n_actions) that receives ``q(s, ·)``; ε-greedy and the greedy choice are those of
:mod:`skidnav.sim.q_values` applied to it, so there is one ε-greedy rule in skidnav.

>>> import numpy as np
>>> w, values = np.zeros((2, 4)), np.zeros((1, 2))
>>> w[1, 2], w[0, 3] = 1.0, 0.5
>>> q_learning_update(w, np.array([0, 1]), 0, 1.0, np.array([2, 3]), False, 0.25, 0.9, values)
1.9
>>> w[0].tolist()  # δ = 1 + 0.9 · max(0.5, 1) − 0 = 1.9, step 0.25 on features 0 and 1
[0.475, 0.475, 0.0, 0.5]
"""

from __future__ import annotations

import numpy as np

from skidnav._jit import inline_jit, jit
from skidnav.sim.q_values import epsilon_greedy, greedy_first, max_value


@inline_jit
def linear_value(w: np.ndarray, action: int, tiles: np.ndarray) -> float:
    """``q(s, action) = Σ_i w[action, tiles[i]]``."""
    total = 0.0
    for i in range(tiles.shape[0]):
        total += w[action, tiles[i]]
    return total


@inline_jit
def fill_values(w: np.ndarray, tiles: np.ndarray, values: np.ndarray) -> None:
    """``values[0, a] = q(s, a)`` for every action."""
    for action in range(w.shape[0]):
        values[0, action] = linear_value(w, action, tiles)


@jit
def choose_action(
    w: np.ndarray, tiles: np.ndarray, values: np.ndarray, epsilon: float, rng: np.random.Generator
) -> int:
    """ε-greedy action in the state of ``tiles`` (ties broken uniformly by ``rng``)."""
    fill_values(w, tiles, values)
    return epsilon_greedy(values, 0, epsilon, rng)


@jit
def greedy_linear(w: np.ndarray, tiles: np.ndarray, values: np.ndarray) -> int:
    """The lowest-index greedy action in the state of ``tiles`` (draws nothing)."""
    fill_values(w, tiles, values)
    return greedy_first(values, 0)


@inline_jit
def add_to_features(w: np.ndarray, action: int, tiles: np.ndarray, amount: float) -> None:
    """``w[action, tiles[i]] += amount`` for each active feature."""
    for i in range(tiles.shape[0]):
        w[action, tiles[i]] += amount


@jit
def q_learning_update(
    w: np.ndarray,
    tiles: np.ndarray,
    action: int,
    reward: float,
    next_tiles: np.ndarray,
    terminated: bool,
    step: float,
    gamma: float,
    values: np.ndarray,
) -> float:
    """Semi-gradient Q-learning (Sutton & Barto (2018) §10.1 with the target of §6.5):
    ``w[a] += step · δ · x(s)``, ``δ = r + γ · max_a' q(s', a') − q(s, a)`` (no bootstrap after
    termination). Returns the TD target ``r + γ · max_a' q(s', a')``."""
    target = reward
    if not terminated:
        fill_values(w, next_tiles, values)
        target += gamma * max_value(values, 0)
    add_to_features(w, action, tiles, step * (target - linear_value(w, action, tiles)))
    return target


@jit
def sarsa_lambda_update(
    w: np.ndarray,
    traces: np.ndarray,
    tiles: np.ndarray,
    action: int,
    reward: float,
    next_tiles: np.ndarray,
    next_action: int,
    terminated: bool,
    step: float,
    gamma: float,
    lam: float,
) -> None:
    """One step of Sarsa(λ) with binary features and **replacing** traces (Sutton & Barto
    (2018) §12.7, the boxed algorithm): ``z[a, F(s)] = 1``; ``δ = r + γ q(s', a') − q(s, a)``
    (``γ q(s', a')`` left out after termination); ``w += step · δ · z``; ``z *= γλ``.

    ``traces`` has the shape of ``w``; the caller zeroes it at the start of each episode.
    """
    for i in range(tiles.shape[0]):
        traces[action, tiles[i]] = 1.0
    delta = reward - linear_value(w, action, tiles)
    if not terminated:
        delta += gamma * linear_value(w, next_action, next_tiles)
    amount, decay = step * delta, gamma * lam
    for a in range(w.shape[0]):
        for i in range(w.shape[1]):
            w[a, i] += amount * traces[a, i]
            traces[a, i] *= decay


@jit
def model_update(
    next_model: np.ndarray,
    reward_model: np.ndarray,
    tiles: np.ndarray,
    action: int,
    reward: float,
    next_tiles: np.ndarray,
    terminated: bool,
    step: float,
    predicted: np.ndarray,
) -> None:
    """The least-mean-squares updates of Linear Dyna's model of ``action`` (Sutton, Szepesvári,
    Geramifard & Bowling 2008, §4): ``F_a += step · (x' − F_a x) xᵀ`` and
    ``b_a += step · (r − b_aᵀ x) x``, ``x`` the features of the state, ``x'`` those of the next
    state (the zero vector after termination: no value follows).

    ``next_model`` float64 (n_actions, n_features, n_features) holds ``F_a`` transposed
    (``next_model[a, i]`` is column ``i`` of ``F_a``, so ``F_a x`` adds rows); ``reward_model``
    float64 (n_actions, n_features) holds ``b_a``; ``predicted`` is a scratch float64
    (n_features,); ``step`` is the model's α divided by the active features.
    """
    predict_next(next_model, action, tiles, predicted)
    if not terminated:
        for i in range(next_tiles.shape[0]):
            predicted[next_tiles[i]] -= 1.0
    # predicted now holds F_a x − x'; every active column moves a fraction toward x'.
    for i in range(tiles.shape[0]):
        row = tiles[i]
        for j in range(predicted.shape[0]):
            next_model[action, row, j] -= step * predicted[j]
    error = reward - linear_value(reward_model, action, tiles)
    add_to_features(reward_model, action, tiles, step * error)


@inline_jit
def predict_next(
    next_model: np.ndarray, action: int, tiles: np.ndarray, predicted: np.ndarray
) -> None:
    """``predicted = F_a x`` for the binary ``x`` of ``tiles`` (a sum of rows of the model)."""
    predicted[:] = 0.0
    for i in range(tiles.shape[0]):
        row = tiles[i]
        for j in range(predicted.shape[0]):
            predicted[j] += next_model[action, row, j]


@inline_jit
def dense_value(w: np.ndarray, action: int, features: np.ndarray) -> float:
    """``w[action] · features`` for a dense feature vector."""
    total = 0.0
    for i in range(features.shape[0]):
        total += w[action, i] * features[i]
    return total


@jit
def linear_dyna_planning(
    w: np.ndarray,
    next_model: np.ndarray,
    reward_model: np.ndarray,
    visited: np.ndarray,
    n_visited: int,
    n_updates: int,
    step: float,
    gamma: float,
    rng: np.random.Generator,
    predicted: np.ndarray,
) -> None:
    """``n_updates`` planning updates of Linear Dyna for control (Sutton et al. 2008, §5, with
    action values): draw a row of ``visited`` (int64 (capacity, n_tilings), the features of
    recently visited states; the first ``n_visited`` rows filled) and an action ``a``, both
    uniformly (two ``rng.random()``), then move ``q(x, a)`` toward the model's target
    ``b_aᵀ x + γ · max_a' w[a'] · (F_a x)``: ``w[a] += step · δ · x``."""
    n_actions = w.shape[0]
    for _ in range(n_updates):
        tiles = visited[int(rng.random() * n_visited)]
        action = int(rng.random() * n_actions)
        predict_next(next_model, action, tiles, predicted)
        best = dense_value(w, 0, predicted)
        for other in range(1, n_actions):
            best = max(best, dense_value(w, other, predicted))
        target = linear_value(reward_model, action, tiles) + gamma * best
        add_to_features(w, action, tiles, step * (target - linear_value(w, action, tiles)))
