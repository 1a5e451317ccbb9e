"""The benchmark's rules on hand-made trajectories: success within the goal radius, a collision
ends the run, the 100-s limit, AT measured from the first 0.1 m of motion, the metric equal to
``barn_score``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skidnav.studies.barn.rules import BarnClock, score_trajectory
from skidnav.world.barn import barn_score

GOAL = (0.0, 10.0)
OT = 2.0
"""OT [s] of the hand-made world: clip bounds 4 s and 16 s."""


def straight(speeds: list[float], period: float = 0.1) -> np.ndarray:
    """Positions (T + 1, 2) [m] along +y from the origin, one action per speed [m/s]."""
    steps = np.array([0.0, *speeds]) * period
    return np.column_stack([np.zeros(len(steps)), np.cumsum(steps)])


def score(positions: np.ndarray, collisions: np.ndarray | None = None) -> object:
    hits = np.zeros(len(positions) - 1, bool) if collisions is None else collisions
    return score_trajectory(positions, hits, GOAL, 1.0, OT, control_period=0.1)


def test_a_success_ends_at_the_first_action_within_the_goal_radius() -> None:
    outcome = score(straight([2.0] * 60))  # 0.2 m per action: y = 9.0 m after 45 actions
    assert outcome.success and not outcome.collision and not outcome.timeout
    assert outcome.actions == 45
    # the clock starts at the first action 0.1 m from the start (the first, 0.2 m)
    assert outcome.clock_start == pytest.approx(0.1) and outcome.time == pytest.approx(4.4)
    assert outcome.metric == barn_score(True, outcome.time, OT) == pytest.approx(OT / 4.4)


def test_the_clock_starts_when_the_robot_has_moved_a_tenth_of_a_metre() -> None:
    # 20 actions in place, then 4 of 2 cm (0.08 m: not started), then 10 cm each: 0.18 m at
    # action 25, the clock's start, and 9.08 m, within the goal's metre, at action 24 + 90
    speeds = [0.0] * 20 + [0.2] * 4 + [1.0] * 200
    outcome = score(straight(speeds))
    assert outcome.clock_start == pytest.approx(2.5)
    assert outcome.success and outcome.actions == 114
    assert outcome.time == pytest.approx(11.4 - 2.5)
    assert outcome.metric == pytest.approx(OT / min(max(outcome.time, 2 * OT), 8 * OT))


def test_a_collision_ends_the_run_as_a_failure_even_within_the_goal_radius() -> None:
    positions = straight([2.0] * 60)
    collisions = np.zeros(60, bool)
    collisions[44] = True  # the action that would have reached the goal
    outcome = score(positions, collisions)
    assert outcome.collision and not outcome.success and outcome.actions == 45
    assert outcome.metric == 0.0 and outcome.time == pytest.approx(4.4)


def test_a_timeout_after_100_s_of_the_clock() -> None:
    outcome = score(straight([2.0] + [0.0] * 2000))  # moves once, then stands
    assert outcome.timeout and not outcome.success and outcome.actions == 1001
    assert outcome.time == pytest.approx(100.0) and outcome.metric == 0.0


def test_a_robot_that_never_moves_times_out_after_100_s_with_its_clock_unstarted() -> None:
    outcome = score(straight([0.0] * 1500))
    assert outcome.timeout and outcome.actions == 1000
    assert outcome.time == 0.0 and math.isnan(outcome.clock_start) and outcome.metric == 0.0


def test_a_success_at_the_last_moment_is_a_timeout() -> None:
    # the clock starts at action 1; the goal radius is reached exactly at t - t_s = 100 s
    speeds = [1.0] + [0.0] * 999 + [90.0]
    outcome = score(straight(speeds, period=0.1))
    assert outcome.actions == 1001 and outcome.timeout and not outcome.success


def test_the_rule_does_not_accept_an_unfinished_record() -> None:
    with pytest.raises(ValueError, match="expected an ended run"):
        score(straight([2.0] * 10))


def test_the_clock_refuses_a_step_after_the_end() -> None:
    clock = BarnClock((0.0, 0.0), GOAL, 1.0, control_period=0.1)
    assert clock.step((0.0, 0.0), True)
    with pytest.raises(AssertionError):
        clock.step((0.0, 0.0), False)
