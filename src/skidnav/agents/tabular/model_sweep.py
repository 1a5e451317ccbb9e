"""Value iteration over everything the model-based agent has learned (``dyna-sweep``).

One sweep updates every pair (s, a) of every state outside the known wall cells, in state order
(Gauss–Seidel), to its model target with step 1 (a full backup, Sutton & Barto (2018) §4.4):

* a pair seen in reality: the multinomial model's expected target Σ p(s′|s, a)(r̄ + γ (1 − β)
  max_a′ Q(s′, a′)) (:func:`skidnav.models.multinomial_targets.expected_target`);
* a pair never seen: the kinematic table's predicted outcome with the learned mean rewards
  (:func:`skidnav.agents.kinematic_planning.kinematic_value`), walls found by collisions
  respected — the optimistic "unknown cells are free" model that makes the agent try the
  shortest predicted path and learn the walls it meets.

Sweeps repeat until no value moves by more than ``tolerance`` or ``max_sweeps`` were made.
"""

from __future__ import annotations

import numpy as np

from skidnav._jit import jit
from skidnav.agents.kinematic_planning import (
    USE_KINEMATIC,
    PlannerArrays,
    kinematic_value,
    mean_rewards,
)
from skidnav.models.multinomial_kernels import MultinomialArrays
from skidnav.models.multinomial_targets import expected_target
from skidnav.world.discretization import GridShape


@jit
def pair_slots(model: MultinomialArrays, n_states: int, n_actions: int) -> np.ndarray:
    """int64 (n_states · n_actions,): the model's slot of every pair key, −1 if never seen (one
    pass over the model, so a sweep needs no hash lookups)."""
    slots = np.full(n_states * n_actions, -1, dtype=np.int64)
    for pair in range(model.counters[0]):
        slots[model.pair_key[pair]] = pair
    return slots


@jit
def _sweep_once(
    q: np.ndarray,
    model: MultinomialArrays,
    planner: PlannerArrays,
    slots: np.ndarray,
    means: np.ndarray,
    gamma: float,
    grid: GridShape,
) -> tuple[float, int]:
    """One Gauss–Seidel sweep (``means``: the learned mean rewards, :func:`mean_rewards`);
    returns (largest change of a value, values updated)."""
    n_states, n_actions = q.shape
    head, total, counts = model.pair_head, model.pair_total, model.entry_count
    sums, terminals = model.entry_reward_sum, model.entry_terminal_count
    next_states, siblings = model.entry_next_state, model.entry_sibling
    kinematic = planner.counters[USE_KINEMATIC] != 0
    change, updates = 0.0, 0
    for state in range(n_states):
        cell = state // grid.n_headings
        if planner.walls[cell // grid.n_y, cell % grid.n_y]:
            continue
        for action in range(n_actions):
            pair = slots[state * n_actions + action]
            if pair >= 0:
                target = expected_target(
                    q, head, total, counts, sums, terminals, next_states, siblings, pair, gamma
                )
            elif kinematic:
                target = kinematic_value(
                    q, planner.pred_next, planner.pred_row, means, state, action, gamma
                )
            else:
                continue
            change = max(change, abs(target - q[state, action]))
            q[state, action] = target
            updates += 1
    return change, updates


@jit
def model_value_iteration(
    q: np.ndarray,
    model: MultinomialArrays,
    planner: PlannerArrays,
    gamma: float,
    grid: GridShape,
    max_sweeps: int,
    tolerance: float,
) -> tuple[int, int]:
    """Sweep (module docs) until the largest change is ≤ ``tolerance`` or after ``max_sweeps``;
    ``q`` float64 (n_states, n_actions) is updated in place. Returns (sweeps, value updates)."""
    slots = pair_slots(model, q.shape[0], q.shape[1])
    means = mean_rewards(planner.reward_stats)  # real rewards do not change while solving
    updates = 0
    for sweep in range(1, max_sweeps + 1):
        change, made = _sweep_once(q, model, planner, slots, means, gamma, grid)
        updates += made
        if change <= tolerance:
            return sweep, updates
    return max_sweeps, updates
