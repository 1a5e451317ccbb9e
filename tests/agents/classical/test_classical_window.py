"""The classical navigator on a robot with inertia: its velocity from its own poses, the dynamic
window of the commands reachable from it (the whole range for a robot that takes any command at
once), and the recovery when it is stuck."""

from __future__ import annotations

import itertools
import math

import gymnasium
import numpy as np
import pytest

import skidnav
from skidnav.agents.classical.window import Odometry, ProgressCheck, window_commands
from skidnav.robot.kinematics import exact_step
from skidnav.world.barn import load_barn_world
from tests.agents.classical.support import JACKAL, barn_env

R, C, TOP = 0.098, 0.187795, 2.0 / 0.098
"""The Jackal's wheel radius [m], half track [m] and top wheel speed [rad/s]."""
PINCH = (2.622, 6.989, 0.795)
"""A pose [m, m, rad] on BARN world 0 between cylinders the padded footprint all but touches:
the MuJoCo Jackal ended there, and from there every motion touches at once, so standing still
is the controller's best admissible command."""


def twist(commands: np.ndarray, half_track: float = C) -> tuple[np.ndarray, np.ndarray]:
    """(v [m/s], ψ̇ [rad/s]) of wheel-speed commands (K, 2) by the ICR model without slip."""
    left, right = commands[:, 0], commands[:, 1]
    return R * (left + right) / 2, R * (right - left) / (2 * half_track)


def test_odometry_reads_the_velocity_from_successive_poses() -> None:
    odometry = Odometry(0.1)
    pose = (1.0, 2.0, 0.3)
    assert odometry.update(*pose) == (0.0, 0.0)  # at rest at the first pose
    for v, yaw_rate in ((1.5, 0.0), (1.0, 2.0), (-0.3, -1.0)):
        pose = exact_step(*pose, v, 0.0, yaw_rate, 0.1)
        speed, turn = odometry.update(*pose)
        half_turn = 0.05 * yaw_rate  # the chord of an arc: v sinc(ψ̇T/2) along the mean heading
        chord = v * math.sin(half_turn) / half_turn if yaw_rate else v
        assert speed == pytest.approx(chord, rel=1e-9)
        assert turn == pytest.approx(yaw_rate, rel=1e-9)


def test_the_window_holds_only_the_commands_reachable_within_a_period() -> None:
    commands = window_commands(
        (1.0, 0.5), (0.8, 1.0), R, C, TOP, (-0.3, 2.0), 4.0, (9, 21)
    )  # a = 8 m/s², α = 10 rad/s², T = 0.1 s
    v, yaw = twist(commands)
    assert v.max() == pytest.approx(1.8) and v.min() >= 0.2 - 1e-9
    assert yaw.max() == pytest.approx(1.5) and yaw.min() == pytest.approx(-0.5)
    assert 0.0 in yaw  # driving straight is among them
    at_rest = window_commands((0.0, 0.0), (0.8, 1.0), R, C, TOP, (-0.3, 2.0), 4.0, (9, 21))
    v, yaw = twist(at_rest)
    assert v.min() == pytest.approx(-0.3) and v.max() == pytest.approx(0.8)
    assert np.abs(yaw).max() == pytest.approx(1.0) and ((v == 0) & (yaw != 0)).any()  # turns
    whole = window_commands((0.0, 0.0), (math.inf, math.inf), R, C, TOP, (-0.3, 2.0), 4.0, (9, 21))
    v, yaw = twist(whole)
    assert v.max() == pytest.approx(2.0) and np.abs(yaw).max() == pytest.approx(4.0)


def test_a_robot_that_takes_any_command_at_once_has_the_whole_range() -> None:
    """Without acceleration limits the navigator searches the fixed samples every step; with
    them, from rest, only the slow commands: the first command is at most a T."""
    env = barn_env(0)
    observation, _ = env.reset(seed=0)
    instant = skidnav.make_agent("classical", env, **JACKAL)
    assert instant.greedy.reach == (math.inf, math.inf)
    v, _ = twist(instant.greedy_action(observation)[None, :])
    assert v[0] > 1.5  # full speed ahead at once
    limited = skidnav.make_agent("classical", env, **JACKAL, acceleration=4.0)
    speeds = []
    for _ in range(6):
        action = limited.greedy_action(observation)
        speeds.append(twist(action[None, :])[0][0])
        observation, *_ = env.step(action)
    assert speeds[0] <= 0.4 + 1e-9  # a T from rest
    assert all(b - a <= 0.4 + 1e-9 for a, b in itertools.pairwise(speeds))
    assert speeds[-1] > 1.5  # and on up to full speed


def pinched_env() -> gymnasium.Env[object, object]:
    """The kinematic Jackal on BARN world 0, starting at :data:`PINCH`."""
    world = load_barn_world(0)
    return gymnasium.make(
        "skidnav/SkidSteerNav-v0", grid_map=world.map.grid, discretization=world.discretization,
        start_pose=PINCH, goal_disc=(*world.goal, world.goal_radius), robot="jackal",
        control_period=0.1, action="continuous", observation="features", lidar_rays=271,
        lidar_range=10.0, lidar_fov=math.radians(270), slip="nominal",
    )  # fmt: skip


def test_the_recovery_moves_a_robot_that_stands_still_for_ever() -> None:
    """A robot that does not move whatever it is told (the same observation every period): in
    the pinch the controller stands still for ever without the progress check; with it, after
    ``stuck_time`` (2 s, 20 periods) the recovery moves a wheel for ``recovery_time`` (1 s)."""
    env = pinched_env()
    observation, _ = env.reset(seed=0)
    patient = skidnav.make_agent("classical", env, stuck_time=0.0)
    assert all(not patient.act(observation).any() for _ in range(40))
    agent = skidnav.make_agent("classical", env)
    actions = np.array([agent.act(observation) for _ in range(40)])
    moving = np.abs(actions).max(axis=1) > 0.5
    assert not moving[:20].any() and moving[20:30].all() and not moving[30:].any()
    assert agent.navigator.stuck == 1


def test_the_progress_check_looks_back_stuck_time() -> None:
    check = ProgressCheck(periods=3, distance=0.1)
    assert [check.stuck(0.0, 0.01 * k) for k in range(5)] == [False] * 3 + [True, True]
    check.reset()
    assert [check.stuck(0.05 * k, 0.0) for k in range(5)] == [False] * 5  # 0.15 m in 3
    assert not any(ProgressCheck(0, 1.0).stuck(0.0, 0.0) for _ in range(5))  # no check
