"""The Gymnasium env: API contract, dynamics, rewards, episode end, determinism, rendering."""

import math

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import skidnav  # noqa: F401  (registers the env)
from skidnav.envs.navigation import SkidSteerNavEnv
from skidnav.robot.slip import SlipField, make_slip_field
from skidnav.world.colours import GOAL, START
from skidnav.world.discretization import Discretization
from skidnav.world.mapfile import parse_map

CORRIDOR = (
    """skidnav-map 1
width 25
height 25
map
"""
    + "\n".join(
        ["#" * 25] * 9
        + ["#" + "." * 23 + "#"] * 3
        + ["#..S" + "." * 12 + "G" + "." * 7 + "#"]  # j = 12: start (3, 12), goal (16, 12)
        + ["#" + "." * 23 + "#"] * 3
        + ["#" * 25] * 9
    )
    + "\n"
)


def no_slip() -> SlipField:
    return SlipField(eta=np.zeros((7, 7)), x_icr=np.full((7, 7), 0.05))


def make_env(**kwargs) -> SkidSteerNavEnv:
    kwargs.setdefault("grid_map", parse_map(CORRIDOR))
    kwargs.setdefault("slip_field", no_slip())
    return SkidSteerNavEnv(**kwargs)


@pytest.mark.filterwarnings("ignore:.*different from the unwrapped")
def test_check_env_passes_on_the_registered_env():
    env = gymnasium.make("skidnav/SkidSteerNav-v0", render_mode="rgb_array")
    check_env(env.unwrapped)
    check_env(env)
    assert env.observation_space.n == 12_500 and env.action_space.n == 4


def test_forward_action_moves_r_times_wheel_speed_without_slip():
    env = make_env()
    env.reset(seed=0)
    x0 = env.pose[0]
    _, reward, terminated, truncated, info = env.step(0)
    assert env.pose[0] - x0 == pytest.approx(0.0225 * 1.7, rel=1e-12)
    assert reward == -1.0 and not terminated and not truncated and not info["collision"]
    assert info["kinematic_log"].shape == (10, 6)
    np.testing.assert_allclose(info["kinematic_log"][:, 1:4], [[1.7, 1.7, 0.03825]] * 10)


def test_turn_rotates_and_slides_the_body():
    env = make_env()
    env.reset(seed=0)
    start = env.pose.copy()
    env.step(2)
    assert env.pose[2] == pytest.approx(0.6375)
    assert math.hypot(*(env.pose[:2] - start[:2])) == pytest.approx(0.032, abs=2e-3)


def test_collision_stops_the_robot_at_its_last_free_cell():
    env = make_env()
    env.reset(seed=0)
    env.step(2)
    env.step(2)  # facing up-left, ~73°, towards the wall two cells above
    collided = False
    for _ in range(6):
        _, reward, _, _, info = env.step(0)
        i, j = info["cell"][:2]
        assert not env.grid_map.occupancy[i, j]
        if info["collision"]:
            collided = True
            assert reward == -10.0
            assert len(info["kinematic_log"]) < 10
            break
    assert collided


def test_goal_terminates_with_plus_ten_and_truncation_is_separate():
    env = make_env()
    env.reset(seed=0)
    rewards, terminated = [], False
    while not terminated:
        _, reward, terminated, truncated, info = env.step(0)
        rewards.append(reward)
        assert not truncated
    assert rewards[-1] == 10.0 and all(r == -1.0 for r in rewards[:-1])
    assert info["cell"][:2] == env.grid_map.goal
    short = gymnasium.wrappers.TimeLimit(make_env(), 3)
    short.reset(seed=0)
    outcomes = [short.step(1)[2:4] for _ in range(3)]
    assert outcomes == [(False, False), (False, False), (False, True)]


def test_the_env_itself_never_truncates():
    env = make_env()
    env.reset(seed=0)
    flags = [env.step(1)[2:4] for _ in range(700)]  # backwards into the wall, away from the goal
    assert set(flags) == {(False, False)}
    assert not hasattr(env, "max_episode_steps")


@pytest.mark.parametrize(("override", "limit"), [({}, 500), ({"max_episode_steps": 1000}, 1000)])
def test_time_limit_is_registered_and_overridable_through_make(override, limit):
    env = gymnasium.make(
        "skidnav/SkidSteerNav-v0", grid_map=parse_map(CORRIDOR), slip="slippery", **override
    )
    assert env.spec.max_episode_steps == limit
    assert gymnasium.spec("skidnav/SkidSteerNav-v0").max_episode_steps == 500
    env.reset(seed=0)
    flags = [env.step(1)[2:4] for _ in range(limit)]  # backwards, away from the goal
    assert flags[-1] == (False, True)
    assert set(flags[:-1]) == {(False, False)}


def test_a_goal_on_the_last_allowed_action_is_terminated_and_truncated():
    env = gymnasium.wrappers.TimeLimit(make_env(), 9)  # forward reaches the goal at action 9
    env.reset(seed=0)
    flags = [env.step(0)[2:4] for _ in range(9)]
    assert flags[-1] == (True, True)  # Gymnasium's convention: agents check terminated first
    assert set(flags[:-1]) == {(False, False)}


def test_step_penalty_is_the_true_region_variance_on_a_slippery_floor():
    slip = make_slip_field("slippery", np.random.default_rng(0))
    env = make_env(slip_field=slip)
    env.reset(seed=0)
    _, reward, _, _, info = env.step(1)
    region_i, region_j = divmod(info["region"], 7)
    variance = slip.eta[region_i, region_j] ** 2 / 12
    assert reward == pytest.approx(-1.0 - 10.0 * variance)


def test_observed_variance_is_learned_from_forward_actions():
    slip = SlipField(eta=np.full((7, 7), 1.0), x_icr=np.full((7, 7), 0.05))
    env = make_env(slip_field=slip, variance="observed")
    env.reset(seed=3)
    _, reward, _, _, _ = env.step(3)  # no forward action yet: nothing observed
    assert reward == -1.0
    for _ in range(30):
        env.step(0)
        env.step(1)
    stats = env.task.variance_stats
    region = env.discretization.region(*env.pose[:2])
    assert stats[region, 0] > 20
    assert stats[region, 2] / (stats[region, 0] - 1) == pytest.approx(1.0 / 12, rel=0.5)


def test_same_seed_same_trajectory_and_other_seeds_differ():
    def run(seed):
        env = gymnasium.make("skidnav/SkidSteerNav-v0", slip="slippery", world_seed=4)
        env.reset(seed=seed)
        actions = np.random.default_rng(0).integers(0, 4, 60)
        return np.array([env.step(int(a))[4]["pose"] for a in actions])

    assert np.array_equal(run(5), run(5))
    assert not np.array_equal(run(5), run(6))


def test_pose_observation_and_rendering():
    env = make_env(observation="pose", render_mode="rgb_array")
    observation, _ = env.reset(seed=0)
    assert env.observation_space.contains(observation)
    env.step(0)
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
    assert (frame == GOAL).all(axis=2).any() and (frame == START).all(axis=2).any()
    text = make_env(render_mode="ansi")
    text.reset(seed=0)
    rows = text.render().splitlines()
    assert len(rows) == 25 and "G" in rows[12] and "→" in rows[12]


def test_drift_scales_eta_only_so_x_icr_stays_within_the_axles():
    env = SkidSteerNavEnv(
        map_kind="free", world_seed=4, slip="slippery", drift_amplitude=2.0, drift_period=3.0
    )
    env.reset(seed=0)
    x_icr = env.slip_field.x_icr.ravel()
    assert np.all((-env.robot.front_axle <= x_icr) & (x_icr <= env.robot.rear_axle))
    for action in [2, 3, 0] * 10:  # turns at every drift phase: v_y = −x_ICR(region) · yaw_rate
        log = env.step(action)[4]["kinematic_log"]
        regions = log[:, 0].astype(int)
        np.testing.assert_allclose(log[:, 4], -x_icr[regions] * log[:, 5], atol=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"observation": "image"}, "observation"),
        ({"variance": "guess"}, "variance"),
        (
            {"slip_field": SlipField(eta=np.zeros((7, 7)), x_icr=np.full((7, 7), -0.06))},
            r"expected x_icr in \[-a, b\] = \[-0.05, 0.05\] m in every region, got -0.06 m",
        ),
        (
            {"discretization": Discretization(arena_width=1.0, arena_height=0.505)},
            r"expected the discretization's arena 1 × 0.505 m to be the robot's 0.62 × 0.505 m",
        ),
    ],
)
def test_bad_arguments(kwargs, message):
    with pytest.raises(ValueError, match=message):
        make_env(**kwargs)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    world_seed=st.integers(0, 10_000),
    kind=st.sampled_from(["obstacles", "maze", "free"]),
    preset=st.sampled_from(["thesis", "slippery", "rough"]),
    integrator=st.sampled_from(["euler", "exact"]),
    actions=st.lists(st.integers(0, 3), min_size=1, max_size=80),
)
def test_pose_never_leaves_the_arena_nor_ends_in_a_wall(
    world_seed, kind, preset, integrator, actions
):
    from skidnav.robot.params import RobotParams

    env = SkidSteerNavEnv(
        map_kind=kind,
        world_seed=world_seed,
        slip=preset,
        robot=RobotParams(integrator=integrator),
        drift_amplitude=0.5,
        drift_period=5.0,
    )
    env.reset(seed=world_seed)
    for action in actions:
        _, _, terminated, _, info = env.step(action)
        x, y, _ = info["pose"]
        assert 0.0 <= x <= 0.62 and 0.0 <= y <= 0.505
        i, j, _ = info["cell"]
        assert not env.grid_map.occupancy[i, j]
        if terminated:
            break
