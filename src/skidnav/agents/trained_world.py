"""The world a saved agent was trained for, written beside it, and the check that a robot run
is that world (``skidnav run`` with ``save_agents``, ``skidnav robot run --agent-file``;
docs/robot-learning.md).

A saved agent's own files say what its family needs to rebuild it (:mod:`skidnav.agents.saved`),
not always where it learned: a Q table is a table of states, whatever the robot or the goal.
``world.json`` beside ``agent.json`` records that world once for every family: the nominal robot
(its datasheet geometry), the discretization, the duration of one action [s] and the map (walls,
start and goal cells), with ``map.txt``, the same map as a map file a robot config can name.

>>> from skidnav.world.grid import GridMap, border_walls
>>> trained = TrainedWorld("q-learning", RobotParams(), Discretization(), 1.0,
...                        GridMap(border_walls((25, 25)), (5, 5), (15, 15)))
>>> run_map = GridMap(border_walls((25, 25)), (5, 5), (16, 15))
>>> trained.mismatch(RobotParams(), Discretization(), 1.0, run_map)
"it was trained for the goal cell (15, 15), the run's map has its goal at (16, 15)"
>>> trained.mismatch(RobotParams(), Discretization(), 0.1, trained.grid_map)
"it was trained with actions of 1 s, the run's last 0.1 s (set [run] period × substeps to 1 s)"
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from skidnav.agents.geometry import geometry_from_json, geometry_json
from skidnav.errors import CorruptFileError, first_line, shown
from skidnav.files.atomic import write_atomic
from skidnav.files.saved import read_json
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization
from skidnav.world.grid import MAX_SIZE, GridMap, refine_map
from skidnav.world.mapfile import format_map

WORLD_FILE = "world.json"
MAP_FILE = "map.txt"
WORLD_FORMAT = "skidnav-trained-world"
WORLD_VERSION = 1
MAX_WORLD_BYTES = 4 * 2**20
"""Largest ``world.json`` read [bytes] (a 25 × 25 map takes about 2 kB)."""
DATASHEET = ("wheel_radius", "half_track", "front_axle", "rear_axle", "x_icr", "wheel_speed")
"""The robot's fields a run must share with the trained world (its timing is the action
duration, checked on its own; the arena is the discretization's)."""


@dataclass(frozen=True)
class TrainedWorld:
    """Where an agent was trained.

    Attributes:
        agent: the agent's registry name.
        robot: the nominal robot (the datasheet its model starts from).
        discretization: cells, heading bins and slip regions of the arena.
        action_duration: one action [s] (the env's ``dt × substeps``).
        grid_map: walls, start and goal cells.
    """

    agent: str
    robot: RobotParams
    discretization: Discretization
    action_duration: float
    grid_map: GridMap

    def to_json(self) -> dict[str, Any]:
        """The ``world.json`` content."""
        return {
            "format": WORLD_FORMAT,
            "version": WORLD_VERSION,
            "agent": self.agent,
            "geometry": geometry_json(self.robot, self.discretization),
            "action_duration": self.action_duration,
            "start": list(self.grid_map.start),
            "goal": list(self.grid_map.goal),
            "walls": self.grid_map.occupancy.astype(np.int8).tolist(),
        }

    def files(self) -> dict[str, bytes]:
        """``world.json`` and ``map.txt`` by name."""
        text = json.dumps(self.to_json(), separators=(",", ":"))
        return {WORLD_FILE: text.encode("utf-8"), MAP_FILE: format_map(self.grid_map).encode()}

    def write(self, folder: Path) -> None:
        """Write :meth:`files` into ``folder``, each atomically."""
        for name, data in self.files().items():
            write_atomic(folder / name, data)

    def mismatch(
        self,
        robot: RobotParams,
        grid: Discretization,
        action_duration: float,
        grid_map: GridMap,
    ) -> str | None:
        """What of a run (its nominal ``robot``, ``grid``, actions of ``action_duration`` [s]
        and ``grid_map``) differs from this world, in a phrase; None if nothing does."""
        walls = self.grid_map.occupancy
        return (
            robot_mismatch(self.robot, robot)
            or grid_mismatch(self.discretization, grid)
            or duration_mismatch(self.action_duration, action_duration)
            or goal_mismatch(self.grid_map.goal, grid_map)
            or (
                "it was trained in an arena of other walls than the run's map"
                if walls.shape != grid_map.occupancy.shape or (walls != grid_map.occupancy).any()
                else None
            )
        )


def robot_mismatch(trained: RobotParams, robot: RobotParams) -> str | None:
    """The first datasheet field (:data:`DATASHEET`) of ``robot`` that differs from
    ``trained``'s, in a phrase; None if none does."""
    for name in DATASHEET:
        mine, theirs = getattr(trained, name), getattr(robot, name)
        if not math.isclose(mine, theirs, rel_tol=1e-9, abs_tol=1e-12):
            return f"it was trained for a robot of {name} {mine:g}, the run's has {theirs:g}"
    return None


def grid_mismatch(trained: Discretization, grid: Discretization) -> str | None:
    """A phrase naming both arenas/grids if they differ; None if they do not."""
    if trained == grid:
        return None
    mine, theirs = _grid_text(trained), _grid_text(grid)
    return f"it was trained on the arena/grid {mine}, the run's is {theirs}"


def duration_mismatch(trained: float, action_duration: float) -> str | None:
    """A phrase naming both action durations [s] if they differ; None if they do not."""
    if math.isclose(trained, action_duration, rel_tol=1e-9):
        return None
    return (
        f"it was trained with actions of {trained:g} s, the run's last {action_duration:g} s "
        f"(set [run] period × substeps to {trained:g} s)"
    )


def goal_mismatch(trained: tuple[int, int], grid_map: GridMap) -> str | None:
    """A phrase naming both goal cells if ``grid_map``'s is not ``trained``; None if it is."""
    if tuple(trained) == tuple(grid_map.goal):
        return None
    return (
        f"it was trained for the goal cell {tuple(trained)}, the run's map has its goal at "
        f"{tuple(grid_map.goal)}"
    )


def agent_mismatch(
    agent: Any, robot: RobotParams, grid: Discretization, action_duration: float, grid_map: GridMap
) -> str | None:
    """What the saved ``agent`` itself says of its world that a run differs from (for an agent
    without ``world.json``): its nominal ``robot`` (datasheet and action duration), its
    ``discretization`` and its ``goal`` cell, those of them it has; None if nothing differs."""
    trained_robot = getattr(agent, "robot", None)
    trained_grid = getattr(agent, "discretization", None)
    goal = getattr(agent, "goal", None)
    phrases = []
    if isinstance(trained_robot, RobotParams):
        phrases.append(robot_mismatch(trained_robot, robot))
    if isinstance(trained_grid, Discretization):
        phrases.append(grid_mismatch(trained_grid, grid))
    if isinstance(trained_robot, RobotParams):
        phrases.append(duration_mismatch(trained_robot.action_duration, action_duration))
    if goal is not None:
        phrases.append(goal_mismatch(goal, grid_map))
    return next((phrase for phrase in phrases if phrase), None)


def _grid_text(grid: Discretization) -> str:
    return (
        f"{grid.n_x} × {grid.n_y} cells × {grid.n_headings} headings, {grid.regions_x} × "
        f"{grid.regions_y} regions, {grid.arena_width:g} × {grid.arena_height:g} m"
    )


def trained_world(agent: str, env: Any) -> TrainedWorld | None:
    """The world of the navigation env ``env`` an agent named ``agent`` was trained in (its
    discretization the one ``env`` shows the agent, e.g. a finer grid's, else the unwrapped
    env's), or None for an env without a robot and a map (a grid world)."""
    nav = getattr(env, "unwrapped", env)
    robot, grid_map = getattr(nav, "robot", None), getattr(nav, "grid_map", None)
    grid = getattr(env, "discretization", None) or getattr(nav, "discretization", None)
    if not (isinstance(robot, RobotParams) and isinstance(grid, Discretization)):
        return None
    if not isinstance(grid_map, GridMap):
        return None
    if grid_map.shape != (grid.n_x, grid.n_y):
        grid_map = refine_map(grid_map, (grid.n_x, grid.n_y))
    return TrainedWorld(agent, robot, grid, robot.action_duration, grid_map)


def world_beside(json_path: Path, agent: str) -> TrainedWorld | None:
    """The ``world.json`` beside the saved agent ``json_path`` (its registry name ``agent``), or
    None when there is none; CorruptFileError in one line naming it when it is not a trained
    world or is that of another agent."""
    world_path = json_path.parent / WORLD_FILE
    if not world_path.is_file():
        return None
    trained = read_trained_world(world_path)
    if trained.agent != agent:
        raise CorruptFileError(
            f"{world_path}: the world of agent {trained.agent!r}, not of {json_path.name}'s "
            f"{agent!r}"
        )
    return trained


def read_trained_world(path: Path) -> TrainedWorld:
    """The ``world.json`` at ``path``; CorruptFileError in one line naming it when it is not
    one."""
    data = read_json(path, max_bytes=MAX_WORLD_BYTES, what="trained world")
    try:
        return _world_from_json(data)
    except (KeyError, TypeError, ValueError) as error:
        raise CorruptFileError(f"{path}: not a trained world ({first_line(error, 120)})") from None


def _world_from_json(data: dict[str, Any]) -> TrainedWorld:
    if data.get("format") != WORLD_FORMAT or data.get("version") != WORLD_VERSION:
        raise ValueError(f"expected format {WORLD_FORMAT!r} version {WORLD_VERSION}")
    robot, grid = geometry_from_json(data["geometry"])
    if grid is None:
        raise ValueError("expected a discretization")
    duration = data["action_duration"]
    if type(duration) not in (int, float) or not 0 < duration < math.inf:
        raise ValueError(f"expected action_duration > 0 s, got {shown(duration)}")
    walls = np.asarray(data["walls"])
    if walls.ndim != 2 or not 3 <= min(walls.shape) <= max(walls.shape) <= MAX_SIZE:
        raise ValueError("expected walls to be a table of cells")
    if not np.isin(walls, (0, 1)).all():
        raise ValueError("expected walls of 0 and 1")
    cells = [_cell(data[key], key) for key in ("start", "goal")]
    grid_map = GridMap(walls.astype(bool), cells[0], cells[1])
    agent = data["agent"]
    if not isinstance(agent, str):
        raise ValueError(f"expected an agent name, got {shown(agent)}")
    return TrainedWorld(agent, robot, grid, float(duration), grid_map)


def _cell(value: Any, key: str) -> tuple[int, int]:
    if not (
        isinstance(value, list)
        and len(value) == 2
        and all(type(v) is int and v >= 0 for v in value)
    ):
        raise ValueError(f"expected {key} to be a cell [i, j], got {shown(value)}")
    return value[0], value[1]
