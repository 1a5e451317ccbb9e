"""The random numbers of one MPPI batch, drawn in compiled code from the planner's Generator.

Every number is a standard normal of ``Generator.standard_normal`` in NumPy's own order: the
perturbations' (K, H, 2), then the model draws' (K · M, 5), then the noise's (K · M, H, 3), each
in C order — the numbers a call ``rng.standard_normal(shape)`` per array would give, one by one
(numba's Generator runs NumPy's ziggurat on the same bit generator, so the stream and the
Generator's state after it are NumPy's, about 2.7× faster than NumPy's own call here). The
perturbations are smoothed, added to the plan and clipped in the same pass, element by element
in the order and with the operations of the NumPy expressions they replace
(:meth:`~skidnav.agents.mpc.planner.MPPIPlanner.sample`), so the batch is the same bit for bit,
compiled or interpreted (``NUMBA_DISABLE_JIT=1``: then each draw is one NumPy call, slowly).
"""

from __future__ import annotations

import math

import numpy as np

from skidnav._jit import inline_jit, jit


@inline_jit
def sample_sequences(
    rng: np.random.Generator,
    plan: np.ndarray,
    noise_std: float,
    correlation: float,
    limit: float,
    controls: np.ndarray,
    perturbation: np.ndarray,
    drawn: bool,
) -> None:
    """Steps 1–2 of :mod:`~skidnav.agents.mpc.planner`: K perturbation sequences of standard
    normals n, ε_t = β ε_{t−1} + √(1 − β²) σ n_t (β = ``correlation``; white for β = 0),
    sequence 0 zero, and the sequences U + ε clipped to ± ``limit``.

    Args:
        rng: the planner's Generator (2 K H normals drawn, sequence by sequence, step by step).
        plan: float64 (H, 2) U, the planned wheel speeds [rad/s].
        noise_std: σ [rad/s]. correlation: β in [0, 1). limit: Ω [rad/s].
        controls: float64 (K, H, 2) receives clip(U + ε, −Ω, Ω) [rad/s].
        perturbation: float64 (K, H, 2) receives the clipped perturbation, controls − U
            [rad/s], or with ``drawn`` the perturbation ε as drawn
            (:attr:`~skidnav.agents.mpc.config.MPPIConfig.plan_update`).
    """
    innovation = math.sqrt(1.0 - correlation * correlation)
    for k in range(controls.shape[0]):
        left, right = 0.0, 0.0
        for t in range(controls.shape[1]):
            new_left = rng.standard_normal() * noise_std
            new_right = rng.standard_normal() * noise_std
            if correlation > 0.0 and t > 0:
                new_left = correlation * left + innovation * new_left
                new_right = correlation * right + innovation * new_right
            left, right = new_left, new_right
            if k == 0:  # the plan itself (its normals drawn all the same)
                new_left, new_right = 0.0, 0.0
            plan_left, plan_right = plan[t, 0], plan[t, 1]
            clipped_left = min(max(plan_left + new_left, -limit), limit)
            clipped_right = min(max(plan_right + new_right, -limit), limit)
            controls[k, t, 0], controls[k, t, 1] = clipped_left, clipped_right
            if drawn:
                perturbation[k, t, 0], perturbation[k, t, 1] = new_left, new_right
            else:
                perturbation[k, t, 0] = clipped_left - plan_left
                perturbation[k, t, 1] = clipped_right - plan_right


@inline_jit
def standard_normals(rng: np.random.Generator, out: np.ndarray) -> None:
    """Fill the C-contiguous ``out`` with standard normals in C order (as
    ``rng.standard_normal(out.shape)``)."""
    flat = out.reshape(-1)
    for index in range(flat.shape[0]):
        flat[index] = rng.standard_normal()


@jit
def sample_batch(
    rng: np.random.Generator,
    plan: np.ndarray,
    noise_std: float,
    correlation: float,
    limit: float,
    controls: np.ndarray,
    perturbation: np.ndarray,
    model: np.ndarray,
    noise: np.ndarray,
    sample_model: bool,
    drawn: bool,
) -> None:
    """One batch's numbers in the module doc's order: :func:`sample_sequences` (arguments as
    there), then, if ``sample_model``, the standard normals of the model draws ``model``
    float64 (K · M, 5) and of the noise ``noise`` float64 (K · M, H, 3) (else they are left as
    they are: zeros)."""
    sample_sequences(rng, plan, noise_std, correlation, limit, controls, perturbation, drawn)
    if sample_model:
        standard_normals(rng, model)
        standard_normals(rng, noise)
