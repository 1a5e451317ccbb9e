"""The compiled navigation kernels give bit-identical results with and without the JIT."""

import hashlib
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

DIGEST_SCRIPT = """
import hashlib, numpy as np, skidnav
from skidnav.envs.navigation import SkidSteerNavEnv
from skidnav.kernels.navigation import simulate_batch
from skidnav.robot.params import RobotParams
parts = []
for integrator in ("euler", "exact"):
    env = SkidSteerNavEnv(map_kind="obstacles", world_seed=3, slip="slippery",
                          drift_amplitude=0.5, drift_period=7.0,
                          robot=RobotParams(integrator=integrator), variance="observed")
    env.reset(seed=11)
    for a in np.random.default_rng(2).integers(0, 4, 300):
        obs, reward, term, trunc, info = env.step(int(a))
        parts.append(np.array([*info["pose"], reward, obs], dtype=np.float64).tobytes())
        parts.append(info["kinematic_log"].tobytes())
        if term:
            env.reset()
    poses = np.tile(env.start_pose(), (64, 1))
    rewards = np.zeros(64); states = np.zeros(64, dtype=np.int64)
    actions = np.arange(64) % 4
    simulate_batch(env.task, poses, actions, 3.0, np.random.default_rng(5), rewards, states)
    parts += [poses.tobytes(), rewards.tobytes(), states.tobytes()]
print(hashlib.sha256(b"".join(parts)).hexdigest())
"""


def _digest(disable_jit: bool) -> str:
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).parents[2] / "src"))
    env["NUMBA_DISABLE_JIT"] = "1" if disable_jit else "0"
    result = subprocess.run(
        [sys.executable, "-c", DIGEST_SCRIPT], env=env, capture_output=True, text=True, check=True
    )
    return result.stdout.strip()


def test_trajectories_are_bit_identical_with_and_without_jit():
    compiled = _digest(disable_jit=False)
    interpreted = _digest(disable_jit=True)
    assert len(compiled) == 64
    assert compiled == interpreted


def test_draw_noise_matches_the_generator_vector_draw():
    from skidnav.kernels.navigation import draw_noise

    noise = np.empty(20)
    draw_noise(np.random.default_rng(9), noise)
    assert np.array_equal(noise, np.random.default_rng(9).random(20))
    assert (
        hashlib.sha256(noise.tobytes()).hexdigest()
        != hashlib.sha256(np.zeros(20).tobytes()).hexdigest()
    )
