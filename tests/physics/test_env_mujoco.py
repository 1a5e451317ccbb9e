"""``SkidSteerNav-v0`` with ``dynamics="mujoco"``: the navigation MDP's rules on the physical
robot (skidnav.physics.mdp), measured with tolerances where the physics decides."""

from __future__ import annotations

import math
import types
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("mujoco")

from gymnasium.utils.env_checker import check_env

import skidnav.envs  # noqa: F401  (registers the env)
from skidnav.agents.greedy import greedy_rollout
from skidnav.agents.tabular.fast_training import FusedEnv
from skidnav.agents.tabular.registry import make_agent
from skidnav.agents.training import train_agent
from skidnav.physics import backend
from skidnav.physics.backend import PhysicsUnavailable
from skidnav.robot.kinematics import body_velocities
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SlipField
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap, border_walls

ENV_ID = "skidnav/SkidSteerNav-v0"
SMALL_ROBOT = RobotParams(arena_width=0.3, arena_height=0.3)
SMALL_GRID = Discretization(n_x=10, n_y=10, n_headings=10, arena_width=0.3, arena_height=0.3)
SMALL_MAP = GridMap(border_walls((10, 10)), start=(2, 2), goal=(5, 3))
"""A 0.3 m × 0.3 m walled arena of 10 × 10 cells, the goal 3 cells ahead of the start."""


def small_env(**options: Any) -> Any:
    """The mujoco env on :data:`SMALL_MAP` (made, with Gymnasium's wrappers)."""
    kwargs: dict[str, Any] = dict(
        dynamics="mujoco", grid_map=SMALL_MAP, world_seed=3, robot=SMALL_ROBOT,
        discretization=SMALL_GRID, max_episode_steps=150,
    )  # fmt: skip
    kwargs.update(options)
    return gym.make(ENV_ID, **kwargs)


def spy_substeps(env: Any, monkeypatch: pytest.MonkeyPatch) -> list[tuple[Any, ...]]:
    """Record (pose after, set points, twist) of every sub-step of the env's MuJoCo robot."""
    body = env.unwrapped.physics_robot
    original = body.substep
    records: list[tuple[Any, ...]] = []

    def substep(*args: Any) -> Any:
        set_points, twist = original(*args)
        records.append((body.pose, set_points, twist))
        return set_points, twist

    monkeypatch.setattr(body, "substep", substep)
    return records


def test_check_env_passes() -> None:
    check_env(small_env().unwrapped, skip_render_check=True)


def test_same_spaces_as_the_kinematic_env() -> None:
    for observation in ("discrete", "pose"):
        options = dict(map_kind="obstacles", world_seed=2, observation=observation)
        physics = gym.make(ENV_ID, dynamics="mujoco", **options)
        kinematic = gym.make(ENV_ID, **options)
        assert physics.observation_space == kinematic.observation_space
        assert physics.action_space == kinematic.action_space
        assert physics.spec.max_episode_steps == kinematic.spec.max_episode_steps  # type: ignore[union-attr]


def test_same_seed_same_trajectory() -> None:
    actions = [int(a) for a in np.random.default_rng(4).integers(0, 4, 25)]
    runs = []
    for _ in range(2):
        env = small_env(slip="slippery")
        env.reset(seed=11)
        runs.append([(env.step(a)[1], env.unwrapped.pose.tolist()) for a in actions])
    assert runs[0] == runs[1]
    assert len({tuple(pose) for _, pose in runs[0]}) > 10  # it did move


def test_a_forward_action_moves_r_omega_t() -> None:
    no_slip = SlipField(eta=np.zeros((7, 7)), x_icr=np.full((7, 7), 0.05))
    env = gym.make(ENV_ID, dynamics="mujoco", map_kind="free", world_seed=1,
                   slip_field=no_slip, floor="rubber-mat")  # fmt: skip
    env.reset(seed=0)
    start = env.unwrapped.pose.copy()
    _, reward, _, _, info = env.step(0)
    moved = env.unwrapped.pose - start
    robot = env.unwrapped.robot
    expected = robot.wheel_radius * robot.wheel_speed * robot.action_duration  # 3.825 cm
    assert moved[0] == pytest.approx(expected, rel=0.03)  # from rest: the servos spin up
    assert abs(moved[1]) < 1e-3 and abs(moved[2]) < 0.01
    assert info["wheel_speeds"] == pytest.approx((1.7, 1.7), rel=0.02)  # measured
    assert reward == -1.0 and not info["collision"]


def test_a_wall_stops_the_robot_at_its_last_free_substep(monkeypatch: pytest.MonkeyPatch) -> None:
    env = small_env()
    env.reset(seed=0)
    records = spy_substeps(env, monkeypatch)
    grid, walls = env.unwrapped.discretization, SMALL_MAP.occupancy
    for _ in range(20):  # facing +x: 6 free cells ahead, then the border
        del records[:]
        _, reward, terminated, _, info = env.step(0)
        if info["collision"]:
            break
    assert info["collision"] and not terminated and reward == -10.0
    n_free = info["kinematic_log"].shape[0]
    assert n_free < len(records) <= 10  # the colliding sub-step ended the action
    x, y, heading = env.unwrapped.pose
    assert walls[grid.cell(*records[n_free][0][:2])]  # the colliding sub-step's position
    if n_free:
        assert (x, y) == records[n_free - 1][0][:2]  # the last free position
    assert math.cos(heading - records[n_free][0][2]) == pytest.approx(1.0, abs=1e-12)
    assert not walls[grid.cell(x, y)]
    body = env.unwrapped.physics_robot
    assert body.body_twist() == (0.0, 0.0, 0.0) and body.wheel_speeds() == (0.0, 0.0)


def test_the_kinematic_log_holds_the_measured_twist(monkeypatch: pytest.MonkeyPatch) -> None:
    env = small_env(floor="laminate")
    env.reset(seed=0)
    records = spy_substeps(env, monkeypatch)
    _, _, _, _, info = env.step(2)  # turn left in place
    log = info["kinematic_log"]
    assert log.shape == (10, 6)
    np.testing.assert_array_equal(log[:, 3:], np.array([twist for _, _, twist in records]))
    np.testing.assert_array_equal(log[:, 1:3], np.tile([-1.7, 1.7], (10, 1)))  # commanded
    region = env.unwrapped.discretization.region(*env.unwrapped.start_pose()[:2])
    assert np.all(log[:, 0] == region)
    robot = env.unwrapped.robot
    icr_yaw = body_velocities(-1.7, 1.7, robot.x_icr, robot.wheel_radius, robot.half_track)[2]
    assert 0.0 < log[5:, 5].mean() < 0.8 * icr_yaw  # the physics turns slower than the ICR model


def test_observed_variance_records_forward_set_points(monkeypatch: pytest.MonkeyPatch) -> None:
    env = small_env(slip="slippery", variance="observed")
    env.reset(seed=0)
    records = spy_substeps(env, monkeypatch)
    stats = env.unwrapped.task.variance_stats
    env.step(2)
    assert not stats.any()  # turns are not recorded
    _, _, _, _, info = env.step(0)
    speeds = np.array([set_points for _, set_points, _ in records[10:]]).ravel()
    n_free = info["kinematic_log"].shape[0]
    assert stats[:, 0].sum() == 2 * n_free
    assert stats[:, 1] @ stats[:, 0] == pytest.approx(speeds[: 2 * n_free].sum())


def test_learning_on_physics_reaches_the_goal() -> None:
    env, evaluation = small_env(), small_env()
    assert FusedEnv.find(env) is None  # the fused trainer falls back to train_agent
    assert FusedEnv.find(small_env(dynamics="kinematic")) is not None
    config = {"epsilon": 0.2, "planning_steps": 20}
    agent = make_agent("dyna-q", SMALL_GRID.n_states, 4, config, np.random.default_rng(17))
    log = train_agent(agent, env, 8, max_steps=150, seed=23)
    assert log.successes[-3:].all()
    assert 0 < greedy_rollout(agent, evaluation, 40, seed=5) <= 12


def test_bad_options_are_one_line_errors() -> None:
    for options, words in (
        ({"dynamics": "rigid"}, "expected dynamics"),
        ({"floor": "lava"}, "expected floor"),
        ({"dynamics": "kinematic", "floor": "laminate"}, "expected floor=None"),
    ):
        with pytest.raises(ValueError, match=words) as error:
            small_env(**options)
        assert "\n" not in str(error.value)


def test_without_mujoco_the_error_is_one_line(monkeypatch: pytest.MonkeyPatch) -> None:
    def missing(name: str) -> Any:
        raise ImportError(f"No module named {name!r}")

    backend.load_mujoco.cache_clear()
    monkeypatch.setattr(backend, "importlib", types.SimpleNamespace(import_module=missing))
    try:
        with pytest.raises(PhysicsUnavailable) as error:
            small_env()
        small_env(dynamics="kinematic").reset(seed=0)  # the default needs no MuJoCo
    finally:
        backend.load_mujoco.cache_clear()
    assert "\n" not in str(error.value) and backend.INSTALL_HINT in str(error.value)
