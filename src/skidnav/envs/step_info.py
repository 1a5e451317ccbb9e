"""The ``info`` of one navigation step: one typed record, built in one place (:func:`step_info`)
for the Gymnasium env and the real-time loop alike, and read by agents.

The info dict holds every :class:`StepInfo` field under its own name (the documented keys below,
for any Gymnasium code) and the record itself under :data:`STEP_INFO_KEY`, for code that reads
attributes:

* ``pose``: (x [m], y [m], heading [rad]) where the action ended (heading unwrapped);
* ``cell``: (i, j, heading bin) of that pose (:meth:`Discretization.unflatten` of the state);
* ``collision``: True if the action ran into a wall (the env) or the virtual bumper stopped it
  (the real-time loop);
* ``wheel_speeds``: (ω_L, ω_R) [rad/s] of the last sub-step: after slip in the env; as commanded
  on a real robot, whose wheel speeds the loop does not measure;
* ``region``: flat slip region of the end pose;
* ``kinematic_log``: float64 (n, 6), one row per free sub-step (control period),
  columns ``sim.navigation.LOG_COLUMNS`` [region, ω_L_cmd, ω_R_cmd, v_x, v_y, yaw_rate]:
  what the kinematic models learn from (n = 0 when nothing moved freely);
* ``cost``: the action's cost, minus its reward without the goal bonus
  (:func:`skidnav.sim.navigation.action_cost`; 0 at a reset). NaN where nothing scored it:
  the real-time loop ranks nothing by it.

>>> import numpy as np
>>> info = step_info((0.1, 0.2, 0.0), (4, 9, 10), False, (1.7, 1.7), 8, np.zeros((10, 6)))
>>> info["pose"], info["collision"], info[STEP_INFO_KEY].kinematic_log.shape
((0.1, 0.2, 0.0), False, (10, 6))
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np

STEP_INFO_KEY = "step_info"
"""Key of the :class:`StepInfo` record in the info dict."""


class StepInfo(NamedTuple):
    """What one step of the navigation MDP tells beyond its observation (module doc for units)."""

    pose: tuple[float, float, float]
    cell: tuple[int, int, int]
    collision: bool
    wheel_speeds: tuple[float, float]
    region: int
    kinematic_log: np.ndarray
    cost: float = math.nan


def step_info(
    pose: Sequence[float],
    cell: tuple[int, int, int],
    collision: bool,
    wheel_speeds: tuple[float, float],
    region: int,
    kinematic_log: np.ndarray,
    cost: float = math.nan,
) -> dict[str, Any]:
    """The info dict of a step (see module doc); numbers become Python floats, ints and bools."""
    x, y, heading = pose
    record = StepInfo(
        (float(x), float(y), float(heading)),
        cell,
        bool(collision),
        (float(wheel_speeds[0]), float(wheel_speeds[1])),
        int(region),
        kinematic_log,
        float(cost),
    )
    info = record._asdict()
    info[STEP_INFO_KEY] = record
    return info
