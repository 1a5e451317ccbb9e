"""The benchmark's rules for one run, as its ``run.py`` applies them, at the control period.

``run.py`` (Daffan/the-barn-challenge) samples the robot's position every 0.1 s of simulated
time. Here a sample is the pose at the end of each action (actions of ``control_period`` s, the
benchmark's 0.1 s), action k ending at t_k = k · ``control_period`` after the reset:

1. **The clock starts when the robot moves.** ``run.py`` waits until the robot is 0.1 m or more
   from its start and takes that sample's time as the start: t_s = t_k0, k0 the first action
   ending at least :data:`START_DISTANCE` from the reset's position.
2. **The run ends at the first sample, from k0 on, that is within the goal radius (1 m of the
   goal point), in a collision, or 100 s after the start** (t_k − t_s ≥ 100 s). A collision
   outranks a timeout, which outranks a success, as in ``run.py``'s report of the last sample.
3. **AT = t_end − t_s**, and the score is
   :func:`~skidnav.world.barn.barn_score` (success, AT, OT).

Two cases ``run.py`` never meets, because Gazebo's robot cannot stay still under a navigator
forever nor touch a cylinder before it moved: here a collision before the clock starts ends the
run at once (a failure, AT = 0), and a robot that has not left its start after
:data:`~skidnav.world.barn.TIME_LIMIT` seconds times out (AT = 0: its clock never started).

>>> clock = BarnClock((0.0, 0.0), (0.0, 3.0), 1.0, control_period=1.0)
>>> [clock.step((0.0, y), False) for y in (0.05, 1.0, 1.9, 2.0)]
[False, False, False, True]
>>> outcome = clock.outcome(optimal_time=1.0)
>>> outcome.success, outcome.time, outcome.clock_start, outcome.actions, outcome.metric
(True, 2.0, 2.0, 4, 0.5)
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from skidnav.world.barn import TIME_LIMIT, barn_score

START_DISTANCE = 0.1
"""Distance from the start [m] at which ``run.py`` starts the clock."""


class BarnOutcome(NamedTuple):
    """How one run ended under the benchmark's rules (module doc).

    Attributes:
        success: reached the goal radius, without a collision, within the time limit.
        collision: ended by a collision.
        timeout: ended by the time limit.
        time: AT [s], from the clock's start to the run's end (0 when the clock never started).
        clock_start: t_s [s] after the reset (NaN when the robot never left its start).
        actions: actions taken until the run ended.
        metric: the BARN score, :func:`~skidnav.world.barn.barn_score` (success, AT, OT).
    """

    success: bool
    collision: bool
    timeout: bool
    time: float
    clock_start: float
    actions: int
    metric: float


class BarnClock:
    """The rules of the module doc, told one action at a time.

    Args:
        start: the position [m] (x, y) the run starts from.
        goal: the goal point [m] (x, y).
        goal_radius: success distance [m] (BARN: 1 m).
        control_period: seconds per action [s] (BARN: 0.1 s).
        time_limit: seconds from the clock's start [s] (BARN: 100 s).
    """

    def __init__(
        self,
        start: tuple[float, float],
        goal: tuple[float, float],
        goal_radius: float,
        *,
        control_period: float,
        time_limit: float = TIME_LIMIT,
    ) -> None:
        self.start, self.goal, self.goal_radius = start, goal, goal_radius
        self.limit = round(time_limit / control_period)  # whole actions, no rounding drift
        self.control_period = control_period
        self.actions = 0
        self.started_at: int | None = None
        self.ended: str | None = None

    def step(self, position: tuple[float, float], collided: bool) -> bool:
        """Record one action ending at ``position`` [m] (``collided``: it ran into a wall);
        True when the run has ended (then no more actions are taken)."""
        assert self.ended is None, "the run has ended"
        self.actions += 1
        if self.started_at is None and math.dist(position, self.start) >= START_DISTANCE:
            self.started_at = self.actions
        if collided:
            self.ended = "collision"
        elif self._elapsed() >= self.limit:
            self.ended = "timeout"
        elif self.started_at is not None and math.dist(position, self.goal) <= self.goal_radius:
            self.ended = "success"
        return self.ended is not None

    def _elapsed(self) -> int:
        """Actions since the clock started (since the reset while it has not)."""
        return self.actions - (self.started_at or 0)

    def outcome(self, optimal_time: float) -> BarnOutcome:
        """The run's :class:`BarnOutcome`, OT = ``optimal_time`` [s]; ValueError before the run
        has ended."""
        if self.ended is None:
            raise ValueError(f"expected an ended run, got {self.actions} actions and no end")
        started_at = self.started_at
        time = 0.0 if started_at is None else self._elapsed() * self.control_period
        success = self.ended == "success"
        return BarnOutcome(
            success=success,
            collision=self.ended == "collision",
            timeout=self.ended == "timeout",
            time=time,
            clock_start=math.nan if started_at is None else started_at * self.control_period,
            actions=self.actions,
            metric=barn_score(success, time, optimal_time),
        )


def score_trajectory(
    positions: np.ndarray,
    collisions: np.ndarray,
    goal: tuple[float, float],
    goal_radius: float,
    optimal_time: float,
    *,
    control_period: float,
) -> BarnOutcome:
    """The outcome of a recorded run: ``positions`` float (T + 1, 2) [m], the reset's then one
    per action; ``collisions`` bool (T,), per action. ValueError when the record ends before
    the rules end the run."""
    start = (float(positions[0, 0]), float(positions[0, 1]))
    clock = BarnClock(start, goal, goal_radius, control_period=control_period)
    for (x, y), collided in zip(positions[1:].tolist(), collisions.tolist(), strict=True):
        if clock.step((x, y), bool(collided)):
            break
    return clock.outcome(optimal_time)
