"""Tile coding: a hand-computed example, the layout of the features, refusals."""

from __future__ import annotations

import numpy as np
import pytest

from skidnav.agents.linear.tile_coding import MAX_FEATURES, active_tiles, check_coder, n_features


def tiles_of(
    observation: list[float], low: list[float], high: list[float], tiles: list[int], n: int
) -> list[int]:
    out = np.zeros(n, dtype=np.int64)
    active_tiles(np.array(observation), np.array(low), np.array(high), np.array(tiles), out)
    return out.tolist()


def test_a_two_dimensional_example_by_hand() -> None:
    # Box [0, 1] × [0, 2], 2 × 2 tiles (widths 0.5 and 1), 4 tilings: u = (0.6, 1.7). Tiling t is
    # shifted by t · (1, 3) / 4 tile widths modulo 1: offsets (0, 0), (.25, .75), (.5, .5),
    # (.75, .25); each tiling has 3 × 3 tiles, indexed (t · 3 + c0) · 3 + c1.
    # t = 0: c = (⌊0.6⌋, ⌊1.7⌋) = (0, 1) → 1;   t = 1: (⌊0.85⌋, ⌊2.45⌋) = (0, 2) → 9 + 2 = 11
    # t = 2: (⌊1.1⌋, ⌊2.2⌋) = (1, 2) → 18 + 5 = 23;   t = 3: (⌊1.35⌋, ⌊1.95⌋) = (1, 1) → 27 + 4 = 31
    assert tiles_of([0.3, 1.7], [0.0, 0.0], [1.0, 2.0], [2, 2], 4) == [1, 11, 23, 31]
    assert n_features(np.array([2, 2]), 4) == 36


def test_one_active_feature_per_tiling_inside_its_block() -> None:
    rng = np.random.default_rng(0)
    low, high, tiles = (
        np.array([0.0, -1.0, -np.pi]),
        np.array([0.62, 1.0, np.pi]),
        np.array([4, 3, 5]),
    )
    block = int(np.prod(tiles + 1))
    out = np.zeros(8, dtype=np.int64)
    for _ in range(200):
        active_tiles(rng.uniform(low, high), low, high, tiles, out)
        assert ((out // block) == np.arange(8)).all()


def test_outside_the_box_is_coded_as_its_nearest_boundary_point() -> None:
    box = ([0.0], [1.0], [4], 3)
    assert tiles_of([-5.0], *box) == tiles_of([0.0], *box)
    assert tiles_of([7.0], *box) == tiles_of([1.0], *box)


def test_nearby_points_share_more_tiles_than_distant_ones() -> None:
    box = ([0.0], [1.0], [4], 8)
    base = set(tiles_of([0.5], *box))
    assert len(base & set(tiles_of([0.52], *box))) > len(base & set(tiles_of([0.7], *box))) > 0


@pytest.mark.parametrize(
    ("low", "high", "tiles", "n_tilings", "message"),
    [
        ([0.0], [np.inf], [4], 8, "finite bounds"),
        ([1.0], [0.0], [4], 8, "high > low"),
        ([0.0], [1.0], [0], 8, "tiles >= 1"),
        ([0.0] * 8, [1.0] * 8, [9] * 8, 8, f"at most {MAX_FEATURES:,} features"),
    ],
)
def test_bad_coders_are_refused_in_one_line(
    low: list[float], high: list[float], tiles: list[int], n_tilings: int, message: str
) -> None:
    with pytest.raises(ValueError, match=message) as error:
        check_coder(np.array(low), np.array(high), np.array(tiles), n_tilings)
    assert "\n" not in str(error.value)
