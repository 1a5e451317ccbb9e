"""The Gymnasium env as agents see it: ``env.step`` of ``gymnasium.make("skidnav/SkidSteerNav-v0")``
(discrete observations, Gymnasium's wrappers included: TimeLimit, OrderEnforcing, the passive env
checker), a random policy, resets at every episode end. Prints the median of three timings, the
same env unwrapped, and the made env as plain Python (NUMBA_DISABLE_JIT=1, in a subprocess) as a
ratio, all measured in this run on one core."""

from __future__ import annotations

import statistics
import time

import gymnasium
import numpy as np
from plain_python import interpreted

import skidnav  # noqa: F401  (registers the env)

TARGET = 30_000
"""env.step through ``gymnasium.make``, steps/s."""
REPEATS = 3


def steps_per_second(n_steps: int, unwrapped: bool = False) -> float:
    """Steps/s of ``env.step`` on the obstacles map (world seed 0), after 500 warm-up steps."""
    env = gymnasium.make("skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=0)
    if unwrapped:
        env = env.unwrapped  # type: ignore[assignment]
    env.reset(seed=0)
    actions = [int(a) for a in np.random.default_rng(1).integers(0, 4, n_steps + 500)]
    step = env.step
    for action in actions[:500]:
        if any(step(action)[2:4]):
            env.reset()
    start = time.perf_counter()
    for action in actions[500:]:
        _, _, terminated, truncated, _ = step(action)
        if terminated or truncated:
            env.reset()
    return n_steps / (time.perf_counter() - start)


def median_rate(n_steps: int, unwrapped: bool = False) -> float:
    """Median of :data:`REPEATS` timings of :func:`steps_per_second`."""
    return statistics.median(steps_per_second(n_steps, unwrapped) for _ in range(REPEATS))


def interpreted_rate() -> float:
    """The made env's steps/s as plain Python (:func:`plain_python.interpreted`)."""
    return interpreted("bench_env", "steps_per_second(2_000)")


def main() -> None:
    made = median_rate(50_000)
    bare = median_rate(50_000, unwrapped=True)
    plain = interpreted_rate()
    print(
        f"env.step through gymnasium.make: {made:,.0f} steps/s (median of {REPEATS}), "
        f"{made / TARGET:.1f}x the target {TARGET:,}/s, {made / plain:,.0f}x plain Python "
        f"({plain:,.0f} steps/s)"
    )
    print(f"env.step unwrapped: {bare:,.0f} steps/s; Gymnasium's wrappers cost {bare / made:.2f}x")


if __name__ == "__main__":
    main()
