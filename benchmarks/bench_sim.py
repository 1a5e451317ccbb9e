"""Simulator speed: the compiled batch kernel and the Gymnasium API, each as a ratio against the
same sub-step loop run as plain Python (the identical code under NUMBA_DISABLE_JIT=1), measured in
the same run. Prints one line per figure."""

from __future__ import annotations

import time

import numpy as np
from plain_python import interpreted

from skidnav.envs.navigation import SkidSteerNavEnv
from skidnav.sim.navigation import simulate_batch

TARGET_BATCH = 1_000_000
TARGET_API = 30_000


def batch_actions_per_second(n_robots: int, repeats: int) -> float:
    """Actions/s of :func:`simulate_batch` (10 sub-steps each), best of ``repeats``, one core."""
    env = SkidSteerNavEnv(map_kind="free", world_seed=0, slip="slippery")
    rng = np.random.default_rng(0)
    actions = rng.integers(0, 4, n_robots)
    rewards, states = np.zeros(n_robots), np.zeros(n_robots, dtype=np.int64)
    best = 0.0
    for _ in range(repeats + 1):  # the first round compiles (or warms up)
        poses = np.tile(env.start_pose(), (n_robots, 1))
        start = time.perf_counter()
        simulate_batch(env.task, poses, actions, 0.0, rng, rewards, states)
        best = max(best, n_robots / (time.perf_counter() - start))
    return best


def api_steps_per_second(n_steps: int) -> float:
    """Steps/s through ``env.step`` with a random policy."""
    env = SkidSteerNavEnv(map_kind="obstacles", world_seed=0)
    env.reset(seed=0)
    actions = np.random.default_rng(1).integers(0, 4, n_steps + 500)
    for action in actions[:500]:
        env.step(int(action))
    start = time.perf_counter()
    for action in actions[500:]:
        if env.step(int(action))[2]:
            env.reset()
    return n_steps / (time.perf_counter() - start)


def interpreted_actions_per_second() -> float:
    """The batch kernel's actions/s as plain Python (:func:`plain_python.interpreted`)."""
    return interpreted("bench_sim", "batch_actions_per_second(2_000, 1)")


def main() -> None:
    plain = interpreted_actions_per_second()
    batch = batch_actions_per_second(400_000, 3)
    api = api_steps_per_second(40_000)
    print(f"simulator plain Python (NUMBA_DISABLE_JIT=1): {plain:,.0f} actions/s")
    print(
        f"simulator batch kernel: {batch:,.0f} actions/s (10 sub-steps each, one core), "
        f"{batch / plain:,.0f}x plain Python (targets: >= {TARGET_BATCH:,}/s, >= 50x)"
    )
    print(
        f"Gymnasium API env.step: {api:,.0f} steps/s, {api / plain:,.1f}x plain-Python kernel "
        f"(target: >= {TARGET_API:,}/s)"
    )


if __name__ == "__main__":
    main()
