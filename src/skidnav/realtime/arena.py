"""The arena a real-time run shares with its simulated robot: map, random streams, start pose.

The sim server and the real-time loop must agree on the map, so both build it here from the same
specification and root seed. Random streams (:mod:`skidnav.seeding`): the children of the root
seed named by :data:`~skidnav.seeding.ARENA_ROLES` — the map, the slip field, the simulated robot
(slip draws, noise, drops) and the agent.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from skidnav.errors import UserError
from skidnav.seeding import ARENA_ROLES, streams
from skidnav.world.discretization import Discretization
from skidnav.world.grid import MAP_KINDS, GridMap
from skidnav.world.maps import build_map


def seed_streams(seed: int) -> dict[str, np.random.Generator]:
    """Independent generators named as :data:`~skidnav.seeding.ARENA_ROLES`, from one root
    seed."""
    return streams(seed, ARENA_ROLES)


def arena_map(spec: str, seed: int, grid: Discretization) -> GridMap:
    """The map of an arena ``[run] map`` (or ``--map``) names: a map kind (``free``,
    ``obstacles``, ``maze``, generated from the map stream of ``seed``) or the path of a map
    file, of ``grid``'s cells (:func:`skidnav.world.maps.build_map`).

    Raises:
        UserError: unknown kind, unreadable file or a map of another size than ``grid``.
    """
    shape = (grid.n_x, grid.n_y)
    rng = seed_streams(seed)["map"]
    if spec in MAP_KINDS:
        try:
            return build_map(rng, kind=spec, shape=shape)
        except ValueError as error:
            raise UserError(str(error)) from None
    if not Path(spec).is_file():
        raise UserError(f"map {spec!r} is neither one of {', '.join(MAP_KINDS)} nor a file")
    return build_map(rng, file=spec, shape=shape)


def start_pose(grid_map: GridMap, grid: Discretization) -> tuple[float, float, float]:
    """Centre of the start cell, heading 0 (+x), as the env (x [m], y [m], heading [rad])."""
    x, y = grid.cell_centre(*grid_map.start)
    return x, y, 0.0
