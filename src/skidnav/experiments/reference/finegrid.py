"""The same world seen through a finer state grid: what a tabular agent with a
``discretization`` learns over, and what the oracle solves at a finer resolution
(docs/discretization-gap.md).

The world — walls, start pose, goal, slip field, robot — is the map's (25 × 25 cells by
default). A finer grid (n_x, n_y, n_headings) refines its cells by integer factors f_x, f_y
(n_x − 1 = f_x · (map's n_x − 1), :func:`skidnav.world.grid.refine_map`) and has any number of
heading bins. Two uses:

* :class:`FineStates` gives an agent the flat state of its pose on the finer grid while the env
  runs the world itself (``observation="pose"`` underneath), so the goal is still the map's goal
  cell, the start the same pose: only the agent's states are finer. The compiled trainer drives
  only the env's own states, so such runs train in the plain loop.
* :func:`refined_task` is the world's navigation task on the finer grid (the same walls in metres;
  its own goal, one fine cell, is replaced by :func:`goal_states`, every fine state inside the
  map's goal cell), for the oracle's sampled model
  (:func:`skidnav.experiments.reference.oracle.solve`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

import numpy as np

from skidnav.agents.catalog import CatalogEntry
from skidnav.errors import UserError, within
from skidnav.experiments.config import DEFAULT_ENV_ID, ExperimentConfig
from skidnav.sim.navigation import NavigationTask
from skidnav.sim.task import build_task
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap, refine_map


def state_grid(nav: Any, levels: tuple[int, ...]) -> Discretization:
    """The unwrapped skid-steer env ``nav``'s discretization with ``levels`` (n_x, n_y,
    n_headings) instead of its own (same arena and slip regions)."""
    n_x, n_y, n_headings = levels
    grid: Discretization = dataclasses.replace(
        nav.discretization, n_x=n_x, n_y=n_y, n_headings=n_headings
    )
    return grid


def refines_positions(levels: tuple[int, ...], grid_map: GridMap | None) -> bool:
    """True if ``levels`` (n_x, n_y, n_headings; () for none) have other cells than
    ``grid_map`` (not only other heading bins)."""
    return bool(levels) and grid_map is not None and (levels[0], levels[1]) != grid_map.shape


def refined_task(nav: Any, grid: Discretization) -> NavigationTask:
    """The navigation task of ``nav``'s world (its map refined to ``grid``'s cells, its slip
    field, robot and rewards) on ``grid``; ValueError when ``grid`` does not refine the map."""
    fine_map = refine_map(nav.grid_map, (grid.n_x, grid.n_y))
    return build_task(fine_map, nav.slip_field, nav.robot, grid, nav.task.rewards)


def goal_states(grid: Discretization, grid_map: GridMap) -> np.ndarray:
    """bool (grid.n_states,): the states of ``grid`` whose cell lies in ``grid_map``'s goal cell
    (fine cell i′ lies in coarse cell i′ // f_x, as :func:`~skidnav.world.grid.refine_map`).

    >>> from skidnav.world.grid import border_walls
    >>> coarse = GridMap(border_walls((5, 5)), start=(1, 1), goal=(2, 3))
    >>> goal = goal_states(Discretization(n_x=9, n_y=9, n_headings=2), coarse)
    >>> cells = [Discretization(9, 9, 2).unflatten(s)[:2] for s in np.flatnonzero(goal)]
    >>> int(goal.sum()), cells[::2]
    (8, [(4, 6), (4, 7), (5, 6), (5, 7)])
    """
    factor_x = (grid.n_x - 1) // (grid_map.shape[0] - 1)
    factor_y = (grid.n_y - 1) // (grid_map.shape[1] - 1)
    cells = grid.state_cells()
    goal_i, goal_j = grid_map.goal
    mask: np.ndarray = (cells[:, 0] // factor_x == goal_i) & (cells[:, 1] // factor_y == goal_j)
    return mask


class TablePolicy:
    """The greedy policy of a Q table (n_states, n_actions): the lowest action among the maxima,
    as :meth:`skidnav.agents.tabular.agent.TabularAgent.greedy_action`."""

    def __init__(self, q: np.ndarray) -> None:
        self.q = q

    def greedy_action(self, state: int) -> int:
        """The greedy action in ``state``."""
        return int(np.argmax(self.q[int(state)]))


def check_grids(
    config: ExperimentConfig,
    grid_map: GridMap,
    map_label: str,
    entries: Mapping[str, CatalogEntry],
) -> None:
    """UserError unless every agent's ``discretization`` and every ``optimum_grids`` entry
    refines ``grid_map``'s cells, and an agent on finer cells than the map's is a tabular agent
    that does not plan on the navigation task's own cells. ``entries``: the catalog entry of
    each agent name of ``config``."""
    wanted: list[tuple[str, tuple[int, ...], CatalogEntry | None]] = [
        (f"agent {a.label!r} discretization", a.discretization, entries[a.name])
        for a in config.agents
    ]
    wanted += [("optimum_grids", levels, None) for levels in config.optimum_grids]
    for what, levels, described in wanted:
        if not levels:
            continue
        if config.env_id != DEFAULT_ENV_ID:
            raise UserError(f"{what}: a discretization needs the {DEFAULT_ENV_ID} environment")
        if described is not None and described.family.name != "tabular":
            raise UserError(f"{what}: only tabular agents take a discretization")
        try:
            refine_map(grid_map, (levels[0], levels[1]))
        except ValueError as error:
            raise within(error, f"{what} on map {map_label!r}") from None
        fine = refines_positions(levels, grid_map)
        if described is not None and fine and described.asks_for("task"):
            raise UserError(
                f"{what}: {described.name!r} plans on the environment's own cells; finer cells "
                "than the map's take agents that learn from states alone (e.g. q-learning, "
                "dyna-q, dyna-q-plus, prioritized-sweeping)"
            )
