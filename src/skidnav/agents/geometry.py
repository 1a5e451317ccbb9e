"""The robot and the discretization an agent plans with, and how they are saved.

An agent that plans on the robot's kinematics (the model-based tabular agents,
``linear-dyna-kinematic``, ``mppi-kinematic``) keeps a :class:`~skidnav.robot.params.RobotParams`
and a :class:`~skidnav.world.discretization.Discretization`: :func:`geometry_from_task` takes them
from a navigation task (the nominal robot, never the slip field's truth), :func:`geometry_json`
and :func:`geometry_from_json` write and check them in a saved agent's JSON.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, fields
from typing import Any

from skidnav.errors import shown
from skidnav.robot.params import RobotParams
from skidnav.sim.navigation import NavigationTask
from skidnav.world.discretization import Discretization


def geometry_from_task(task: NavigationTask) -> tuple[RobotParams, Discretization]:
    """Robot and discretization of a navigation task. The robot is the task robot's datasheet
    (:class:`~skidnav.robot.datasheet.Datasheet`: wheel radius, half track, top wheel speed and
    the x_ICR its geometry states, with the task's timing and arena), the prior of every
    kinematic learner; never the floor's truth (its slip field, effective r and c, x_ICR)."""
    kc, grid = task.robot, task.grid
    robot = RobotParams(
        wheel_radius=kc.wheel_radius, half_track=kc.half_track, wheel_speed=kc.wheel_speed,
        dt=kc.dt, substeps=kc.substeps, arena_width=kc.arena_width,
        arena_height=kc.arena_height, integrator="exact" if kc.exact_integration else "euler",
        footprint_length=kc.footprint_length, footprint_width=kc.footprint_width,
    )  # fmt: skip
    discretization = Discretization(
        n_x=grid.n_x, n_y=grid.n_y, n_headings=grid.n_headings, regions_x=grid.regions_x,
        regions_y=grid.regions_y, arena_width=grid.arena_width, arena_height=grid.arena_height,
    )  # fmt: skip
    return robot, discretization


LATER_ROBOT_FIELDS = frozenset({"footprint_length", "footprint_width"})
"""Fields of :class:`RobotParams` that agents saved before them lack (a point robot)."""


def geometry_json(robot: RobotParams, grid: Discretization | None) -> dict[str, Any]:
    """The robot and discretization (None: no geometry) as saved in an agent's JSON: every
    field of :class:`RobotParams` and :class:`Discretization` by name."""
    return {"robot": asdict(robot), "discretization": None if grid is None else asdict(grid)}


def geometry_from_json(value: Any) -> tuple[RobotParams, Discretization | None]:
    """The robot and discretization of :func:`geometry_json`; ValueError (one line, quoting at
    most an excerpt) unless it is exactly that: the two tables with every field, of its type,
    finite, and valid for the dataclasses."""
    if not isinstance(value, Mapping) or set(value) != {"robot", "discretization"}:
        raise ValueError("expected a geometry with 'robot' and 'discretization'")
    robot = _dataclass_from_json(RobotParams, value["robot"], "robot", LATER_ROBOT_FIELDS)
    grid = value["discretization"]
    if grid is None:
        return robot, None
    return robot, _dataclass_from_json(Discretization, grid, "discretization")


def _dataclass_from_json(
    cls: Any, value: Any, where: str, later: frozenset[str] = frozenset()
) -> Any:
    """``cls(**value)`` once ``value`` has exactly ``cls``'s fields, each of its default's type
    (an int where an int is, a finite number where a float is); the fields ``later`` (added
    after files were first saved) may be absent, and take their defaults."""
    defaults = {field.name: field.default for field in fields(cls)}
    if not isinstance(value, Mapping) or not set(defaults) - later <= set(value) <= set(defaults):
        raise ValueError(f"expected the {where} fields {sorted(defaults)}")
    for name, default in defaults.items():
        if name not in value:
            continue
        item = value[name]
        if isinstance(default, bool) or isinstance(item, bool):
            ok = type(item) is type(default)
        elif isinstance(default, int):
            ok = isinstance(item, int)
        elif isinstance(default, float):
            ok = isinstance(item, (int, float)) and math.isfinite(item)
        else:
            ok = isinstance(item, type(default))
        if not ok:
            raise ValueError(f"expected {where}.{name} like {default!r}, got {shown(item)}")
    return cls(**value)
