"""Finer grids inherit the walls of the map: the same metres are walls on both grids."""

from __future__ import annotations

import numpy as np
import pytest

from skidnav.world.discretization import Discretization
from skidnav.world.grid import generate_map, refine_map


@pytest.mark.parametrize("fine", [(49, 49), (73, 97), (25, 25)])
def test_finer_cells_inherit_the_walls_at_every_position(fine):
    coarse = generate_map("obstacles", np.random.default_rng(3))
    refined = refine_map(coarse, fine)
    coarse_grid, fine_grid = Discretization(), Discretization(n_x=fine[0], n_y=fine[1])
    rng = np.random.default_rng(0)
    for x, y in zip(rng.uniform(0, 0.62, 3000), rng.uniform(0, 0.505, 3000), strict=True):
        assert coarse.occupancy[coarse_grid.cell(x, y)] == refined.occupancy[fine_grid.cell(x, y)]
    assert refined.occupancy.sum() >= coarse.occupancy.sum()  # equal: the identity (25, 25)


def test_the_start_pose_and_the_goal_stay_where_they_were():
    coarse = generate_map("obstacles", np.random.default_rng(5))
    for fine in ((49, 49), (73, 73)):
        refined = refine_map(coarse, fine)
        grid = Discretization(n_x=fine[0], n_y=fine[1])
        start = Discretization().cell_centre(*coarse.start)
        assert grid.cell(*start) == refined.start  # the start pose lies in the fine start cell
        goal = grid.cell_centre(*refined.goal)
        assert Discretization().cell(*goal) == coarse.goal


def test_a_grid_that_does_not_nest_is_refused_in_one_line():
    coarse = generate_map("free", np.random.default_rng(0))
    with pytest.raises(ValueError, match=r"^expected n_y − 1 to be a multiple of 24 .*got 50$"):
        refine_map(coarse, (49, 50))
