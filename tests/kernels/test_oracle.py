"""The oracle: value iteration on hand-made models, and on small maps whose optimum is known."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest

import skidnav  # noqa: F401  (registers the env)
from skidnav.experiments.oracle import compute_oracle, load_or_compute_oracle
from skidnav.kernels.oracle import GOAL_STATE, UNREACHABLE, expected_actions, oracle_q
from skidnav.world.grid import GridMap, border_walls


def _chain() -> np.ndarray:
    """4 states, 2 actions, 2 samples. State 0 --a0--> 1 --a0--> goal; a1 from 0: half the
    samples reach the goal, half stay; state 2 loops on itself; state 3 is a wall (−2)."""
    outcomes = np.empty((4, 2, 2), dtype=np.int32)
    outcomes[0, 0] = [1, 1]
    outcomes[0, 1] = [GOAL_STATE, 0]
    outcomes[1, 0] = [GOAL_STATE, GOAL_STATE]
    outcomes[1, 1] = [0, 0]
    outcomes[2] = 2
    outcomes[3] = -2
    return outcomes


def test_value_iteration_on_a_hand_made_model() -> None:
    values, sweeps = expected_actions(_chain(), 10_000, 1e-12)
    # V(1) = 1. V(0) = min(1 + V(1), 1 + V(0)/2) = min(2, 2) (the fixed point of V = 1 + V/2).
    assert values[1] == pytest.approx(1.0)
    assert values[0] == pytest.approx(2.0)
    assert values[2] >= UNREACHABLE  # never reaches the goal
    assert sweeps > 1
    q = oracle_q(_chain(), values)
    assert q[1].tolist() == pytest.approx([-1.0, -3.0])
    assert q[3].tolist() == [0.0, 0.0]


def _env(goal: tuple[int, int], walls: list[tuple[int, int]] = ()) -> gymnasium.Env:  # type: ignore[assignment]
    occupancy = border_walls((25, 25))
    for cell in walls:
        occupancy[cell] = True
    grid_map = GridMap(occupancy, start=(2, 2), goal=goal)
    return gymnasium.make(
        "skidnav/SkidSteerNav-v0", grid_map=grid_map, slip="thesis", max_episode_steps=50
    )


def test_goal_one_action_ahead() -> None:
    # Start at the centre of cell 2 heading +x: one forward action (3.8 cm, cells 2.58 cm) ends
    # in cell 3.
    oracle = compute_oracle(_env(goal=(3, 2)), 8, 0, [0, 1, 2], 50)
    assert oracle.start_value == pytest.approx(1.0)
    assert oracle.rollout_lengths.tolist() == [1, 1, 1]
    assert oracle.rollout_mean == 1.0


def test_goal_two_forward_actions_ahead_is_at_least_two() -> None:
    # Two forward actions from the centre of cell 2 end at x = 6.46 + 7.66 cm = cell 5, and no
    # action sequence does it in one. The oracle's value is an expectation over the poses of
    # each state (a policy over cells cannot aim from one exact pose), so it may exceed 2.
    oracle = compute_oracle(_env(goal=(5, 2)), 64, 0, [0, 1], 50)
    assert 2.0 <= oracle.start_value <= 5.0
    assert (oracle.rollout_lengths >= 2).all()


def test_walled_off_goal_is_unreachable() -> None:
    ring = [
        (i, j) for i in range(9, 14) for j in range(9, 14) if not (10 <= i <= 12 and 10 <= j <= 12)
    ]
    oracle = compute_oracle(_env(goal=(11, 11), walls=ring), 4, 0, [0], 50)
    assert oracle.start_value == float("inf")
    assert np.isnan(oracle.rollout_mean)


def test_the_cache_returns_the_same_oracle(tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setenv("SKIDNAV_CACHE_DIR", str(tmp_path))
    first = load_or_compute_oracle(_env(goal=(5, 2)), 4, 3, [0], 50)
    files = list((tmp_path / "oracles").glob("*.npz"))
    assert len(files) == 1
    again = load_or_compute_oracle(_env(goal=(5, 2)), 4, 3, [0], 50)
    assert again.start_value == first.start_value
    assert np.array_equal(again.q, first.q)
    other = load_or_compute_oracle(_env(goal=(6, 2)), 4, 3, [0], 50)  # another world, another key
    assert len(list((tmp_path / "oracles").glob("*.npz"))) == 2
    assert other.start_value != first.start_value
    files[0].write_bytes(b"not a zip file")  # a corrupt cache entry is computed again
    assert load_or_compute_oracle(_env(goal=(5, 2)), 4, 3, [0], 50).start_value == first.start_value
