"""The arena a real-time run shares with its simulated robot: map, random streams, start pose.

The sim server and the real-time loop must agree on the map, so both build it here from the same
specification and root seed. Random streams: ``np.random.SeedSequence(seed).spawn(4)`` gives, in
order, the map, the slip field, the simulated robot (slip draws, noise, drops) and the agent.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from skidnav.errors import UserError
from skidnav.world.discretization import Discretization
from skidnav.world.grid import MAP_KINDS, GridMap, generate_map
from skidnav.world.mapfile import load_map

STREAMS = ("map", "slip", "robot", "agent")


def seed_streams(seed: int) -> dict[str, np.random.Generator]:
    """Independent generators named as :data:`STREAMS`, from one root seed."""
    children = np.random.SeedSequence(seed).spawn(len(STREAMS))
    return {
        name: np.random.default_rng(child) for name, child in zip(STREAMS, children, strict=True)
    }


def build_map(spec: str, seed: int, grid: Discretization) -> GridMap:
    """A map kind (``free``, ``obstacles``, ``maze``, generated from the map stream of ``seed``)
    or the path of a map file.

    Raises:
        UserError: unknown kind, unreadable file or a map of another size than ``grid``.
    """
    if spec in MAP_KINDS:
        try:
            return generate_map(spec, seed_streams(seed)["map"], (grid.n_x, grid.n_y))
        except ValueError as error:
            raise UserError(str(error)) from None
    path = Path(spec)
    if not path.is_file():
        raise UserError(f"map {spec!r} is neither one of {', '.join(MAP_KINDS)} nor a file")
    grid_map = load_map(path)
    if grid_map.shape != (grid.n_x, grid.n_y):
        raise UserError(f"{spec}: map is {grid_map.shape}, expected {(grid.n_x, grid.n_y)}")
    return grid_map


def start_pose(grid_map: GridMap, grid: Discretization) -> tuple[float, float, float]:
    """Centre of the start cell, heading 0 (+x), as the env (x [m], y [m], heading [rad])."""
    x, y = grid.cell_centre(*grid_map.start)
    return x, y, 0.0
