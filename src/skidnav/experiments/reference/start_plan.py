"""The fewest actions from the exact start pose: what the best computable policy achieves where
every agent's evaluation starts, the calibration of the convergence test
(:mod:`skidnav.experiments.metrics`).

The oracle's L* is the expected number of actions of the best policy over cells when the poses
within a cell are spread (:mod:`skidnav.experiments.reference.oracle`). Every evaluation starts from
one exact pose, from which a policy can do better than that expectation, and from which the oracle's
own greedy cell policy can loop for ever (an action that works on average over a cell hits a wall
from that point, the robot is put back in the same cell, and the same action is chosen again).
So each world also gets the **start plan**: the fewest-actions action sequence from the exact
start pose to the goal cell under the simulator without slip noise, found by breadth-first search
over poses (:func:`skidnav.sim.shortest_plan.shortest_plan`), replayed open loop from every
evaluation seed's reset (the slip noise every agent's evaluation meets). Its length against L*
says how generous the test's band is; whether its rollouts pass the test says whether a policy
can pass it from that start at all.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np

from skidnav.sim.shortest_plan import shortest_plan

PLAN_RESOLUTION = 0.004
"""Poses closer than this [m] in x and in y (and in one heading bin) count as one in the search."""
PLAN_HEADING_BINS = 72
"""Heading bins of the search (5° each)."""
PLAN_MAX_NODES = 1_000_000
"""Most poses the search keeps (24 MB); past it the plan is reported as not found."""


class StartPlan(NamedTuple):
    """The start plan of one world (module docs).

    Attributes:
        actions: int64 (length,), the plan; empty when none was found.
        rollout_lengths: int64 (n_seeds,), actions until the goal when the plan is replayed from
            each evaluation seed's reset, −1 where it did not reach the goal.
    """

    actions: np.ndarray
    rollout_lengths: np.ndarray


def start_plan(env: Any, seeds: Sequence[int], max_steps: int) -> StartPlan:
    """The start plan of the world of the skid-steer ``env`` (kinematic dynamics), at most
    ``max_steps`` actions long, and its replays from ``reset(seed=s)`` for every seed."""
    nav = env.unwrapped
    plan = shortest_plan(
        nav.task, nav.start_pose(), max_steps, PLAN_RESOLUTION, PLAN_HEADING_BINS, PLAN_MAX_NODES
    )
    lengths = np.full(len(seeds), -1, dtype=np.int64)
    for k, seed in enumerate(seeds):
        env.reset(seed=int(seed))
        for step, action in enumerate(plan, start=1):
            if env.step(int(action))[2]:
                lengths[k] = step
                break
    return StartPlan(plan, lengths)
