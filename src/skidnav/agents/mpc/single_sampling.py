"""The random numbers of one MPPI batch of the fast path (``MPPIConfig.precision =
"float32"``): standard normals by Box–Muller, two from each counter-based uniform
(:func:`~skidnav.agents.mpc.single.counter_uniform`, 53 bits) of a stream whose key the
planner's Generator draws once per batch (``Generator.random``), in single precision, and the
sequences made of them.

A uniform is a function of its index, so every loop runs over the samples in the innermost
loop, which the compiler vectorises: the uniforms and their halves, the normals, the AR(1)
smoothing and the clip, with the formulas of :mod:`~skidnav.agents.mpc.single` — the same
numbers compiled, interpreted (``NUMBA_DISABLE_JIT=1``) and in the benchmark's NumPy twin. The
Generator's own uniforms, one call each, took half the time of the batch's sampling
(26,240 of them, 1.9–2.4 ns each, against 0.6 ns for the counter's); the batch takes about
half the time of the double-precision batch's ziggurat (:mod:`~skidnav.agents.mpc.sampling`).

Layout (all float32, the samples last, each step's contiguous): the normals ``normals``
(2 · n_words,) — the cosines' half, then the sines' — hold the perturbations' (H, 2, K) first,
then, when the model is sampled, the model draws' (5, K · M) and the noise's (H, 3, K · M).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from skidnav._jit import vector_jit
from skidnav.agents.mpc.dynamics import N_DRAWS
from skidnav.agents.mpc.rollouts import RolloutDraws
from skidnav.agents.mpc.single import (
    box_muller,
    counter_uniform,
    float_parts,
    sequence_step,
    stream_key,
    uniform_halves,
)


def normal_count(samples: int, horizon: int, rollouts: int, sample_model: bool) -> int:
    """How many normals a batch uses: 2 K H for the sequences, and 5 R + 3 R H for the
    model's draws and noise of R = K · M rollouts when the model is sampled."""
    return 2 * samples * horizon + ((N_DRAWS + 3 * horizon) * rollouts if sample_model else 0)


@vector_jit
def draw_normals(key: np.uint64, parts: np.ndarray, normals: np.ndarray) -> None:
    """``normals`` float32 (2 n,) from the first n uniforms of the stream ``key`` (``parts``
    float32 (3, n) scratch): the cosine normal of uniform w at w, its sine normal at n + w.
    (n is read from ``normals``: read from ``parts``, the compiler no longer vectorised the
    Box–Muller loop, 5× slower.)"""
    n = normals.shape[0] // 2
    for word in range(n):  # vectorised: uint64 in, float32 out
        parts[0, word], parts[2, word] = uniform_halves(counter_uniform(key, np.uint64(word + 1)))
    bits = parts[0].view(np.int32)
    for word in range(n):  # vectorised, int32: the count's mantissa and exponent
        bits[word], parts[1, word] = float_parts(bits[word])
    for word in range(n):  # vectorised, float32 throughout
        normals[word], normals[n + word] = box_muller(
            parts[0, word], parts[1, word], parts[2, word]
        )


@vector_jit
def make_sequences(
    normals: np.ndarray,
    plan: np.ndarray,
    scales: tuple[float, float, float],
    smoothed: np.ndarray,
    controls: np.ndarray,
    perturbation: np.ndarray,
) -> None:
    """Steps 1–2 of :mod:`~skidnav.agents.mpc.planner` in float32 from the first 2 K H
    ``normals``: ``scales`` (σ [rad/s], β, Ω [rad/s]); ``smoothed`` float32 (2, K) scratch;
    ``controls`` and ``perturbation`` float32 (H, 2, K) receive clip(U + ε) and its clipped
    perturbation [rad/s]; sequence 0 is the plan itself (its normals drawn all the same)."""
    horizon, samples = controls.shape[0], controls.shape[2]
    noise_std, correlation, limit = scales
    first = (np.float32(noise_std), np.float32(0.0), np.float32(1.0), np.float32(limit))
    later = (
        first[0], np.float32(correlation),
        np.float32(math.sqrt(1.0 - correlation * correlation)), first[3],
    )  # fmt: skip
    for t in range(horizon):
        step_scales = first if t == 0 else later
        for wheel in range(2):
            start = (2 * t + wheel) * samples
            planned = np.float32(plan[t, wheel])
            for k in range(samples):  # vectorised
                smoothed[wheel, k], controls[t, wheel, k], perturbation[t, wheel, k] = (
                    sequence_step(smoothed[wheel, k], normals[start + k], planned, step_scales)
                )
            clipped = min(max(planned, -first[3]), first[3])
            controls[t, wheel, 0], perturbation[t, wheel, 0] = clipped, clipped - planned


class SingleBatch(NamedTuple):
    """The arrays of the fast path's batches, allocated once per planner and overwritten by
    each batch (module doc).

    Attributes:
        parts: float32 (3, n) the halves of the n uniforms, the first split into mantissa and
            exponent.
        normals: float32 (2 n,) the standard normals.
        smoothed: float32 (2, K) the AR(1) perturbations of the last step made.
        controls: float32 (H, 2, K) the sequences clip(U + ε) [rad/s].
        perturbation: float32 (H, 2, K) their clipped perturbations [rad/s].
        draws: the rollouts' normals as views of ``normals`` (zeros when the model is not
            sampled): ``model`` float32 (5, K · M), ``noise`` float32 (H, 3, K · M).
    """

    parts: np.ndarray
    normals: np.ndarray
    smoothed: np.ndarray
    controls: np.ndarray
    perturbation: np.ndarray
    draws: RolloutDraws


def single_batch(
    samples: int, horizon: int, per_sequence: int, noise_scale: float, sample_model: bool
) -> SingleBatch:
    """The zeroed arrays of K = ``samples`` sequences of H = ``horizon`` steps, M =
    ``per_sequence`` model draws each; ``noise_scale`` 1/√(sub-steps), 0 without sampling."""
    rollouts = samples * per_sequence
    words = (normal_count(samples, horizon, rollouts, sample_model) + 1) // 2
    normals = np.zeros(2 * words, np.float32)
    start, middle = 2 * samples * horizon, 2 * samples * horizon + N_DRAWS * rollouts
    if sample_model:
        model = normals[start:middle].reshape(N_DRAWS, rollouts)
        noise = normals[middle : middle + 3 * horizon * rollouts].reshape(horizon, 3, rollouts)
    else:
        model = np.zeros((N_DRAWS, rollouts), np.float32)
        noise = np.zeros((horizon, 3, rollouts), np.float32)
    shape = (horizon, 2, samples)
    return SingleBatch(
        np.zeros((3, words), np.float32), normals,
        np.zeros((2, samples), np.float32), np.zeros(shape, np.float32),
        np.zeros(shape, np.float32), RolloutDraws(model, noise, noise_scale, per_sequence),
    )  # fmt: skip


def sample_single(
    rng: np.random.Generator, plan: np.ndarray, scales: tuple[float, float, float],
    batch: SingleBatch,
) -> None:  # fmt: skip
    """One batch into ``batch``: :func:`draw_normals` of a new stream of ``rng``, then
    :func:`make_sequences` around the plan U float64 (H, 2) [rad/s] with ``scales``
    (σ [rad/s], β, Ω [rad/s])."""
    draw_normals(stream_key(rng), batch.parts, batch.normals)
    make_sequences(batch.normals, plan, scales, batch.smoothed, batch.controls, batch.perturbation)
