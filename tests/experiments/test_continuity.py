"""Continuity metrics on hand-made traces with known answers, the recorder on the real env, and
the trajectory picture."""

from __future__ import annotations

import math
import struct
from pathlib import Path

import gymnasium
import numpy as np
import pytest
from PIL import Image

import skidnav.envs  # noqa: F401  (registers the env)
from skidnav.agents.tabular.registry import make_agent
from skidnav.agents.wheel_policy import WheelSpeedPolicy
from skidnav.envs.navigation import SkidSteerNavEnv
from skidnav.envs.registration import ENV_ID
from skidnav.errors import UserError
from skidnav.studies.continuity.traces import (
    Trace,
    aggregate,
    comparison_table,
    heading_reversals,
    record_rollout,
    tabular_policy,
    trace_metrics,
    wheel_speed_policy,
)
from skidnav.studies.continuity.trajectory_plot import save_trajectory_picture, trajectory_picture
from skidnav.studies.generalisation import GoalSeeker

FULL = 1.7
DISCRETE_COMMANDS = [(FULL, FULL), (-FULL, -FULL), (-FULL, FULL), (FULL, -FULL)]


def make_trace(
    poses: list[list[float]] | np.ndarray,
    commands: list[list[float]] | np.ndarray | None = None,
    *,
    period: float = 1.0,
    terminated: bool = True,
) -> Trace:
    poses = np.asarray(poses, dtype=np.float64)
    n = len(poses) - 1
    commands = np.full((n, 2), FULL) if commands is None else np.asarray(commands, np.float64)
    return Trace(
        poses, commands, period, np.zeros(n), np.zeros(n, bool), terminated, not terminated
    )


class Commands:
    """A WheelSpeedPolicy giving the discrete command of a discrete policy's action."""

    lidar_rays, lidar_range = 8, 0.3

    def __init__(self, choose: object) -> None:
        self.choose = choose

    def wheel_speeds(self, observation: np.ndarray) -> tuple[float, float]:
        return DISCRETE_COMMANDS[self.choose(observation)]  # type: ignore[operator]


# --- metrics on hand-made traces ---------------------------------------------------------------


def test_a_straight_line_has_its_length_and_no_change() -> None:
    # 3-4-5 triangles: two segments of 0.05 m and one of 0.10 m, all along one heading
    poses = [[0.1, 0.1, 0.6], [0.13, 0.14, 0.6], [0.16, 0.18, 0.6], [0.22, 0.26, 0.6]]
    metrics = trace_metrics(make_trace(poses, period=0.5))
    assert metrics.path_length == pytest.approx(0.20, abs=1e-12)
    assert metrics.wheel_change == 0.0
    assert metrics.reversals_per_metre == 0.0
    assert metrics.time_to_goal == 1.5
    assert metrics.energy == pytest.approx(3 * 2 * FULL**2 * 0.5)


def test_wheel_change_and_energy_of_known_commands() -> None:
    commands = [[1.0, 2.0], [1.0, -1.0], [0.0, 0.0], [0.5, 0.5]]
    metrics = trace_metrics(make_trace(np.zeros((5, 3)), commands, period=0.25))
    # |Δω|: (0 + 3), (1 + 1), (0.5 + 0.5) over 2 wheels × 3 transitions
    assert metrics.wheel_change == pytest.approx(6.0 / 6.0)
    assert metrics.energy == pytest.approx((1 + 4 + 1 + 1 + 0 + 0 + 0.25 + 0.25) * 0.25)
    assert math.isnan(metrics.reversals_per_metre)  # no path to divide by


def test_one_action_has_no_wheel_change() -> None:
    metrics = trace_metrics(make_trace([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]]))
    assert math.isnan(metrics.wheel_change)
    assert metrics.path_length == pytest.approx(0.1)


def test_a_zig_zag_reverses_at_every_turn_and_straight_legs_do_not_count() -> None:
    # heading +0.5, straight, −0.5, straight, +0.5, −0.5 rad per 1 s period, 0.1 m per period
    headings = np.cumsum([0.0, 0.5, 0.0, -0.5, 0.0, 0.5, -0.5])
    poses = np.column_stack([0.1 * np.arange(7), np.zeros(7), headings])
    metrics = trace_metrics(make_trace(poses))
    assert metrics.path_length == pytest.approx(0.6)
    assert metrics.reversals_per_metre == pytest.approx(3 / 0.6)


def test_rates_below_the_threshold_are_straight() -> None:
    wiggle = np.cumsum([0.0, 0.02, -0.02, 0.02, -0.02])  # 0.02 rad/s < 0.05 rad/s
    poses = np.column_stack([0.1 * np.arange(5), np.zeros(5), wiggle])
    assert trace_metrics(make_trace(poses)).reversals_per_metre == 0.0
    assert trace_metrics(make_trace(poses), reversal_threshold=0.01).reversals_per_metre == (
        pytest.approx(3 / 0.4)
    )
    assert heading_reversals(np.array([0.04, -0.04])) == 0
    assert heading_reversals(np.array([0.05, -0.05])) == 1  # the threshold itself counts


def test_headings_crossing_pi_turn_the_short_way() -> None:
    # +0.1 rad across the ±π seam each period, as a wrapped heading would record it: no reversal
    headings = [3.1, 3.2 - 2 * math.pi, 3.3 - 2 * math.pi, 3.2 - 2 * math.pi]
    poses = np.column_stack([0.1 * np.arange(4), np.zeros(4), headings])
    assert trace_metrics(make_trace(poses)).reversals_per_metre == pytest.approx(1 / 0.3)


def test_a_failure_has_no_time_to_goal_and_is_left_out_of_its_mean() -> None:
    line = [[0.1 * t, 0.0, 0.0] for t in range(7)]
    failed = make_trace(line, terminated=False)
    metrics = trace_metrics(failed)
    assert metrics.success == 0.0
    assert math.isnan(metrics.time_to_goal)
    assert metrics.path_length == pytest.approx(0.6)  # the path itself is still measured
    traces = [make_trace(line[:5]), failed, make_trace(line)]
    intervals = aggregate(traces, np.random.default_rng(0))
    assert intervals["time_to_goal"].estimate == pytest.approx(5.0)  # (4 + 6) / 2
    assert intervals["success"].estimate == pytest.approx(2 / 3)
    table = comparison_table({"p": traces}, np.random.default_rng(0)).set_index("metric")
    assert table.loc["time_to_goal", "n"] == 2
    assert table.loc["success", "n"] == 3
    assert table.loc["time_to_goal", "unit"] == "s"


def test_intervals_contain_the_mean_and_are_seeded() -> None:
    traces = [make_trace([[0.0, 0.0, 0.0], [0.05 * n, 0.0, 0.0]]) for n in range(1, 9)]
    first = aggregate(traces, np.random.default_rng(5))["path_length"]
    again = aggregate(traces, np.random.default_rng(5))["path_length"]
    assert first == again
    assert first.estimate == pytest.approx(0.05 * 4.5)
    assert first.low < first.estimate < first.high


def test_inconsistent_traces_are_refused() -> None:
    good = make_trace([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]])
    with pytest.raises(ValueError, match="commands of shape"):
        trace_metrics(good._replace(commands=np.zeros((2, 2))))
    with pytest.raises(ValueError, match="control period"):
        trace_metrics(good._replace(control_period=0.0))
    with pytest.raises(ValueError, match="poses of shape"):
        trace_metrics(good._replace(poses=np.zeros((0, 3))))


# --- the recorder on the real env ------------------------------------------------------------


def test_an_untrained_tabular_agent_drives_forward_at_full_speed() -> None:
    env = gymnasium.make(ENV_ID, map_kind="free", world_seed=1)
    nav = env.unwrapped
    agent = make_agent("q-learning", nav.discretization.n_states, 4, rng=np.random.default_rng(0))
    trace = record_rollout(env, tabular_policy(agent), seed=2, max_steps=20)
    assert trace.n_actions == 20 and trace.truncated and not trace.terminated
    assert (trace.commands == FULL).all()  # greedy on an all-zero table: action 0, forward
    assert trace.poses.shape == (21, 3)
    assert trace.poses[0].tolist() == nav.start_pose().tolist()
    assert trace.control_period == 1.0
    metrics = trace_metrics(trace)
    assert metrics.energy == pytest.approx(2 * FULL**2 * 20 * 1.0)
    assert metrics.wheel_change == 0.0
    assert metrics.collisions == trace.collisions.sum() > 0  # straight into the east border


def test_a_continuous_policy_equal_to_the_discrete_one_gives_the_same_trace() -> None:
    options = {"map_kind": "free", "world_seed": 1, "observation": "features"}
    discrete = gymnasium.make(ENV_ID, **options)
    continuous = gymnasium.make(ENV_ID, action="continuous", **options)
    seeker = GoalSeeker()
    policy = Commands(seeker.greedy_action)
    assert isinstance(policy, WheelSpeedPolicy)
    got = record_rollout(continuous, wheel_speed_policy(policy, continuous), seed=3)
    expected = record_rollout(discrete, tabular_policy(seeker), seed=3)
    assert expected.terminated and expected.n_actions > 10  # it turns as well as drives
    for name in ("poses", "commands", "rewards", "collisions"):
        assert getattr(got, name).tobytes() == getattr(expected, name).tobytes(), name
    assert (got.control_period, got.terminated, got.truncated) == (1.0, True, False)
    np.testing.assert_array_equal(trace_metrics(got), trace_metrics(expected))


def test_the_recorder_is_deterministic_and_reads_the_control_period() -> None:
    options = {"map_kind": "obstacles", "world_seed": 2, "slip": "slippery"}
    env = gymnasium.make(
        ENV_ID, action="continuous", observation="features", control_period=0.5, **options
    )

    def arc(observation: np.ndarray) -> np.ndarray:
        return np.array([0.8, 1.2]) if observation[6] > 0 else np.array([1.2, 0.8])

    first = record_rollout(env, arc, seed=7, max_steps=30)
    again = record_rollout(env, arc, seed=7, max_steps=30)
    assert first.poses.tobytes() == again.poses.tobytes()
    assert first.control_period == 0.5
    assert trace_metrics(first).energy == pytest.approx(first.n_actions * (0.64 + 1.44) * 0.5)


def test_mismatched_envs_and_missing_limits_are_refused() -> None:
    discrete = gymnasium.make(ENV_ID, map_kind="free", world_seed=1, observation="features")
    policy = Commands(lambda observation: 0)
    with pytest.raises(ValueError, match="continuous"):
        wheel_speed_policy(policy, discrete)
    fewer_rays = gymnasium.make(ENV_ID, action="continuous", observation="features", lidar_rays=4)
    with pytest.raises(ValueError, match="lidar_rays"):
        wheel_speed_policy(policy, fewer_rays)
    with pytest.raises(ValueError, match="max_steps"):
        record_rollout(SkidSteerNavEnv(map_kind="free"), lambda observation: 0)


# --- the picture -----------------------------------------------------------------------------


def test_the_picture_is_a_png_of_the_expected_size_with_every_line(tmp_path: Path) -> None:
    env = gymnasium.make(ENV_ID, map_kind="obstacles", world_seed=1)
    nav = env.unwrapped
    forward = record_rollout(env, lambda observation: 0, seed=0, max_steps=6)
    turns = iter([0, 2, 2, 0, 0, 2, 2, 0])
    left = record_rollout(env, lambda observation: next(turns), seed=0, max_steps=8)
    traces = {"forward": forward, "left": left}
    png = trajectory_picture(nav.grid_map, traces, title="two")
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert struct.unpack(">II", png[16:24]) == (576, 540)  # 6.4 × 6.0 in at 90 dpi
    path = tmp_path / "trajectories.png"
    save_trajectory_picture(path, nav.grid_map, traces)
    with Image.open(path) as image:
        assert image.format == "PNG" and image.size == (576, 540)
        pixels = np.asarray(image.convert("RGB")).reshape(-1, 3).astype(int)
    for colour in ((31, 119, 180), (255, 127, 14)):  # tab10's first two: one line each
        assert (np.abs(pixels - colour).sum(axis=1) < 10).sum() > 50
    with pytest.raises(UserError, match="cannot write"):
        save_trajectory_picture(tmp_path / "missing" / "t.png", nav.grid_map, traces)
