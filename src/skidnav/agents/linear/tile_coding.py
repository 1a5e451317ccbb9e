"""Tile coding of a continuous observation (Sutton & Barto (2018) §9.5.4), compiled.

An observation ``x`` (float64, shape (k,)) inside the box ``[low, high]`` is covered by
``n_tilings`` grids (*tilings*). Along dimension ``j`` a tile is ``w_j = (high_j − low_j) /
tiles_j`` wide; tiling ``t`` is displaced from the first by ``t · (1, 3, 5, …, 2k − 1) · w /
n_tilings`` (the asymmetric displacement vector the book recommends, §9.5.4), taken modulo one
tile width. Each tiling therefore has ``tiles_j + 1`` tiles along dimension ``j`` (the shifted
grid overhangs the box by less than one tile), and the weight vector has

    n_features = n_tilings · Π_j (tiles_j + 1)

entries, one per tile of every tiling. Along dimension ``j``, in tiling ``t``, the tile holding
``x`` is

    c_j = ⌊u_j + ((t · (2j + 1)) mod n_tilings) / n_tilings⌋,   u_j = (x_j − low_j) / w_j

with ``u_j`` clipped to ``[0, tiles_j]`` (an observation outside the box is coded as the nearest
point of its boundary). The active feature of tiling ``t`` is the row-major index of
``(t, c_0, …, c_{k−1})`` in the shape ``(n_tilings, tiles_0 + 1, …, tiles_{k−1} + 1)``, so
exactly one feature per tiling is active and the indices are increasing in ``t``.

No hashing: every tile has its own weight; callers refuse sizes above a bound
(:data:`MAX_FEATURES`). A dimension that wraps around (a heading in [−π, π]) is tiled as an
interval like any other: its two ends fall in different tiles.

>>> import numpy as np
>>> low, high, tiles = np.array([0.0]), np.array([1.0]), np.array([4])
>>> out = np.zeros(2, dtype=np.int64)
>>> active_tiles(np.array([0.6]), low, high, tiles, out)  # u = 2.4; offsets 0 and 1/2
>>> out.tolist()  # tiling 0: tile 2; tiling 1: ⌊2.9⌋ = 2, after the 5 tiles of tiling 0
[2, 7]
"""

from __future__ import annotations

import numpy as np

from skidnav._jit import jit

MAX_FEATURES = 2**22
"""Most features (weights per action) a tile coder may have: 4,194,304, 32 MiB per action."""


def n_features(tiles: np.ndarray, n_tilings: int) -> int:
    """``n_tilings · Π (tiles + 1)``: the length of the weight vector per action (exact Python
    integer, so an oversized coder is refused instead of overflowing).

    >>> n_features(np.array([4, 4, 4]), 8)
    1000
    """
    size = int(n_tilings)
    for count in tiles.tolist():
        size *= int(count) + 1
    return size


def check_coder(low: np.ndarray, high: np.ndarray, tiles: np.ndarray, n_tilings: int) -> int:
    """Validate a tile coder and return its number of features; one-line ValueError naming the
    problem (bounds not finite or not increasing, a tile count below 1, too many features)."""
    if low.ndim != 1 or low.shape != high.shape or low.shape != tiles.shape or low.size == 0:
        raise ValueError(
            f"expected low, high and tiles of one shape (k,), got {low.shape}, {high.shape}, "
            f"{tiles.shape}"
        )
    if not (np.isfinite(low).all() and np.isfinite(high).all() and (high > low).all()):
        raise ValueError(f"expected finite bounds with high > low, got {low} and {high}")
    if (tiles < 1).any() or n_tilings < 1:
        raise ValueError(f"expected tiles >= 1 and n_tilings >= 1, got {tiles}, {n_tilings}")
    size = n_features(tiles, n_tilings)
    if size > MAX_FEATURES:
        raise ValueError(
            f"expected at most {MAX_FEATURES:,} features, got {size:,} "
            f"({n_tilings} tilings × Π(tiles + 1)); use fewer tiles or tilings"
        )
    return size


@jit
def active_tiles(
    observation: np.ndarray, low: np.ndarray, high: np.ndarray, tiles: np.ndarray, out: np.ndarray
) -> None:
    """Write the active feature of each tiling into ``out`` (int64, shape (n_tilings,)).

    ``observation``, ``low``, ``high``: float64 (k,) in the observation's units; ``tiles``:
    int64 (k,) tiles per dimension. Draws nothing; no allocation.
    """
    n_tilings = out.shape[0]
    k = observation.shape[0]
    for tiling in range(n_tilings):
        index = tiling
        for dim in range(k):
            count = tiles[dim]
            scaled = (observation[dim] - low[dim]) / (high[dim] - low[dim]) * count
            scaled = min(max(scaled, 0.0), float(count))
            offset = ((tiling * (2 * dim + 1)) % n_tilings) / n_tilings
            index = index * (count + 1) + int(scaled + offset)  # ≥ 0: int() is the floor
        out[tiling] = index
