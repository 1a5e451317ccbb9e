"""The oracle: value iteration on hand-made models, and on small maps whose optimum is known;
the expected cost beside the expected actions."""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
from pathlib import Path

import gymnasium
import numpy as np
import pytest

import skidnav  # noqa: F401  (registers the env)
from skidnav.experiments.reference.oracle import Oracle, compute_oracle, load_or_compute_oracle
from skidnav.sim.value_iteration import (
    GOAL_STATE,
    UNREACHABLE,
    expected_actions,
    expected_costs,
    oracle_q,
    sample_outcomes,
)
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
    q = oracle_q(_chain(), np.ones((4, 2)), values)
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


def _reference_actions(outcomes: np.ndarray, tolerance: float) -> np.ndarray:
    """Gauss–Seidel value iteration for the expected actions written out for unit costs:
    V(s) = min(1 + mean V(s′), UNREACHABLE), in state order."""
    values = np.full(len(outcomes), UNREACHABLE)
    while True:
        change = 0.0
        for state in range(len(outcomes)):
            if outcomes[state, 0, 0] < -1:
                continue
            after = [
                1.0 + sum(values[s] for s in outcomes[state, a] if s >= 0) / outcomes.shape[2]
                for a in range(outcomes.shape[1])
            ]
            best = min(min(after), UNREACHABLE)
            change = max(change, abs(best - values[state]))
            values[state] = best
        if change <= tolerance:
            return values


def test_unit_costs_give_the_expected_actions_bit_for_bit() -> None:
    rng = np.random.default_rng(4)
    outcomes = rng.integers(-1, 40, size=(40, 4, 3)).astype(np.int32)
    outcomes[[5, 17]] = -2  # walls
    unit = np.ones((40, 4))
    values, _ = expected_costs(outcomes, unit, 10_000, 1e-12)
    assert values.tobytes() == _reference_actions(outcomes, 1e-12).tobytes()
    assert values.tobytes() == expected_actions(outcomes, 10_000, 1e-12)[0].tobytes()


def _detour() -> tuple[np.ndarray, np.ndarray]:
    """6 states, 2 actions, 2 samples, and each action's cost. From 0, a0 leads through 1,
    whose step to the goal costs 9; a1 leads through 2 and 3 at cost 1 each. State 4 gambles:
    a0 reaches the goal in one sample of two at cost 3, else stays. State 5 is a wall. Every
    other action stays where it is at cost 1."""
    outcomes = np.empty((6, 2, 2), dtype=np.int32)
    costs = np.ones((6, 2))
    for state in range(5):
        outcomes[state, 1] = state
    outcomes[0] = [[1, 1], [2, 2]]
    outcomes[1, 0], costs[1, 0] = GOAL_STATE, 9.0
    outcomes[2, 0] = 3
    outcomes[3, 0] = GOAL_STATE
    outcomes[4, 0], costs[4, 0] = [GOAL_STATE, 4], 3.0
    outcomes[5] = -2
    return outcomes, costs


def test_expected_cost_of_a_hand_made_model() -> None:
    outcomes, costs = _detour()
    actions, _ = expected_actions(outcomes, 10_000, 1e-12)
    values, _ = expected_costs(outcomes, costs, 10_000, 1e-12)
    assert actions[:5].tolist() == pytest.approx([2.0, 1.0, 2.0, 1.0, 2.0])
    # V(1) = 9, V(0) = min(1 + 9, 1 + V(2)) = 3, V(4) = 3 + V(4)/2 = 6
    assert values[:5].tolist() == pytest.approx([3.0, 9.0, 2.0, 1.0, 6.0])
    q = oracle_q(outcomes, costs, values)
    assert q[0].tolist() == pytest.approx([-10.0, -3.0])  # the cheaper path takes more actions
    assert oracle_q(outcomes, np.ones((6, 2)), actions)[0].argmax() == 0


def _fingerprint(oracle: Oracle) -> str:
    digest = hashlib.sha256(np.ascontiguousarray(oracle.q).tobytes())
    digest.update(
        f"{oracle.start_value!r},{oracle.rollout_lengths.tolist()},{oracle.sweeps}".encode()
    )
    return digest.hexdigest()[:16]


@pytest.mark.parametrize(
    ("slip", "fingerprint"), [("thesis", "59919f93255b7169"), ("slippery", "38eb2c1b00d50274")]
)
def test_the_expected_actions_are_pinned(slip: str, fingerprint: str) -> None:
    """The action-optimal Q table, L*, its rollouts and sweeps: a change of this fingerprint is a
    change of the oracle's numbers, to be made deliberately and stated."""
    env = gymnasium.make("skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=5, slip=slip,
                         max_episode_steps=120)  # fmt: skip
    assert _fingerprint(compute_oracle(env, 8, 3, [0, 1, 2], 120)) == fingerprint


def test_on_the_thesis_floor_the_cost_is_the_number_of_actions() -> None:
    # η ≤ 0.012 rad/s there: a free step costs 1 + 10·η²/12 < 1.0002, and the open floor
    # between start and goal leaves no wall to run into.
    oracle = compute_oracle(_env(goal=(9, 9)), 16, 0, [0, 1, 2], 50)
    assert oracle.start_value > 5.0
    assert oracle.start_value <= oracle.start_cost <= oracle.start_value * 1.001
    assert (oracle.cost_rollout_lengths > 0).all()
    assert np.allclose(oracle.rollout_costs, oracle.cost_rollout_lengths, rtol=1e-3)
    assert oracle.rollout_cost == pytest.approx(oracle.rollout_costs.mean())


def test_goal_one_action_ahead_costs_one_free_step() -> None:
    oracle = compute_oracle(_env(goal=(3, 2)), 8, 0, [0, 1, 2], 50)
    assert oracle.start_cost == 1.0  # η = 0 in the goal's region: the step costs 1 exactly
    assert oracle.rollout_costs.tolist() == [1.0, 1.0, 1.0]


def _evaluate(outcomes: np.ndarray, costs: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, ...]:
    """(expected actions, expected cost) of the greedy policy of ``q`` on a sampled model: the
    solver on the model where every action of a state does what the policy's does."""
    chosen = q.argmax(axis=1)
    rows = np.arange(len(outcomes))
    only = np.repeat(outcomes[rows, chosen][:, None, :], outcomes.shape[1], axis=1)
    only_costs = np.repeat(costs[rows, chosen][:, None], outcomes.shape[1], axis=1)
    return expected_actions(only, 100_000, 1e-9)[0], expected_costs(
        only, only_costs, 100_000, 1e-9
    )[0]


def test_on_a_slippery_floor_the_cheapest_path_takes_more_actions() -> None:
    env = gymnasium.make("skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=0,
                         slip="slippery").unwrapped  # fmt: skip
    n_states = int(env.observation_space.n)
    outcomes = np.empty((n_states, 4, 16), dtype=np.int32)
    costs = np.empty((n_states, 4))
    sample_outcomes(env.task, 16, np.random.default_rng(0), outcomes, costs)
    actions, _ = expected_actions(outcomes, 100_000, 1e-9)
    cheapest, _ = expected_costs(outcomes, costs, 100_000, 1e-9)
    start = env.reset(seed=0)[0]
    shortest_policy = _evaluate(outcomes, costs, oracle_q(outcomes, np.ones_like(costs), actions))
    cheapest_policy = _evaluate(outcomes, costs, oracle_q(outcomes, costs, cheapest))
    assert cheapest[start] > actions[start] + 10.0  # C* > L*: slip and collisions cost more
    assert cheapest_policy[0][start] > actions[start] + 5.0  # ... and the cheapest path is longer
    assert cheapest_policy[1][start] == pytest.approx(cheapest[start])
    assert shortest_policy[0][start] == pytest.approx(actions[start])
    assert shortest_policy[1][start] > cheapest[start] + 10.0  # the shortest path costs more


def test_the_oracle_is_deterministic() -> None:
    env = gymnasium.make("skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=5,
                         slip="slippery", max_episode_steps=120)  # fmt: skip
    first, again = (compute_oracle(env, 4, 3, [0, 1, 2], 120) for _ in range(2))
    for name, value in first._asdict().items():
        assert np.asarray(value).tobytes() == np.asarray(getattr(again, name)).tobytes(), name
    assert first.start_cost > first.start_value


NO_JIT_SCRIPT = """
import hashlib
import gymnasium, numpy as np
import skidnav
from skidnav.agents.tabular.fast_training import train_agent_fast
from skidnav.agents.training import Evaluation
from skidnav.agents.tabular.registry import make_agent
from skidnav.experiments.reference.oracle import compute_oracle
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization

robot = RobotParams(arena_width=0.3, arena_height=0.3)
grid = Discretization(n_x=10, n_y=10, n_headings=10, arena_width=0.3, arena_height=0.3)
make = lambda: gymnasium.make("skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=2,
                              slip="slippery", robot=robot, discretization=grid,
                              max_episode_steps=60)
oracle = compute_oracle(make(), 2, 1, [0, 1], 60)
config = {"epsilon": 0.3, "planning_steps": 10}
agent = make_agent("dyna-q", grid.n_states, 4, config, np.random.default_rng(2))
log = train_agent_fast(agent, make(), 10, evaluation=Evaluation(make(), [0, 1]), seed=4)
digest = hashlib.sha256()
for value in (*oracle, log.greedy_lengths, log.greedy_costs):
    digest.update(np.asarray(value).tobytes())
reached = [int(np.isfinite(costs).sum()) for costs in (oracle.rollout_costs, log.greedy_costs)]
print(digest.hexdigest(), *reached)
"""


def _no_jit_digest(disable_jit: bool) -> str:
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).parents[2] / "src"))
    env["NUMBA_DISABLE_JIT"] = "1" if disable_jit else "0"
    result = subprocess.run(
        [sys.executable, "-c", NO_JIT_SCRIPT], env=env, capture_output=True, text=True,
        check=True, timeout=600,
    )  # fmt: skip
    return result.stdout.strip()


def test_costs_are_bit_identical_with_and_without_jit() -> None:
    compiled = _no_jit_digest(disable_jit=False)
    assert compiled == _no_jit_digest(disable_jit=True)
    _, oracle_reached, agent_reached = compiled.split()
    assert int(oracle_reached) > 0 and int(agent_reached) > 0  # rollouts that reached the goal
