"""``skidnav robot run --agent-file PATH``: a saved agent of any family on the robot
(docs/robot-learning.md).

The file's ``"format"`` names its family (:func:`skidnav.agents.saved.saved_family`), and the
family says what it does on the robot: a tabular agent keeps learning online from its saved
tables (:mod:`.control.loop`), ``mppi-kinematic`` keeps learning its kinematic model and its map
(:mod:`.control.mppi_loop`), and an agent of every other family acts frozen through its family's
policy loader (:attr:`~skidnav.agents.family.Family.policy`), as ``--policy-file`` runs it
(:mod:`.control.policy_loop`): the deep ``ppo`` and ``sac``, policy search and the named
policies' files by their wheel speeds, the linear agents and ``dqn`` (discrete actions over the
feature observation) by the wheel speeds of their greedy actions
(:mod:`skidnav.agents.discrete_policy`). A family that neither learns on the robot nor has a
policy loader would be refused; every registered family does one or the other.

Before anything moves, the run must be the world the agent was trained for: ``world.json``
beside the file, when ``skidnav run`` wrote one (:mod:`skidnav.agents.trained_world`), or
else what the agent itself records (its states, its nominal robot, grid and goal). A mismatch of
robot, arena/grid, goal or action duration is one :class:`~skidnav.errors.UserError` line naming
the file and the mismatch.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, NamedTuple

from skidnav.agents.saved import saved_family
from skidnav.agents.trained_world import agent_mismatch, world_beside
from skidnav.errors import CorruptFileError, UserError, shown
from skidnav.robot.kinematics import N_ACTIONS
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap

LEARNING_FAMILIES = ("tabular", "mpc")
"""Families whose saved agents keep learning on the robot; the others' act frozen."""


class SavedPilot(NamedTuple):
    """What ``--agent-file`` names: the agent's family and registry name, and its ``.json``."""

    family: str
    name: str
    json_path: Path

    @property
    def learns(self) -> bool:
        """True if the agent keeps learning on the robot (:data:`LEARNING_FAMILIES`)."""
        return self.family in LEARNING_FAMILIES


class RunWorld(NamedTuple):
    """The world of a robot run: its nominal robot, discretization, action duration [s] (``[run]
    period × substeps``) and map."""

    robot: RobotParams
    grid: Discretization
    action_duration: float
    grid_map: GridMap


def open_agent_file(path: Path, world: RunWorld) -> SavedPilot:
    """The saved agent at ``path`` (either of its files or their stem), its ``world.json``
    checked against the run's ``world``.

    Raises:
        CorruptFileError: the file (or its ``world.json``) unreadable or not a saved agent.
        UserError: the agent was trained for another robot, arena/grid, goal or action
            duration, or its family neither learns on the robot nor has a policy loader.
    """
    json_path, meta, family = saved_family(path)
    name = meta.get("agent", family.name)
    if not isinstance(name, str):
        raise CorruptFileError(f"{json_path}: expected an agent name, got {shown(name)}")
    trained = world_beside(json_path, name)
    if trained is not None:
        problem = trained.mismatch(*world)
        if problem is not None:
            raise UserError(f"{json_path}: {problem}")
    if family.name not in LEARNING_FAMILIES and family.policy is None:
        raise UserError(
            f"{json_path}: a saved {family.name} agent does not run on the robot (expected a "
            "tabular agent, mppi-kinematic, or an agent of a family with a policy loader)"
        )
    return SavedPilot(family.name, name, json_path)


def check_loaded(agent: Any, json_path: Path, world: RunWorld) -> None:
    """UserError naming ``json_path`` when the loaded ``agent`` itself says it was trained for
    another world than the run's: a Q table of another number of states or actions, another
    nominal robot, grid, action duration or goal
    (:func:`~skidnav.agents.trained_world.agent_mismatch`)."""
    q = getattr(agent, "q", None)
    if q is not None and q.shape != (world.grid.n_states, N_ACTIONS):
        raise UserError(
            f"{json_path}: it was trained on {q.shape[0]} states × {q.shape[1]} actions, the "
            f"run's grid has {world.grid.n_states} × {N_ACTIONS}"
        )
    problem = agent_mismatch(agent, world.robot, world.grid, world.action_duration, world.grid_map)
    if problem is not None:
        raise UserError(f"{json_path}: {problem}")
