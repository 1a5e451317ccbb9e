"""The cell planner's saved state and its checks, and which kinematic model an agent plans with.

Shared by the agents that plan on the cells through the kinematic model
(:mod:`skidnav.agents.kinematic_planning`): the model-based tabular agents and
``linear-dyna-kinematic``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from skidnav.agents import kinematic_planning as kp
from skidnav.models.kinematic import KinematicModel
from skidnav.robot.kinematics import N_ACTIONS


def hold_kinematic_model(
    model: KinematicModel, source: str, true_kinematics: np.ndarray | None
) -> None:
    """Make ``model`` the one an agent's ``kinematic_model`` names
    (:class:`~skidnav.agents.config.KinematicModelFields`): "learned" leaves it learning,
    "prior" holds the prior, "true" holds ``true_kinematics`` (float64 (n_regions, 4, 3), the
    simulator's expected body velocities; ValueError when there are none, as on a physics or real
    robot)."""
    if source == "prior":
        model.hold()
    elif source == "true":
        if true_kinematics is None:
            raise ValueError(
                "expected the simulator's true_kinematics for kinematic_model 'true' (only the "
                "kinematic env has them), got none"
            )
        model.hold(true_kinematics)


def true_kinematics_from_json(value: Any, n_regions: int) -> np.ndarray:
    """The ``true_kinematics`` a "true" agent saved in its JSON, float64 (n_regions, 4, 3);
    ValueError unless it is exactly that, finite."""
    try:
        table = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        table = np.zeros(0)
    if table.shape != (n_regions, N_ACTIONS, 3) or not np.isfinite(table).all():
        raise ValueError(
            f"expected true_kinematics of {n_regions} × {N_ACTIONS} × 3 finite numbers"
        )
    return table


MAP_ARRAYS = ("walls", "goals", "stale", "wall_evidence", "free_evidence")
"""The planner's map (:class:`~skidnav.agents.kinematic_planning.PlannerArrays`), saved as
``planner_<name>``."""


def check_planner_map(planner: kp.PlannerArrays) -> None:
    """ValueError unless the planner's map evidence are counts and its walls are the cells the
    evidence make walls (:func:`~skidnav.agents.planner_learning.weigh_cell`)."""
    if (planner.wall_evidence < 0).any() or (planner.free_evidence < 0).any():
        raise ValueError("saved planner wall or free evidence are not counts")
    weighed = (planner.wall_evidence > planner.free_evidence) & ~planner.goals
    if not np.array_equal(planner.walls, weighed):
        raise ValueError("saved planner walls disagree with their evidence")


def check_planner_counters(counters: np.ndarray, sizes: list[int], has_kinematic: bool) -> None:
    """ValueError unless the planner counters agree with the saved sweep and episode lists
    (``sizes``: trajectory, neighbour, episode keys): the compiled planner indexes by them."""
    n_trajectory, n_neighbours, n_episode = sizes
    expected = {
        "N_TRAJECTORY": counters[kp.N_TRAJECTORY] == n_trajectory,
        "TRAJECTORY_CURSOR": 0 <= counters[kp.TRAJECTORY_CURSOR] < max(n_trajectory, 1),
        "N_NEIGHBOURS": counters[kp.N_NEIGHBOURS] == n_neighbours,
        "NEIGHBOUR_CURSOR": 0 <= counters[kp.NEIGHBOUR_CURSOR] < max(n_neighbours, 1),
        "EPISODE_LENGTH": counters[kp.EPISODE_LENGTH] == n_episode,
        "REFRESH_RADIUS": counters[kp.REFRESH_RADIUS] >= 0,
        "USE_KINEMATIC": counters[kp.USE_KINEMATIC] in ((0, 1) if has_kinematic else (0,)),
        "EPISODE_TERMINATED": counters[kp.EPISODE_TERMINATED] in (0, 1),
        "MAP_CHANGES": counters[kp.MAP_CHANGES] >= 0,
    }
    wrong = [name for name, ok in expected.items() if not ok]
    if wrong:
        raise ValueError(f"saved planner counters inconsistent with its arrays: {', '.join(wrong)}")
