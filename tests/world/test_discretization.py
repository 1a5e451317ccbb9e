import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from skidnav.world.discretization import Discretization, squeezes_between_walls

DISC = Discretization()


def test_thesis_indices():
    # i = floor(x/0.62·24), j = floor(y/0.505·24), k = floor(atan2/2π·20) + 10
    x, y, heading = 0.3, 0.2, 2.0
    i, j, k = DISC.unflatten(DISC.state(x, y, heading))
    assert (i, j) == (math.floor(x / 0.62 * 24), math.floor(y / 0.505 * 24))
    assert k == math.floor(heading / (2 * math.pi) * 20) + 10
    assert DISC.region(x, y) == math.floor(x / 0.62 * 6) * 7 + math.floor(y / 0.505 * 6)


def test_heading_pi_wraps_to_the_first_bin():
    assert DISC.unflatten(DISC.state(0.3, 0.2, math.pi))[2] == 0
    assert DISC.unflatten(DISC.state(0.3, 0.2, -math.pi))[2] == 0
    assert DISC.unflatten(DISC.state(0.3, 0.2, 3 * math.pi - 1e-9))[2] == 19


@given(x=st.floats(0, 0.62), y=st.floats(0, 0.505), heading=st.floats(-20, 20, allow_nan=False))
def test_flat_index_round_trips(x, y, heading):
    state = DISC.state(x, y, heading)
    assert 0 <= state < DISC.n_states
    i, j, k = DISC.unflatten(state)
    assert (i, j) == DISC.cell(x, y)
    assert (i * DISC.n_y + j) * DISC.n_headings + k == state


def test_levels_are_configurable():
    disc = Discretization(n_x=11, n_y=9, n_headings=8, regions_x=3, regions_y=3)
    assert disc.n_states == 11 * 9 * 8
    cells = disc.state_cells()
    assert cells.shape == (disc.n_states, 2) and cells.max(axis=0).tolist() == [10, 8]
    assert disc.cell(0.62, 0.505) == (10, 8)
    with pytest.raises(ValueError, match="n_x"):
        Discretization(n_x=1)
    assert np.isclose(disc.heading_centre(0), -math.pi + math.pi / 8)


@pytest.mark.parametrize("levels", [(25, 25), (11, 9), (2, 3)])
def test_every_cell_centre_lies_in_its_cell_and_in_the_arena(levels):
    disc = Discretization(n_x=levels[0], n_y=levels[1])
    for i in range(disc.n_x):
        for j in range(disc.n_y):
            x, y = disc.cell_centre(i, j)
            assert 0.0 <= x <= disc.arena_width and 0.0 <= y <= disc.arena_height
            assert disc.cell(x, y) == (i, j)
    # the last level is the zero-width boundary cell: its "centre" is the arena's edge
    assert disc.cell_centre(disc.n_x - 1, disc.n_y - 1) == (disc.arena_width, disc.arena_height)


def test_a_diagonal_move_squeezes_between_walls_only_when_both_cells_beside_it_are_walls():
    walls = np.zeros((4, 4), dtype=bool)
    assert not squeezes_between_walls(walls, 1, 1, 2, 2)
    walls[1, 2] = True  # beside the move (1, 1) → (2, 2): a corner, with room beside it
    assert not squeezes_between_walls(walls, 1, 1, 2, 2)
    walls[2, 1] = True  # and the other: two walls meeting at the corner the move goes through
    assert squeezes_between_walls(walls, 1, 1, 2, 2) and squeezes_between_walls(walls, 2, 2, 1, 1)
    assert not squeezes_between_walls(walls, 1, 1, 2, 1)  # into a wall: not a squeeze
    assert not squeezes_between_walls(walls, 2, 2, 3, 3)
