"""The compiled navigation kernels give bit-identical results with and without the JIT."""

import hashlib
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

from skidnav.envs.navigation import SkidSteerNavEnv

DIGEST_SCRIPT = """
import hashlib, numpy as np, skidnav
from skidnav.envs.navigation import SkidSteerNavEnv
from skidnav.envs.vector import SkidSteerNavVectorEnv
from skidnav.sim.navigation import simulate_batch
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
    vector = SkidSteerNavVectorEnv(16, 30, map_kind="obstacles", world_seed=3, slip="slippery",
                                   robot=RobotParams(integrator=integrator), variance="observed",
                                   observation="features", action="continuous")
    vector.reset(seed=4)
    for commands in np.random.default_rng(3).uniform(-2, 2, (60, 16, 2)):
        observations, rewards, terminated, truncated, _ = vector.step(commands)
        parts += [observations.tobytes(), rewards.tobytes(), terminated.tobytes()]
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
    from skidnav.sim.navigation import draw_noise

    noise = np.empty(20)
    draw_noise(np.random.default_rng(9), noise)
    assert np.array_equal(noise, np.random.default_rng(9).random(20))
    assert (
        hashlib.sha256(noise.tobytes()).hexdigest()
        != hashlib.sha256(np.zeros(20).tobytes()).hexdigest()
    )


def _slippery_env(variance: str = "observed") -> SkidSteerNavEnv:
    return SkidSteerNavEnv(map_kind="obstacles", world_seed=3, slip="slippery",
                           drift_amplitude=0.5, drift_period=7.0, variance=variance)  # fmt: skip


def _free_poses(env: SkidSteerNavEnv, n: int, rng: np.random.Generator) -> np.ndarray:
    """Centres of random free cells with random headings [rad], shape (n, 3)."""
    cells = np.argwhere(env.grid_map.as_uint8() == 0)
    chosen = cells[rng.integers(0, len(cells), n)]
    centres = [env.discretization.cell_centre(int(i), int(j)) for i, j in chosen]
    return np.column_stack([np.array(centres), rng.uniform(-4.0, 4.0, n)])


def test_batch_is_transition_robot_by_robot() -> None:
    from skidnav.sim.navigation import draw_noise, simulate_batch, transition

    batch_env, loop_env = _slippery_env(), _slippery_env()
    poses = _free_poses(batch_env, 300, np.random.default_rng(4))
    actions = np.random.default_rng(6).integers(0, 4, 300)
    rewards, states = np.zeros(300), np.zeros(300, dtype=np.int64)
    batch_poses = poses.copy()
    collisions = simulate_batch(
        batch_env.task, batch_poses, actions, 2.0, np.random.default_rng(8), rewards, states
    )
    rng, noise, log = np.random.default_rng(8), np.empty(20), np.empty((10, 6))
    expected_collisions = 0
    for k in range(300):
        pose = poses[k].copy()
        draw_noise(rng, noise)
        outcome = transition(loop_env.task, pose, int(actions[k]), 2.0, noise, log)
        assert pose.tobytes() == batch_poses[k].tobytes()
        assert (outcome.reward, outcome.state) == (rewards[k], states[k])
        expected_collisions += outcome.collided
    assert collisions == expected_collisions > 0
    assert loop_env.task.variance_stats.tobytes() == batch_env.task.variance_stats.tobytes()


def test_log_replays_to_the_pose_with_the_region_of_each_substep_start() -> None:
    from skidnav.robot.kinematics import euler_step
    from skidnav.sim.navigation import draw_noise, transition

    env = _slippery_env(variance="true")
    robot, grid = env.robot, env.discretization
    rng, noise, log = np.random.default_rng(1), np.empty(20), np.empty((10, 6))
    poses = _free_poses(env, 200, np.random.default_rng(2))
    for k, action in enumerate(np.random.default_rng(3).integers(0, 4, 200)):
        pose = poses[k].copy()
        x, y, heading = pose
        draw_noise(rng, noise)
        outcome = transition(env.task, pose, int(action), 0.5 * k, noise, log)
        for region, _, _, v_x, v_y, yaw_rate in log[: outcome.n_logged]:
            assert region == grid.region(x, y)
            x, y, heading = euler_step(x, y, heading, v_x, v_y, yaw_rate, robot.dt)
            x = min(max(x, 0.0), robot.arena_width)
            y = min(max(y, 0.0), robot.arena_height)
        assert (x, y) == (pose[0], pose[1])
        assert outcome.region == grid.region(x, y)
        assert outcome.state == grid.state(*pose)


def test_task_arrays_give_back_the_task() -> None:
    from skidnav.robot.params import RobotParams
    from skidnav.sim.task import task_arrays, task_from_arrays

    env = SkidSteerNavEnv(map_kind="maze", world_seed=2, slip="slippery", drift_amplitude=0.3,
                          robot=RobotParams(integrator="exact"), variance="observed")  # fmt: skip
    rebuilt = task_from_arrays(*task_arrays(env.task))
    for name, value in env.task._asdict().items():
        copy = getattr(rebuilt, name)
        if isinstance(value, np.ndarray):
            assert np.shares_memory(copy, value), name  # the kernel updates the task's arrays
        else:
            assert copy == value, name
    assert rebuilt.robot.exact_integration and rebuilt.rewards.observed_variance


def test_step_arrays_is_transition() -> None:
    from skidnav.robot.kinematics import commanded_wheel_speeds
    from skidnav.sim.navigation import draw_noise, transition
    from skidnav.sim.task import step_arrays, task_arrays

    fast_env, env = _slippery_env(), _slippery_env()
    poses = _free_poses(env, 100, np.random.default_rng(4))
    arrays = task_arrays(fast_env.task)
    rng, noise = np.random.default_rng(8), np.empty(20)
    log, fast_log = np.empty((10, 6)), np.empty((10, 6))
    for k, action in enumerate(np.random.default_rng(6).integers(0, 4, 100)):
        pose, fast_pose = poses[k].copy(), poses[k].copy()
        draw_noise(rng, noise)
        outcome = transition(env.task, pose, int(action), 0.3 * k, noise, log)
        commands = commanded_wheel_speeds(int(action), env.robot.wheel_speed)
        fast = step_arrays(*arrays, fast_pose, *commands, 0.3 * k, noise, fast_log)
        assert fast == tuple(outcome)
        assert pose.tobytes() == fast_pose.tobytes()
        assert log[: outcome.n_logged].tobytes() == fast_log[: outcome.n_logged].tobytes()
    assert env.task.variance_stats.tobytes() == fast_env.task.variance_stats.tobytes()


def test_drive_substep_is_the_actions_substep() -> None:
    """Driven sub-step by sub-step with an action's wheel speeds, a robot follows the action's
    logged path exactly, with either integrator, until a wall stops it."""
    from skidnav.robot.kinematics import commanded_wheel_speeds
    from skidnav.robot.params import RobotParams
    from skidnav.sim.navigation import transition
    from skidnav.sim.task import drive_substep

    for integrator in ("euler", "exact"):
        env = SkidSteerNavEnv(map_kind="obstacles", world_seed=3, slip="slippery",
                              drift_amplitude=0.5, drift_period=7.0,
                              robot=RobotParams(integrator=integrator))  # fmt: skip
        rng, log, collisions = np.random.default_rng(1), np.empty((10, 6)), 0
        for k, pose in enumerate(_free_poses(env, 150, np.random.default_rng(2))):
            action, noise = k % 4, rng.random(20)
            driven = tuple(float(v) for v in pose)
            end = pose.copy()
            outcome = transition(env.task, end, action, 0.5 * k, noise, log)
            commands = commanded_wheel_speeds(action, env.robot.wheel_speed)
            for step in range(outcome.n_logged + int(outcome.collided)):
                time = 0.5 * k + step * env.robot.dt
                left, right = noise[2 * step], noise[2 * step + 1]
                driven = drive_substep(env.task, driven, commands, time, left, right)
            assert driven == tuple(end)
            collisions += outcome.collided
        assert collisions > 0
