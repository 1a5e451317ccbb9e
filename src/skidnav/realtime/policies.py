"""The continuous policies ``skidnav robot run`` can drive (docs/realtime.md, "Continuous
policies"): a named one (``--policy NAME``, its settings from the config's ``[policies.NAME]``
table) or a saved one (``--policy-file PATH``, by the loader of its format:
:func:`skidnav.agents.saved.load_policy`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from skidnav.agents.policies.goal_tracker import GoalTracker, GoalTrackerConfig
from skidnav.agents.saved import load_policy, saved_json
from skidnav.agents.wheel_policy import WheelSpeedPolicy
from skidnav.errors import UserError, first_line, shown
from skidnav.files.configtables import build_dataclass
from skidnav.realtime.config import RealtimeConfig
from skidnav.robot.kinematics import clipped_wheel_speeds
from skidnav.robot.params import RobotParams
from skidnav.sim.features import PoseFeatures
from skidnav.sim.navigation import is_forward_drive
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap


def _goal_tracker(settings: Mapping[str, Any], robot: RobotParams) -> WheelSpeedPolicy:
    config = build_dataclass(GoalTrackerConfig, dict(settings), "[policies.goal-tracker]")
    return GoalTracker(config, robot)


NAMED_POLICIES: dict[str, Callable[[Mapping[str, Any], RobotParams], WheelSpeedPolicy]] = {
    "goal-tracker": _goal_tracker,
}
"""``--policy`` name → builder from its ``[policies.NAME]`` table and the robot."""


def select_policy(
    name: str | None, file: Path | None, config: RealtimeConfig, robot: RobotParams
) -> tuple[WheelSpeedPolicy, str]:
    """(policy, label) of ``--policy name`` or ``--policy-file file`` (exactly one given);
    the label — the name, or ``file:`` and the JSON file's absolute path — is what the loop
    state records. UserError (one line) for an unknown name, bad settings or a bad file."""
    if (name is None) == (file is None):
        raise UserError("expected one of --policy and --policy-file")
    if file is not None:
        return load_policy(file), f"file:{saved_json(file, 'policy file').resolve()}"
    assert name is not None
    builder = NAMED_POLICIES.get(name)
    if builder is None:
        raise UserError(
            f"unknown policy {shown(name)}; expected one of {', '.join(NAMED_POLICIES)}"
        )
    return builder(config.policies.get(name, {}), robot), name


def check_policy(
    policy: WheelSpeedPolicy,
    label: str,
    grid_map: GridMap,
    grid: Discretization,
    action_duration: float,
) -> None:
    """Ask ``policy`` once for the wheel speeds at the map's start (centre of the start cell,
    heading 0) before the robot is contacted: this compiles the feature kernels and the
    forward-drive rule the loop scores each action with, whose compilation would hold the GIL
    and starve the driver's reader mid-episode, and refuses a policy that fails there
    (UserError) before anything moves. A policy that plans for one goal and one action
    duration (``goal`` (i, j) and ``control_period`` [s] attributes: ``mppi-kinematic``'s
    frozen planner) is refused on a run whose map has another goal cell or whose actions
    (``action_duration`` = ``[run] period × substeps`` [s]) last otherwise; one that records
    the arena its observations were bounded in (``arena`` (W, H) [m]: a saved discrete-action
    agent, :mod:`skidnav.agents.discrete_policy`) on a run of another arena."""
    _check_plan(policy, label, grid_map, action_duration)
    arena = getattr(policy, "arena", None)
    run_arena = (grid.arena_width, grid.arena_height)
    if arena is not None and not np.allclose(arena, run_arena, rtol=1e-9, atol=0.0):
        raise UserError(
            f"policy {label}: it observes an arena of {arena[0]:g} × {arena[1]:g} m, the run's "
            f"is {run_arena[0]:g} × {run_arena[1]:g} m"
        )
    try:
        features = PoseFeatures(grid_map, grid, policy.lidar_rays, policy.lidar_range)
        x, y = grid.cell_centre(*grid_map.start)
        # only checked (two finite numbers): the limit plays no part here
        command = clipped_wheel_speeds(policy.wheel_speeds(features(np.array([x, y, 0.0]))), 1.0)
        is_forward_drive(command)
    except Exception as error:  # a policy's own failure, whatever it is, ends here in one line
        raise UserError(f"policy {label}: fails at the start pose ({first_line(error)})") from None


def _check_plan(
    policy: WheelSpeedPolicy, label: str, grid_map: GridMap, action_duration: float
) -> None:
    """UserError when ``policy`` says it drives to another goal cell than the map's, or plans
    actions of another duration than the run's (:func:`check_policy`)."""
    goal = getattr(policy, "goal", None)
    if goal is not None and tuple(goal) != tuple(grid_map.goal):
        raise UserError(
            f"policy {label}: it drives to the goal cell {tuple(goal)}, the run's map has its goal "
            f"at {tuple(grid_map.goal)} (set [run] map and seed to the policy's world)"
        )
    period = getattr(policy, "control_period", None)
    if period is not None and not math.isclose(period, action_duration, rel_tol=1e-9):
        raise UserError(
            f"policy {label}: it plans actions of {period:g} s, the run's last "
            f"{action_duration:g} s (set [run] period × substeps to {period:g} s)"
        )
