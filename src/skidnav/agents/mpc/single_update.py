"""Steps 3–5 of :mod:`~skidnav.agents.mpc.planner` on the fast path (``MPPIConfig.precision =
"float32"``), compiled: the sequences' costs from their rollouts', their weights, the plan moved
and shifted. The double-precision path keeps NumPy's update, whose sums its measured tables
were made with; here every sum is a loop in a fixed order (the same numbers with
``NUMBA_DISABLE_JIT=1``)."""

from __future__ import annotations

import math

import numpy as np

from skidnav._jit import vector_inline_jit, vector_jit


@vector_jit
def update_plan(
    draw_costs: np.ndarray,
    perturbation: np.ndarray,
    scales: tuple[bool, float, float, float, float],
    plan: np.ndarray,
    costs: np.ndarray,
    weights: np.ndarray,
) -> tuple[float, float]:
    """The planner's update (:meth:`~skidnav.agents.mpc.planner.MPPIPlanner.update`) from the
    rollouts' costs ``draw_costs`` float64 (K · M,) [control steps] and the clipped
    perturbations float32 (H, 2, K) [rad/s]; ``scales`` (worst: the M costs' largest, else
    their mean; γ / σ² of the control cost [1/(rad/s)²]; the temperature λ / T [control
    steps]; the bound Ω [rad/s]; M). Writes the sequences' costs and weights float64 (K,),
    moves and shifts ``plan`` float64 (H, 2) in place and returns the wheel speeds (ω_L, ω_R)
    [rad/s] to command now."""
    worst, control_weight, temperature, limit, per_sequence = scales
    samples, horizon = costs.shape[0], plan.shape[0]
    reduce_draws(draw_costs, int(per_sequence), worst, costs)
    if control_weight > 0.0:
        for t in range(horizon):
            for a in range(2):
                for k in range(samples):
                    costs[k] += control_weight * (plan[t, a] * perturbation[t, a, k])
    lowest = costs.min()
    total = 0.0
    for k in range(samples):
        weights[k] = math.exp(-(costs[k] - lowest) / temperature)
        total += weights[k]
    for k in range(samples):
        weights[k] /= total
    for t in range(horizon):
        for a in range(2):
            moved = plan[t, a] + weighted_sum(weights, perturbation, t, a)
            plan[t, a] = min(max(moved, -limit), limit)
    left, right = plan[0, 0], plan[0, 1]
    for t in range(horizon - 1):
        plan[t, 0], plan[t, 1] = plan[t + 1, 0], plan[t + 1, 1]
    return left, right


@vector_inline_jit
def reduce_draws(draw_costs: np.ndarray, draws: int, worst: bool, costs: np.ndarray) -> None:
    """Each sequence's cost from its M = ``draws`` rollouts' in a row: their largest when
    ``worst``, else their mean (summed in turn)."""
    for k in range(costs.shape[0]):
        total, largest = 0.0, -math.inf
        for m in range(draws):
            total += draw_costs[k * draws + m]
            largest = max(largest, draw_costs[k * draws + m])
        costs[k] = largest if worst else total / draws


@vector_inline_jit
def weighted_sum(weights: np.ndarray, perturbation: np.ndarray, t: int, a: int) -> float:
    """Σ_k w_k ε[t, a, k] in a fixed order: eight running sums over k mod 8 (independent
    chains the processor overlaps, where one running sum waits on each addition), added in
    pairs, then the K mod 8 last terms in turn."""
    s0, s1, s2, s3, s4, s5, s6, s7 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    whole = weights.shape[0] - weights.shape[0] % 8
    for k in range(0, whole, 8):
        s0 += weights[k] * perturbation[t, a, k]
        s1 += weights[k + 1] * perturbation[t, a, k + 1]
        s2 += weights[k + 2] * perturbation[t, a, k + 2]
        s3 += weights[k + 3] * perturbation[t, a, k + 3]
        s4 += weights[k + 4] * perturbation[t, a, k + 4]
        s5 += weights[k + 5] * perturbation[t, a, k + 5]
        s6 += weights[k + 6] * perturbation[t, a, k + 6]
        s7 += weights[k + 7] * perturbation[t, a, k + 7]
    total: float = ((s0 + s1) + (s2 + s3)) + ((s4 + s5) + (s6 + s7))
    for k in range(whole, weights.shape[0]):
        total += weights[k] * perturbation[t, a, k]
    return total
