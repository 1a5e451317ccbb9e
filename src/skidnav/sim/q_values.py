"""The shared tabular learning kernels: the one TD update and the one ε-greedy rule.

Every tabular agent in :mod:`skidnav.agents` (and every compiled trainer) learns through these
functions, so the update rule exists exactly once.

Conventions
-----------
``q`` is the action-value table, a float64 array of shape ``(n_states, n_actions)`` indexed
``q[state, action]``. The TD target of a transition ``(s, a, r, s')`` is

    target = r + γ · c · max_a' q[s', a']

where the *continuation* ``c`` is 0 when the episode **terminated** in ``s'`` (a true end: no value
after it) and 1 otherwise, including when it was merely **truncated** by a time limit (the state
``s'`` still has a future, so the update bootstraps). A learned model may give a fractional ``c``,
the probability that the transition does not terminate. The update is

    q[s, a] ← q[s, a] + α · (target − q[s, a])

(Sutton & Barto (2018) §6.5, Q-learning; Gymnasium's terminated/truncated semantics).

Randomness: every function that draws takes a ``numpy.random.Generator`` and calls only
``rng.random()``, so the results are bit-identical with ``NUMBA_DISABLE_JIT=1``.

>>> import numpy as np
>>> q = np.zeros((2, 2))
>>> q[1] = [1.0, 3.0]
>>> round(td_update(q, 0, 1, 0.5, 1, False, 0.1, 0.9), 6)  # target 0.5 + 0.9 * 3 = 3.2
3.2
>>> round(float(q[0, 1]), 6)
0.32
>>> td_update(q, 0, 0, 1.0, 1, True, 0.5, 0.9)  # terminated: target is the reward alone
1.0
>>> float(q[0, 0])
0.5
"""

from __future__ import annotations

import numpy as np

from skidnav._jit import inline_jit


@inline_jit
def max_value(q: np.ndarray, state: int) -> float:
    """``max_a q[state, a]``: the greedy value of ``state``."""
    best = q[state, 0]
    for action in range(1, q.shape[1]):
        if q[state, action] > best:
            best = q[state, action]
    return float(best)


@inline_jit
def td_target(
    q: np.ndarray, reward: float, next_state: int, continuation: float, gamma: float
) -> float:
    """The one-step Q-learning target ``reward + gamma · continuation · max_a q[next_state, a]``.

    ``continuation`` is 0.0 after termination, 1.0 otherwise (truncation included), or a
    probability in [0, 1] when the transition comes from a learned model. When it is 0 the value
    of ``next_state`` is not read at all (terminal states may hold arbitrary values).
    """
    if continuation == 0.0:
        return reward
    return reward + gamma * continuation * max_value(q, next_state)


@inline_jit
def update_toward(q: np.ndarray, state: int, action: int, target: float, alpha: float) -> float:
    """Move ``q[state, action]`` a fraction ``alpha`` of the way to ``target``; return the TD error
    ``target − q[state, action]`` measured before the update."""
    error = target - q[state, action]
    q[state, action] += alpha * error
    return error


@inline_jit
def visit_step_size(
    visits: np.ndarray, state: int, action: int, alpha: float, exponent: float
) -> float:
    """Step size of a real update of ``(state, action)``: ``alpha · n^(−exponent)``, n the
    pair's real updates including this one, counted in ``visits`` (int64 (n_states, n_actions)).
    With ``exponent`` 0, ``alpha`` itself, and ``visits`` (then any placeholder) is not touched
    (Even-Dar & Mansour (2003), polynomial step sizes)."""
    if exponent == 0.0:
        return alpha
    visits[state, action] += 1
    return alpha * float(visits[state, action]) ** (-exponent)


@inline_jit
def td_update(
    q: np.ndarray,
    state: int,
    action: int,
    reward: float,
    next_state: int,
    terminated: bool,
    alpha: float,
    gamma: float,
) -> float:
    """One Q-learning update from a real transition; returns the TD error before the update.

    Bootstraps on ``next_state`` unless ``terminated`` (truncation still bootstraps).
    """
    continuation = 0.0 if terminated else 1.0
    return update_toward(
        q, state, action, td_target(q, reward, next_state, continuation, gamma), alpha
    )


@inline_jit
def greedy_first(q: np.ndarray, state: int) -> int:
    """The lowest-index action among the maxima of ``q[state]`` (deterministic, draws nothing)."""
    best_action = 0
    for action in range(1, q.shape[1]):
        if q[state, action] > q[state, best_action]:
            best_action = action
    return best_action


@inline_jit
def random_argmax(q: np.ndarray, state: int, rng: np.random.Generator) -> int:
    """An action maximising ``q[state]``, ties broken uniformly at random.

    Draws one ``rng.random()`` only when there is a tie (two or more maximal actions).
    """
    n_actions = q.shape[1]
    best = max_value(q, state)
    n_ties = 0
    for action in range(n_actions):
        if q[state, action] == best:
            n_ties += 1
    if n_ties == 1:
        return greedy_first(q, state)
    pick = int(rng.random() * n_ties)
    for action in range(n_actions):
        if q[state, action] == best:
            if pick == 0:
                return action
            pick -= 1
    return n_actions - 1  # unreachable: pick < n_ties


@inline_jit
def epsilon_greedy(q: np.ndarray, state: int, epsilon: float, rng: np.random.Generator) -> int:
    """ε-greedy action: uniformly random with probability ``epsilon``, else :func:`random_argmax`.

    Draws one ``rng.random()`` for the coin, then one for the random action or for a tie.
    """
    if rng.random() < epsilon:
        return int(rng.random() * q.shape[1])
    return random_argmax(q, state, rng)


def epsilon_at(episode: int, initial: float, decay: float, minimum: float) -> float:
    """Per-episode decaying exploration rate ``max(minimum, initial · decay**episode)``.

    ``episode`` counts completed episodes (0 for the first one).

    >>> epsilon_at(0, 0.5, 0.9, 0.05), round(epsilon_at(2, 0.5, 0.9, 0.05), 6)
    (0.5, 0.405)
    >>> epsilon_at(100, 0.5, 0.9, 0.05)
    0.05
    """
    return max(minimum, initial * decay**episode)
