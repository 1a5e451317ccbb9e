"""Homing on the simulated robot, kinematic log rows from poses, rewards, wheel-speed stats."""

from __future__ import annotations

import itertools
import math
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

from skidnav.realtime.arena import arena_map, seed_streams, start_pose
from skidnav.realtime.config import load_config
from skidnav.realtime.control.episodes import EpisodeLoop
from skidnav.realtime.control.homing import HomingController
from skidnav.realtime.control.transition import IcrEstimates, WheelSpeedStats, log_row, reward_of
from skidnav.realtime.link.interface import Pose
from skidnav.realtime.robot_server.simulated_robot import SimRobot, SimRobotConfig, build_robot
from skidnav.robot.kinematics import body_velocities, euler_step
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization

GRID = Discretization()


@pytest.mark.parametrize(
    ("spec", "slip", "seed"),
    [("free", "rough", 0), ("obstacles", "slippery", 1), ("obstacles", "rough", 3)],
)
def test_homing_brings_the_robot_to_the_start_state(spec: str, slip: str, seed: int) -> None:
    robot = build_robot(
        slip=slip,
        drift=0.0,
        drift_period=600.0,
        map_spec=spec,
        seed=seed,
        config=SimRobotConfig(pose_noise=0.001),
    )
    grid_map = arena_map(spec, seed, GRID)
    rng = np.random.default_rng(seed)
    free = np.argwhere(~grid_map.occupancy)
    i, j = free[int(rng.integers(len(free)))]
    robot.pose = (*GRID.cell_centre(int(i), int(j)), float(rng.uniform(-3, 3)))
    home(robot, HomingController(grid_map, GRID, 1.7, tolerance=0.008))
    assert GRID.state(*robot.pose) == GRID.state(*start_pose(grid_map, GRID))


def home(robot: SimRobot, controller: HomingController) -> None:
    """Drive ``robot`` with ``controller`` until it is home; fail after 300 s of robot time."""
    for _ in range(3000):
        measured = robot.measured_pose()
        assert measured is not None
        command = controller.command(Pose(0.0, *measured))
        if command is None:
            return
        robot.command(*command)
        robot.step()
    pytest.fail("homing did not finish in 300 s of robot time")


def test_log_row_recovers_the_body_twist_of_an_euler_step() -> None:
    robot = RobotParams()
    v_x, v_y, yaw_rate = body_velocities(1.2, 1.7, 0.03, robot.wheel_radius, robot.half_track)
    before = Pose(10.0, 0.3, 0.2, 2.5)
    x, y, heading = euler_step(before.x, before.y, before.heading, v_x, v_y, yaw_rate, 0.1)
    row = log_row(before, Pose(10.05, x, y, heading), 0.1, 17, (1.2, 1.7))
    assert row is not None
    assert row.tolist() == pytest.approx([17, 1.2, 1.7, v_x, v_y, yaw_rate], abs=1e-12)
    assert log_row(before, before, 0.0, 17, (1.2, 1.7)) is None


def test_log_row_wraps_the_heading_difference() -> None:
    row = log_row(
        Pose(0, 0.3, 0.2, math.pi - 0.01), Pose(1, 0.3, 0.2, -math.pi + 0.01), 0.1, 0, (0.0, 0.0)
    )
    assert row is not None and row[5] == pytest.approx(0.2)


def test_wheel_speed_stats_match_numpy_variance() -> None:
    robot = RobotParams()
    stats = WheelSpeedStats(49, robot)
    rng = np.random.default_rng(0)
    left, right = 1.7 - rng.uniform(0, 0.5, 50), 1.7 - rng.uniform(0, 0.5, 50)
    yaw_rate = robot.wheel_radius * (right - left) / (2 * robot.half_track)
    v_x = robot.wheel_radius * (right + left) / 2
    rows = np.column_stack([np.full(50, 5.0), left, right, v_x, np.zeros(50), yaw_rate])
    for row in rows:  # one period per action: no lag pairs, the plain sample variance
        stats.add_rows(row[None, :])
    expected = np.var(np.column_stack([left, right]).ravel(), ddof=1)
    assert stats.variance(5) == pytest.approx(expected)
    assert stats.variance(6) == 0.0


def test_reward_rule_matches_the_env() -> None:
    grid_map = arena_map("free", 0, GRID)
    stats = WheelSpeedStats(GRID.n_regions, RobotParams())
    goal = Pose(0, *GRID.cell_centre(*grid_map.goal), 0.0)
    assert reward_of(goal, True, grid_map.goal, GRID, stats) == (10.0, True)
    elsewhere = Pose(0, *GRID.cell_centre(*grid_map.start), 0.0)
    assert reward_of(elsewhere, True, grid_map.goal, GRID, stats) == (-10.0, False)
    assert reward_of(elsewhere, False, grid_map.goal, GRID, stats) == (-1.0, False)
    region = GRID.region(elsewhere.x, elsewhere.y)
    stats.add(region, 1.0)
    stats.add(region, 2.0)
    assert reward_of(elsewhere, False, grid_map.goal, GRID, stats) == (-1.0 - 10 * 0.5, False)


def test_seed_streams_are_independent_and_reproducible() -> None:
    a, b = seed_streams(4), seed_streams(4)
    assert a["map"].random() == b["map"].random()
    assert a["agent"].random() != a["slip"].random()


def forward_rows(
    rng: np.random.Generator, n_actions: int, eta: float, pose_noise: float, region: int = 5
) -> list[np.ndarray]:
    """Kinematic log rows of ``n_actions`` straight forward actions of 10 periods of 0.1 s:
    wheel speeds 1.7 − U(0, η) drawn each period, poses measured with N(0, pose_noise²) noise."""
    robot, dt = RobotParams(), 0.1
    actions = []
    for _ in range(n_actions):
        left, right = 1.7 - rng.uniform(0, eta, 10), 1.7 - rng.uniform(0, eta, 10)
        v_x = robot.wheel_radius * (left + right) / 2
        yaw = robot.wheel_radius * (right - left) / (2 * robot.half_track)
        heading = np.concatenate([[0.0], np.cumsum(yaw * dt)])
        x = np.concatenate([[0.1], 0.1 + np.cumsum(v_x * np.cos(heading[:-1]) * dt)])
        y = np.concatenate([[0.2], 0.2 + np.cumsum(v_x * np.sin(heading[:-1]) * dt)])
        x, y = x + rng.normal(0, pose_noise, 11), y + rng.normal(0, pose_noise, 11)
        poses = [Pose(k, x[k], y[k], heading[k]) for k in range(11)]
        rows = [log_row(a, b, dt, region, (1.7, 1.7)) for a, b in itertools.pairwise(poses)]
        actions.append(np.array(rows))
    return actions


@pytest.mark.parametrize("eta", [0.0, 0.5, 1.0])
def test_wheel_speed_variance_sees_slip_through_pose_noise(eta: float) -> None:
    """1 mm of pose noise reads as ≈ 0.4 rad²/s² of plain sample variance; the corrected
    estimate stays at the slip's own η²/12."""
    rng = np.random.default_rng(3)
    stats = WheelSpeedStats(49, RobotParams())
    actions = forward_rows(rng, 2000, eta, 0.001)
    for rows in actions:
        stats.add_rows(rows)
    speeds = np.concatenate([rows[:, 3] for rows in actions]) / RobotParams().wheel_radius
    assert np.var(speeds) > 0.15 + eta**2 / 12  # the noise a plain variance would report
    assert stats.variance(5) == pytest.approx(eta**2 / 12, abs=0.01)
    assert stats.variance(6) == 0.0


def test_wheel_speed_stats_load_the_earlier_welford_form() -> None:
    values = np.array([1.2, 1.5, 1.6, 1.1])
    old = np.zeros((49, 3))
    old[5] = len(values), values.mean(), ((values - values.mean()) ** 2).sum()
    stats = WheelSpeedStats(49, RobotParams())
    assert stats.load(old)
    assert stats.variance(5) == pytest.approx(np.var(values, ddof=1))
    assert not stats.load(np.zeros((7, 2)))


def spin_rows(robot: SimRobot, periods: int) -> np.ndarray:
    """Kinematic log rows of the robot spinning on the spot, left then right, from its measured
    poses (0.1 s apart)."""
    rows = []
    before = Pose(0.0, *robot.measured_pose())
    for k in range(periods):
        command = (-1.7, 1.7) if k < periods // 2 else (1.7, -1.7)
        robot.command(*command)
        robot.step()
        after = Pose(0.0, *robot.measured_pose())
        rows.append(log_row(before, after, 0.1, GRID.region(before.x, before.y), command))
        before = after
    return np.array(rows)


def test_homing_with_the_estimated_icr_reaches_the_start_on_a_shifted_floor() -> None:
    """A floor whose x_ICR is −3 cm instead of the nominal +5 cm: spinning at the start gives
    the estimate; homing about that pivot still ends in the start state."""
    robot = build_robot(
        slip="rough",
        drift=0.0,
        drift_period=600.0,
        map_spec="free",
        seed=2,
        config=SimRobotConfig(pose_noise=0.001),
    )
    robot.slip.x_icr[:] = -0.03
    estimates = IcrEstimates(GRID.n_regions, RobotParams().x_icr)
    estimates.add_rows(spin_rows(robot, 400))
    seen = estimates.sums[:, 1] > 20.0  # the spin crosses a corner of four coarse regions
    assert seen.sum() >= 2
    assert estimates.values()[seen] == pytest.approx(-0.03, abs=0.005)
    unseen = estimates.sums[:, 1] == 0.0
    assert estimates.values()[unseen] == pytest.approx(-0.03, abs=0.005)  # the pooled estimate
    grid_map = arena_map("free", 2, GRID)
    controller = HomingController(grid_map, GRID, 1.7, tolerance=0.008, x_icr=estimates.values())
    x, y = GRID.cell_centre(grid_map.start[0] + 6, grid_map.start[1] + 5)
    robot.pose = (x, y, 2.0)
    home(robot, controller)
    assert GRID.state(*robot.pose) == GRID.state(*start_pose(grid_map, GRID))


@pytest.mark.parametrize("offset", [(-3, 5), (4, 5), (8, 5)])
def test_homing_crosses_into_regions_the_robot_never_turned_in(offset: tuple[int, int]) -> None:
    """The MuJoCo robot's floor, x_ICR 0 against the nominal 5 cm, its estimate from a spin at
    the start only: homing from cells above it (regions without a row) reaches the start.
    Shrunk towards the nominal value, those regions kept 5 cm and homing turned back and forth
    at their border for the whole 300 s (each region shrunk to the pooled estimate instead)."""
    robot = build_robot(
        slip="rough",
        drift=0.0,
        drift_period=600.0,
        map_spec="free",
        seed=2,
        config=SimRobotConfig(pose_noise=0.001),
    )
    robot.slip.x_icr[:] = 0.0
    estimates = IcrEstimates(GRID.n_regions, RobotParams().x_icr)
    estimates.add_rows(spin_rows(robot, 200))
    grid_map = arena_map("free", 2, GRID)
    start_i, start_j = grid_map.start
    unseen = estimates.sums[:, 1] == 0.0
    assert unseen[GRID.region(*GRID.cell_centre(start_i + offset[0], start_j + offset[1]))]
    assert np.abs(estimates.values()).max() < 0.01
    controller = HomingController(grid_map, GRID, 1.7, tolerance=0.008, x_icr=estimates.values())
    robot.pose = (*GRID.cell_centre(start_i + offset[0], start_j + offset[1]), 0.0)
    home(robot, controller)
    assert GRID.state(*robot.pose) == GRID.state(*start_pose(grid_map, GRID))


SCORING_KERNELS = """
from skidnav.sim.navigation import action_reward
from skidnav.realtime.arena import arena_map
from skidnav.realtime.control.transition import compile_scoring
from skidnav.robot.kinematics import wrap_angle
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization, cell_of, region_of, state_of

kernels = (state_of, cell_of, region_of, wrap_angle, action_reward)
assert not any(kernel.signatures for kernel in kernels)
grid = Discretization()
compile_scoring(arena_map("obstacles", 0, grid), grid, RobotParams())
print([kernel.__name__ for kernel in kernels if not kernel.signatures])
"""


def test_the_loop_scoring_kernels_are_compiled_before_the_robot_is_contacted() -> None:
    """A fresh process: after ``compile_scoring`` every kernel an action is scored with has a
    compiled signature, so none compiles (holding the GIL) inside the first action."""
    result = subprocess.run(
        [sys.executable, "-c", SCORING_KERNELS], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "[]"


class IdleDriver:
    """A driver never connected: the loop is built, not run."""

    lockstep = False
    on_fault = None


def test_the_bumper_predicts_with_the_estimated_icr() -> None:
    """Beside a wall, a turn in place away from it: with the nominal x_ICR (5 cm) the bumper
    predicts the body to slide into the wall and stops it; once the rows show x_ICR ≈ 0 (the
    MuJoCo robot's) it lets the turn go. Driving into the wall is stopped either way."""
    grid_map = arena_map("free", 0, GRID)
    grid_map.occupancy[12, 5:20] = True
    with tempfile.TemporaryDirectory() as out:
        loop = EpisodeLoop(IdleDriver(), grid_map, load_config(None), Path(out))  # type: ignore[arg-type]
        wall_x = 12 * GRID.cell_width
        beside = Pose(0.0, wall_x - 0.001, GRID.cell_centre(12, 12)[1], math.radians(60.0))
        turn_away, ahead = (-1.7, 1.7), (1.7, 1.7)
        assert loop._would_collide(beside, turn_away)
        rows = np.zeros((400, 6))
        rows[:, 0] = GRID.region(beside.x, beside.y)
        rows[:, 5] = np.where(np.arange(400) % 2 == 0, 0.3, -0.3)  # turns, no sideways slide
        loop.icr.add_rows(rows)
        assert not loop._would_collide(beside, turn_away)
        assert loop._would_collide(beside, ahead)
        loop.log.close()
