"""The continuous policies ``skidnav robot run`` can drive (docs/realtime.md, "Continuous
policies"): a named one (``--policy NAME``, its settings from the config's ``[policies.NAME]``
table) or a saved one (``--policy-file PATH``, by the loader of its format:
:mod:`skidnav.agents.policies.loading`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from skidnav.agents.policies.goal_tracker import GoalTracker, GoalTrackerConfig
from skidnav.agents.policies.loading import load_policy, policy_json
from skidnav.agents.policies.wheel_policy import WheelSpeedPolicy
from skidnav.configtables import build_dataclass
from skidnav.envs.navigation import clipped_wheel_speeds
from skidnav.errors import UserError, first_line, shown
from skidnav.realtime.config import RealtimeConfig
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
        return load_policy(file), f"file:{policy_json(file).resolve()}"
    assert name is not None
    builder = NAMED_POLICIES.get(name)
    if builder is None:
        raise UserError(
            f"unknown policy {shown(name)}; expected one of {', '.join(NAMED_POLICIES)}"
        )
    return builder(config.policies.get(name, {}), robot), name


def check_policy(
    policy: WheelSpeedPolicy, label: str, grid_map: GridMap, grid: Discretization
) -> None:
    """Ask ``policy`` once for the wheel speeds at the map's start (centre of the start cell,
    heading 0) before the robot is contacted: this compiles the feature kernels and the
    forward-drive rule the loop scores each action with, whose compilation would hold the GIL
    and starve the driver's reader mid-episode, and refuses a policy that fails there
    (UserError) before anything moves."""
    try:
        features = PoseFeatures(grid_map, grid, policy.lidar_rays, policy.lidar_range)
        x, y = grid.cell_centre(*grid_map.start)
        # only checked (two finite numbers): the limit plays no part here
        command = clipped_wheel_speeds(policy.wheel_speeds(features(np.array([x, y, 0.0]))), 1.0)
        is_forward_drive(command)
    except Exception as error:  # a policy's own failure, whatever it is, ends here in one line
        raise UserError(f"policy {label}: fails at the start pose ({first_line(error)})") from None
