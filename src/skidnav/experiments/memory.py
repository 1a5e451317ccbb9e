"""The memory an experiment's runs will need, checked when its config is read: a world whose
oracle (the optimal length every convergence verdict is judged against,
:mod:`skidnav.experiments.reference.oracle`) would not fit in :data:`MEMORY_BUDGET` is refused
before any run starts, with the size it would need, instead of each run failing with a
MemoryError.

The oracle holds the sampled next states of every (state, action) pair: an int32 array
(n_states, 4, samples); a world has n_x · n_y cells of its map times the env's 20 heading bins.

>>> oracle_bytes(25 * 25 * 20, 64) / 2**20  # the thesis arena [MiB]
12.20703125
>>> check_oracle_memory("map 'big'", 1000 * 1000 * 20, 64)  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
ValueError: map 'big': its oracle would need 19.1 GiB (20,000,000 states × 4 actions × ...
"""

from __future__ import annotations

from skidnav.experiments.config import ExperimentConfig, MapSpec
from skidnav.world.discretization import Discretization
from skidnav.world.mapfile import load_map_file

MEMORY_BUDGET = 4 * 2**30
"""Largest array a run may need [bytes] (4 GiB: two runs at a time fit a machine of 16 GiB)."""
N_ACTIONS = 4
"""The discrete actions an oracle samples."""
OUTCOME_BYTES = 4
"""One sampled next state (int32)."""


def oracle_bytes(n_states: int, samples: int) -> int:
    """Bytes of an oracle's outcomes over ``n_states`` states with ``samples`` per pair."""
    return n_states * N_ACTIONS * samples * OUTCOME_BYTES


def check_oracle_memory(where: str, n_states: int, samples: int) -> None:
    """ValueError naming ``where``, the size needed and the budget when an oracle over
    ``n_states`` states with ``samples`` per pair would exceed :data:`MEMORY_BUDGET`."""
    needed = oracle_bytes(n_states, samples)
    if needed > MEMORY_BUDGET:
        raise ValueError(
            f"{where}: its oracle would need {needed / 2**30:.1f} GiB ({n_states:,} states × "
            f"{N_ACTIONS} actions × {samples} samples × {OUTCOME_BYTES} bytes); the budget is "
            f"{MEMORY_BUDGET / 2**30:.1f} GiB: use a smaller map or fewer oracle_samples"
        )


def map_states(spec: MapSpec) -> int:
    """States of the env on map ``spec``: its cells (a file's, or a generated map's ``shape``
    option) times the env's heading bins; 0 for a ``shape`` that is not two integers (the map's
    own checks name it)."""
    grid = Discretization()  # the env's state grid without one of its own
    if spec.file:
        sides: object = load_map_file(spec.file).grid.shape
    else:
        sides = dict(spec.options).get("shape", (grid.n_x, grid.n_y))
    if not (
        isinstance(sides, tuple) and len(sides) == 2 and all(isinstance(n, int) for n in sides)
    ):
        return 0
    return int(sides[0]) * int(sides[1]) * grid.n_headings


def check_memory(config: ExperimentConfig) -> None:
    """ValueError (one line) when a world of ``config`` (a map, or an optimum grid) would need
    more than :data:`MEMORY_BUDGET` for its oracle."""
    for spec in config.maps:
        check_oracle_memory(f"map {spec.label!r}", map_states(spec), config.oracle_samples)
    for levels in config.optimum_grids:
        n_x, n_y, n_headings = levels
        where = f"optimum grid {list(levels)}"
        check_oracle_memory(where, n_x * n_y * n_headings, config.optimum_samples)
