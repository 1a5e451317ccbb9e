"""Same seed, same numbers: seeded rollouts through ``gymnasium.make`` hash to the value recorded
before the env's step was restructured (one step info, TimeLimit-owned truncation)."""

from __future__ import annotations

import hashlib
from typing import Any

import gymnasium
import numpy as np

import skidnav  # noqa: F401  (registers the env)
from skidnav.robot.params import RobotParams

EXPECTED_DIGEST = "5bb03b6c37c896cf303fe18f2c5859816b1edaf9a644b6678163dddb40d0d7e2"
"""sha256 of :func:`rollout_bytes`, computed with the code before the change."""

SETUPS: tuple[dict[str, Any], ...] = (
    {"map_kind": "obstacles", "world_seed": 3, "slip": "slippery"},
    {"map_kind": "free", "world_seed": 5, "slip": "thesis", "max_episode_steps": 120},
    {
        "map_kind": "maze",
        "world_seed": 7,
        "slip": "slippery",
        "drift_amplitude": 0.5,
        "drift_period": 7.0,
        "variance": "observed",
        "robot": RobotParams(integrator="exact"),
    },
    {"map_kind": "obstacles", "world_seed": 1, "slip": "rough", "observation": "pose"},
)
"""Env options: both integrators, drifting slip, observed variance, both observations, the
registered time limit and an override of it."""


def _step_bytes(step: tuple[Any, ...]) -> bytes:
    observation, reward, terminated, truncated, info = step
    numbers = [
        *np.ravel(np.asarray(observation, dtype=np.float64)),
        reward,
        terminated,
        truncated and not terminated,  # Gymnasium's TimeLimit also flags a goal at the limit
        *info["pose"],
        *info["cell"],
        info["collision"],
        *info["wheel_speeds"],
        info["region"],
    ]
    return np.array(numbers, dtype=np.float64).tobytes() + info["kinematic_log"].tobytes()


def rollout_bytes(options: dict[str, Any], episodes: int = 3) -> bytes:
    """Random actions from a seeded generator until ``episodes`` episodes ended (terminated or
    truncated); every step's observation, reward, flags and info as bytes."""
    env = gymnasium.make("skidnav/SkidSteerNav-v0", **options)
    actions = np.random.default_rng(2)
    parts = []
    observation, _ = env.reset(seed=11)
    parts.append(np.asarray(observation, dtype=np.float64).tobytes())
    for _ in range(episodes):
        while True:
            step = env.step(int(actions.integers(4)))
            parts.append(_step_bytes(step))
            if step[2] or step[3]:
                break
        observation, _ = env.reset()
        parts.append(np.asarray(observation, dtype=np.float64).tobytes())
    return b"".join(parts)


def test_seeded_rollouts_are_unchanged() -> None:
    digest = hashlib.sha256(b"".join(rollout_bytes(options) for options in SETUPS)).hexdigest()
    assert digest == EXPECTED_DIGEST
