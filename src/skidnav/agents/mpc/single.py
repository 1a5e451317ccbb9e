"""Single-precision formulas of the fast rollouts (``MPPIConfig.precision = "float32"``), in
plain arithmetic: the same function runs on float32 scalars inside a compiled loop, which the
compiler then vectorises over the samples (no call to the C library's sine, cosine or
logarithm, which it cannot vectorise), and on float32 NumPy arrays in the benchmark's NumPy
twin, where it gives the same numbers bit for bit.

Every operand is float32: the constants are ``np.float32`` (numba would widen a float32 and a
Python float to float64, NumPy would not), a choice between two values is ``np.where`` on
arrays and a conditional expression compiled (:func:`choose`), and no operation is contracted
into a fused multiply-add (numba compiles without fastmath). The sine and cosine are Taylor
polynomials on a quarter turn after a three-part Cody–Waite reduction (Muller 2016,
"Elementary Functions", ch. 11): a few units in the last place of float32 for |angle| ≲ 10⁴ rad.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from skidnav._jit import compiled_as, elementwise

F32 = np.float32
_TWO_OVER_PI = F32(0.63661977236758134)
_PIO2_1 = F32(1.5703125)  # π/2 in three parts, the first two exact in few bits
_PIO2_2 = F32(4.837512969970703125e-4)
_PIO2_3 = F32(7.54978995489188216e-8)
_S3, _S5, _S7, _S9 = F32(-1.0 / 6.0), F32(1.0 / 120.0), F32(-1.0 / 5040.0), F32(1.0 / 362880.0)
_C2, _C4, _C6, _C8 = F32(-0.5), F32(1.0 / 24.0), F32(-1.0 / 720.0), F32(1.0 / 40320.0)
_LN2 = F32(0.69314718055994531)
_SQRT2 = F32(1.4142135623730951)
_TWO_PI = F32(6.2831853071795865)
_ZERO, _HALF, _ONE, _TWO, _FOUR = F32(0.0), F32(0.5), F32(1.0), F32(2.0), F32(4.0)
_QUARTER = F32(0.25)
_THIRD, _FIFTH, _SEVENTH, _NINTH = F32(1 / 3), F32(1 / 5), F32(1 / 7), F32(1 / 9)
_BITS = 16777216.0  # 2²⁴: the bits of the first uniform of a Box–Muller pair


@compiled_as(lambda value: math.sqrt(value))
def square_root(value: Any) -> Any:
    """√``value``, correctly rounded: NumPy's on arrays; compiled, the processor's square root
    (``np.sqrt`` of a scalar would call the C library, which the compiler does not vectorise)."""
    return np.sqrt(value)


@compiled_as(lambda condition, when_true, when_false: when_true if condition else when_false)
def choose(condition: Any, when_true: Any, when_false: Any) -> Any:
    """``when_true`` where ``condition`` (bool) else ``when_false``: ``np.where`` on arrays;
    compiled, a conditional expression (a select, which the compiler vectorises)."""
    return np.where(condition, when_true, when_false)


@elementwise
def sin_cos(angle: Any) -> tuple[Any, Any]:
    """(sin, cos) of ``angle`` [rad], float32 (module doc)."""
    quadrant = np.floor(angle * _TWO_OVER_PI + _HALF)
    reduced = ((angle - quadrant * _PIO2_1) - quadrant * _PIO2_2) - quadrant * _PIO2_3
    square = reduced * reduced
    sine = reduced + reduced * square * (_S3 + square * (_S5 + square * (_S7 + square * _S9)))
    cosine = _ONE + square * (_C2 + square * (_C4 + square * (_C6 + square * _C8)))
    quarter = quadrant - _FOUR * np.floor(quadrant * _QUARTER)  # 0, 1, 2, 3
    odd = quarter - _TWO * np.floor(quarter * _HALF)  # quadrants 1 and 3 swap sine and cosine
    odd = odd == _ONE
    sign_sine = choose(quarter >= _TWO, -_ONE, _ONE)  # − in quadrants 2 and 3
    sign_cosine = choose((quarter == _ONE) | (quarter == _TWO), -_ONE, _ONE)
    return sign_sine * choose(odd, cosine, sine), sign_cosine * choose(odd, sine, cosine)


@elementwise
def float_parts(bits: Any) -> tuple[Any, Any]:
    """The bits of a float32 ≥ 1 (int32) split into those of its mantissa m in [1, 2) and its
    exponent e (float32): the float is m · 2^e."""
    return (bits & 0x007FFFFF) | 0x3F800000, F32((bits >> 23) - 127)


@elementwise
def log_of_parts(mantissa: Any, exponent: Any) -> Any:
    """ln(m · 2^(e − 24)) for a whole count m · 2^e in [1, 2²⁴] (:func:`float_parts`), float32:
    2 atanh((m − 1)/(m + 1)) to s⁹ on m in [√½, √2], plus (e − 24) ln 2."""
    high = mantissa > _SQRT2
    mantissa = choose(high, mantissa * _HALF, mantissa)
    exponent = exponent + F32(high) - F32(24.0)
    ratio = (mantissa - _ONE) / (mantissa + _ONE)
    square = ratio * ratio
    series = _ONE + square * (_THIRD + square * (_FIFTH + square * (_SEVENTH + square * _NINTH)))
    return _TWO * ratio * series + exponent * _LN2


_GOLDEN_GAMMA = np.uint64(0x9E3779B97F4A7C15)  # SplitMix64's increment, 2⁶⁴ / φ, odd
_MIX_1, _MIX_2 = np.uint64(0xBF58476D1CE4E5B9), np.uint64(0x94D049BB133111EB)
_SHIFT_1, _SHIFT_2, _SHIFT_3 = np.uint64(30), np.uint64(27), np.uint64(31)
_DROPPED, _ULP = np.uint64(11), 2.0**-53  # 64 − 53 bits dropped; the step of [0, 1)


def stream_key(rng: np.random.Generator) -> np.uint64:
    """The key of a new stream of :func:`counter_uniform`, 0 … 2⁵³ − 1: one
    ``rng.random()`` · 2⁵³ (drawn in Python: passing the Generator to compiled code costs 7 µs)."""
    return np.uint64(rng.random() * 2.0**53)


def _splitmix_uniform(key: Any, index: Any) -> Any:
    z = key + index * _GOLDEN_GAMMA
    z = (z ^ (z >> _SHIFT_1)) * _MIX_1
    z = (z ^ (z >> _SHIFT_2)) * _MIX_2
    return np.float64((z ^ (z >> _SHIFT_3)) >> _DROPPED) * _ULP


@compiled_as(_splitmix_uniform)
def counter_uniform(key: Any, index: Any) -> Any:
    """The ``index``-th uniform of [0, 1) (53 bits, float64) of the stream ``key`` (uint64,
    both; ``index`` ≥ 1): SplitMix64's output for the state key + index · γ (Steele, Lea & Flood
    2014, "Fast splittable pseudorandom number generators", OOPSLA; it passes BigCrush), its
    high 53 bits. A function of the index alone, so a compiled loop over the indices is
    vectorised; the products wrap modulo 2⁶⁴ (NumPy's overflow warning silenced)."""
    with np.errstate(over="ignore"):
        return _splitmix_uniform(key, index)


@elementwise
def uniform_halves(uniform: Any) -> tuple[Any, Any]:
    """The two float32 uniforms of one uniform of [0, 1) with 53 random bits (float64,
    :func:`counter_uniform`): its first 24 bits as a whole count in [1, 2²⁴] and its next 29 as a
    fraction of [0, 1] (rounded to float32)."""
    scaled = uniform * _BITS
    high = np.floor(scaled)
    return F32(high + 1.0), F32(scaled - high)


@elementwise
def box_muller(mantissa: Any, exponent: Any, fraction: Any) -> tuple[Any, Any]:
    """Two standard normals, float32, from :func:`uniform_halves` (the count split by
    :func:`float_parts`): r = √(−2 ln u₁) with u₁ = count · 2⁻²⁴ in (0, 1], at the angle
    2π (``fraction`` − ½) (Box & Muller 1958); |normal| ≤ √(48 ln 2) ≈ 5.8."""
    radius = square_root(-_TWO * log_of_parts(mantissa, exponent))
    sine, cosine = sin_cos(_TWO_PI * (fraction - _HALF))
    return radius * cosine, radius * sine


@elementwise
def sequence_step(
    previous: Any, normal: Any, plan: Any, scales: tuple[Any, Any, Any, Any]
) -> tuple[Any, Any, Any]:
    """One step of the perturbations (steps 1–2 of :mod:`~skidnav.agents.mpc.planner`):
    ε = β ε_prev + √(1 − β²) σ n, the sequence clip(U + ε, ± Ω) and its clipped perturbation;
    ``scales`` (σ, β, √(1 − β²), Ω) float32, (σ, 0, 1, Ω) at the first step (ε = σ n).
    Returns (ε, the wheel speed, the clipped perturbation) [rad/s]."""
    noise_std, correlation, innovation, limit = scales
    smoothed = correlation * previous + innovation * (normal * noise_std)
    wheel = arena_clip(plan + smoothed, -limit, limit)
    return smoothed, wheel, wheel - plan


@elementwise
def arena_clip(value: Any, low: Any, high: Any) -> Any:
    """``value`` clipped to [``low``, ``high``], exactly, float32."""
    value = choose(value < low, low, value)
    return choose(value > high, high, value)


@elementwise
def level(position: Any, scale: Any, top: Any) -> Any:
    """The level ⌊``position`` · ``scale``⌋ of a position [m] clipped to [0, ``top``], float32
    (a cell or a slip region along x or y: ``scale`` (n − 1)/W [1/m], ``top`` n − 1)."""
    return arena_clip(np.floor(position * scale), _ZERO, top)


@elementwise
def sampled_twist(
    coefficients: tuple[Any, Any, Any, Any],
    wheels: tuple[Any, Any],
    model: tuple[Any, Any, Any, Any, Any],
    noise: tuple[Any, Any, Any],
    noise_scale: Any,
) -> tuple[Any, Any, Any]:
    """:func:`skidnav.agents.mpc.dynamics.sampled_twist` in float32, the same operations:
    ``coefficients`` a region's mean (8), factors (7), offsets (5) and noise (3) float32 rows,
    ``wheels`` (ω_L, ω_R) [rad/s], ``model`` the rollout's 5 and ``noise`` its step's 3
    standard normals. Returns (v_x [m/s], v_y [m/s], yaw_rate [rad/s])."""
    m, f, o, s = coefficients
    left, right = wheels
    d_left = f[0] * model[0]
    d_right = f[1] * model[0] + f[2] * model[1]
    v_x = m[0] * left + m[1] * right + m[2]
    v_x = v_x + (d_left * (left - o[0]) + d_right * (right - o[1]))
    d_left = f[3] * model[2]
    d_right = f[4] * model[2] + f[5] * model[3]
    yaw_rate = m[3] * left + m[4] * right + m[5]
    yaw_rate = yaw_rate + (d_left * (left - o[2]) + d_right * (right - o[3]))
    yaw_rate = yaw_rate + noise_scale * s[2] * noise[2]
    v_y = m[6] * yaw_rate + m[7] + f[6] * model[4] * (yaw_rate - o[4])
    v_x = v_x + noise_scale * s[0] * noise[0]
    v_y = v_y + noise_scale * s[1] * noise[1]
    return v_x, v_y, yaw_rate


@elementwise
def pose_step(
    pose: tuple[Any, Any, Any],
    twist: tuple[Any, Any, Any],
    dt: Any,
    exact: bool,
    arena: tuple[Any, Any],
) -> tuple[Any, Any, Any]:
    """:func:`skidnav.robot.kinematics.pose_step` in float32 (explicit Euler, or the exact
    constant-twist step with sin Δψ = 2 sin(Δψ/2) cos(Δψ/2) and 1 − cos Δψ = 2 sin²(Δψ/2),
    without cancellation), the position clipped to the arena (W, H) [m]; ``dt`` [s]."""
    x, y, heading = pose
    v_x, v_y, yaw_rate = twist
    turn = dt * yaw_rate
    if exact:
        half_sine, half_cosine = sin_cos(turn * _HALF)
        small = abs(turn) < F32(1e-9)
        safe = choose(small, _ONE, turn)
        sinc = choose(small, _ONE, _TWO * half_sine * half_cosine / safe)
        cosc = choose(small, _ZERO, _TWO * half_sine * half_sine / safe)
        forward, lateral = (v_x * sinc - v_y * cosc) * dt, (v_x * cosc + v_y * sinc) * dt
    else:
        forward, lateral = dt * v_x, dt * v_y
    sine, cosine = sin_cos(heading)
    new_x = arena_clip(x + (forward * cosine - lateral * sine), _ZERO, arena[0])
    new_y = arena_clip(y + (forward * sine + lateral * cosine), _ZERO, arena[1])
    return new_x, new_y, heading + turn
