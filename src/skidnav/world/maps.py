"""The one map builder: a map description (a generated kind with options, or a map file) to a
:class:`~skidnav.world.grid.GridMap`.

The experiment trial (``[[maps]]`` of a config), the real-time arena (``[run] map``) and the
skid-steer env (``map_kind`` / ``map_file``) all build their maps here, so one description and one
generator state give one map everywhere.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from skidnav.world.grid import GridMap, generate_map
from skidnav.world.mapfile import MapFileError, load_map


def build_map(
    rng: np.random.Generator,
    *,
    kind: str = "",
    file: str | Path | None = None,
    shape: tuple[int, int] | None = None,
    options: Mapping[str, Any] | None = None,
) -> GridMap:
    """The map read from ``file``, else generated: map kind ``kind`` drawn with ``rng``.

    Args:
        rng: the only source of randomness (unused for a file).
        kind: a generated map kind (:data:`~skidnav.world.grid.MAP_KINDS`); ``""`` with a file.
        file: a map file path, or None.
        shape: (n_x, n_y) cells the caller needs: a generated map has that size, a file's map
            must have it; None: a file of any size, a generated map of ``options``' shape or
            the generator's default.
        options: keyword arguments of :func:`~skidnav.world.grid.generate_map` (``shape``,
            ``min_distance``, ``max_tries``); a generated kind only.

    Raises:
        ValueError: both a kind and a file, options with a file, a second shape, an unknown
            kind or an option out of range.
        MapFileError: an unreadable or malformed file, or a map of another size than ``shape``.
    """
    if kind and file is not None:
        raise ValueError(f"expected a map kind or a map file, got both ({kind!r}, {str(file)!r})")
    settings = dict(options or {})
    if file is not None:
        if settings:
            raise ValueError("expected no options for a map file")
        grid_map = load_map(file)
        if shape is not None and grid_map.shape != tuple(shape):
            raise MapFileError(f"{file}: map is {grid_map.shape}, expected {tuple(shape)}")
        return grid_map
    if shape is not None:
        if "shape" in settings:
            raise ValueError(
                f"expected the map shape once, got {settings['shape']!r} and {shape!r}"
            )
        settings["shape"] = shape
    return generate_map(kind, rng, **settings)
