"""The env on the physical robot: ``env.step`` of ``gymnasium.make("skidnav/SkidSteerNav-v0",
dynamics="mujoco")`` on the obstacles arena (discrete observations, Gymnasium's wrappers
included), a random policy, resets at every episode end; the median of three timings, next to
the kinematic env's rate measured the same way in this run, on one core. Skipped (with a line
saying why) where MuJoCo is not installed."""

from __future__ import annotations

import statistics
import time

import gymnasium
import numpy as np

import skidnav  # noqa: F401  (registers the env)
from skidnav.physics.backend import PhysicsUnavailable, load_mujoco

TARGET = 100
"""env.step with ``dynamics="mujoco"`` through ``gymnasium.make``, actions/s (issue 14)."""
AIM = 300
"""The rate aimed at, actions/s."""
REPEATS = 3
STEPS = {"mujoco": 400, "kinematic": 50_000}
"""Timed actions per repeat for each dynamics."""
WARM_UP = 50


def steps_per_second(dynamics: str, n_steps: int) -> float:
    """Actions/s of ``env.step`` on the obstacles map (world seed 0) with ``dynamics``, after
    :data:`WARM_UP` warm-up actions."""
    env = gymnasium.make(
        "skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=0, dynamics=dynamics
    )
    env.reset(seed=0)
    actions = [int(a) for a in np.random.default_rng(1).integers(0, 4, n_steps + WARM_UP)]
    step = env.step
    for action in actions[:WARM_UP]:
        if any(step(action)[2:4]):
            env.reset()
    start = time.perf_counter()
    for action in actions[WARM_UP:]:
        _, _, terminated, truncated, _ = step(action)
        if terminated or truncated:
            env.reset()
    return n_steps / (time.perf_counter() - start)


def median_rate(dynamics: str) -> float:
    """Median of :data:`REPEATS` timings of :func:`steps_per_second`."""
    n_steps = STEPS[dynamics]
    return statistics.median(steps_per_second(dynamics, n_steps) for _ in range(REPEATS))


def main() -> None:
    try:
        load_mujoco()
    except PhysicsUnavailable as error:
        print(f"skipped: {error}")
        return
    physics = median_rate("mujoco")
    kinematic = median_rate("kinematic")
    print(
        f"env.step with dynamics='mujoco' through gymnasium.make (obstacles arena): "
        f"{physics:,.0f} actions/s (median of {REPEATS}), {physics / TARGET:.2f}x the target "
        f"{TARGET}/s, {physics / AIM:.2f}x the aim {AIM}/s"
    )
    print(
        f"kinematic env.step, same run: {kinematic:,.0f} actions/s; the physics costs "
        f"{kinematic / physics:,.0f}x"
    )


if __name__ == "__main__":
    main()
