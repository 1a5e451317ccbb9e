"""The thesis's model-based agents: dyna-kinematic, trajectory-prioritized, dyna-full."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import skidnav.envs  # noqa: F401  (registers the env)
from skidnav.agents import kinematic_planning as kp
from skidnav.agents.greedy import greedy_rollout
from skidnav.agents.tabular.fast_training import train_agent_fast
from skidnav.agents.tabular.model_based import ModelBasedAgent
from skidnav.agents.tabular.registry import load_agent, make_agent
from skidnav.agents.training import train_agent
from skidnav.agents.trajectory_keys import loop_erase
from skidnav.envs.mazes import dyna_maze
from skidnav.errors import CorruptFileError
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SlipField
from skidnav.sim.navigation import transition
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap, border_walls

MODEL_BASED = ("dyna-kinematic", "trajectory-prioritized", "dyna-full")
SMALL = {
    "epsilon": 0.2,
    "epsilon_decay": 0.95,
    "epsilon_min": 0.01,
    "alpha": 0.5,
    "planning_steps": 10,
}


def small_env() -> gym.Env[Any, Any]:
    """A 9 × 9-cell, 10-heading arena of 0.25 m × 0.25 m without slip (deterministic)."""
    robot = RobotParams(arena_width=0.25, arena_height=0.25)
    grid = Discretization(
        n_x=9, n_y=9, n_headings=10, regions_x=2, regions_y=2, arena_width=0.25, arena_height=0.25
    )
    grid_map = GridMap(occupancy=border_walls((9, 9)), start=(2, 2), goal=(3, 6))
    slip = SlipField(
        eta=np.zeros((2, 2)), x_icr=np.full((2, 2), 0.05), drift_phase=np.zeros((2, 2))
    )
    return gym.make(
        "skidnav/SkidSteerNav-v0", grid_map=grid_map, robot=robot, discretization=grid,
        slip_field=slip, max_episode_steps=200,
    )  # fmt: skip


def shortest_path_length(env: gym.Env[Any, Any], limit: int = 7) -> int:
    """Fewest actions from the start to the goal, by exhaustive search of the deterministic
    simulator (action sequences up to ``limit``)."""
    nav: Any = env.unwrapped
    noise, log = np.zeros(20), np.zeros((10, 6))
    frontier = [nav.start_pose()]
    for depth in range(1, limit + 1):
        successors = []
        for pose in frontier:
            for action in range(4):
                moved = pose.copy()
                if transition(nav.task, moved, action, 0.0, noise, log).terminated:
                    return depth
                successors.append(moved)
        frontier = successors
    raise AssertionError("no path within the limit")


def make(name: str, env: gym.Env[Any, Any], seed: int, **options: Any) -> Any:
    context = {"task": env.unwrapped.task} if name in MODEL_BASED else {}  # type: ignore[attr-defined]
    config = {**SMALL, **options}
    if name == "q-learning":
        config.pop("planning_steps")
    n_states = int(env.observation_space.n)  # type: ignore[attr-defined]
    return make_agent(name, n_states, 4, config, np.random.default_rng(seed), **context)


@pytest.mark.parametrize("name", MODEL_BASED)
def test_each_finds_the_shortest_path_on_a_small_skidnav_map(name: str) -> None:
    env = small_env()
    optimum = shortest_path_length(env)
    # One fixed seed: on this aliased map trajectory-prioritized alone also settles on 6–11-action
    # paths for other seeds (docs/agents/trajectory-prioritized.md, "Measured").
    agent = make(name, env, seed=0)
    train_agent_fast(agent, env, 60, seed=0)
    assert greedy_rollout(agent, small_env(), 50) == optimum == 5


@pytest.mark.parametrize("name", MODEL_BASED)
def test_without_geometry_they_still_solve_the_dyna_maze(name: str) -> None:
    options = {"alpha": 0.1, "gamma": 0.95, "epsilon": 0.1, "initial_q": 1.0, "planning_steps": 20}
    agent = make_agent(name, 54, 4, options, np.random.default_rng(3))
    assert isinstance(agent, ModelBasedAgent) and agent.kinematic is None
    train_agent(agent, dyna_maze(), 40, seed=3)
    assert greedy_rollout(agent, dyna_maze(), 100) == 14


def test_model_based_agents_need_fewer_steps_than_q_learning() -> None:
    """Real steps spent in 40 episodes on the small map, mean over 3 seeds."""
    steps = {}
    for name in ("q-learning", *MODEL_BASED):
        totals = []
        for seed in range(3):
            env = small_env()
            totals.append(train_agent_fast(make(name, env, seed), env, 40, seed=seed).lengths.sum())
        steps[name] = float(np.mean(totals))
    for name in MODEL_BASED:
        assert steps[name] < 0.8 * steps["q-learning"], steps


def test_loop_erasure_keeps_a_chain_of_real_transitions() -> None:
    # states 1 → 2 → 3 → 2 → 4 → 1 → 5 (actions = step index), 4 actions
    states = [1, 2, 3, 2, 4, 1, 5]
    keys = np.array([s * 4 + k % 4 for k, s in enumerate(states)], dtype=np.int64)
    erased = loop_erase(keys, 4, 10)
    assert (erased // 4).tolist() == [1, 5]
    assert erased.tolist() == [keys[5], keys[6]]


def test_trajectory_sweeps_run_backward_from_the_goal() -> None:
    env = small_env()
    agent = make("dyna-full", env, seed=0)
    train_agent_fast(agent, env, 15, seed=0)
    assert 1 <= len(agent.trajectories) <= agent.config.n_trajectories
    lengths = [t.size for t in agent.trajectories]
    assert lengths == sorted(lengths)
    counters = agent.planner.counters
    sweep = agent.planner.trajectory_keys[: counters[kp.N_TRAJECTORY]]
    best = agent.trajectories[0]
    assert sweep[: best.size].tolist() == best[::-1].tolist()
    neighbours = agent.planner.neighbour_keys[: counters[kp.N_NEIGHBOURS]]
    assert neighbours.size > 0 and not np.isin(neighbours, sweep).any()
    assert np.unique(neighbours).size == neighbours.size


def test_kinematic_planning_values_pairs_never_visited() -> None:
    values = {}
    for name in ("dyna-q", "dyna-kinematic"):
        env = small_env()
        agent = make(name, env, seed=1)
        train_agent_fast(agent, env, 5, seed=1)
        visited = np.zeros(agent.q.size, dtype=bool)
        visited[agent.model.visited_pairs()] = True
        values[name] = int(np.count_nonzero(agent.q.ravel()[~visited]))
    assert values["dyna-q"] == 0
    assert values["dyna-kinematic"] > 100


def test_walls_guessed_from_collisions_are_real_walls() -> None:
    env = gym.make("skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=4)
    agent = make("dyna-kinematic", env, seed=0)
    train_agent_fast(agent, env, 5, seed=0, max_steps=300)
    walls = agent.planner.walls
    assert walls.sum() >= 5
    assert env.unwrapped.grid_map.occupancy[walls].all()  # type: ignore[attr-defined]


def test_reward_rows_follow_the_kinematic_table() -> None:
    """After whole refreshes (refits) and local ones (walls found), every prediction's reward
    row is the one its predicted state and outcome give (region, collision, goal)."""
    env = gym.make("skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=4, slip="slippery")
    agent = make("dyna-kinematic", env, seed=0)
    train_agent_fast(agent, env, 8, seed=0, max_steps=300)
    planner, grid = agent.planner, agent.kernel_grid
    assert agent.kinematic.refits >= 1 and planner.walls.sum() >= 5
    n_regions = planner.reward_stats.shape[0] - 2
    rows = [
        kp.reward_row(int(next_state), int(outcome), n_regions, grid)
        for next_state, outcome in zip(
            planner.pred_next.ravel(), planner.pred_outcome.ravel(), strict=True
        )
    ]
    np.testing.assert_array_equal(planner.pred_row.ravel(), rows)
    assert {n_regions, n_regions + 1} <= set(rows)  # collisions and the goal occur
    assert len(set(rows)) > n_regions // 2 + 2  # and free moves into most regions


@pytest.mark.parametrize("name", MODEL_BASED)
def test_save_load_round_trip_continues_identically(name: str, tmp_path: Path) -> None:
    env = small_env()
    agent = make(name, env, seed=2)
    train_agent_fast(agent, env, 12, seed=2)
    agent.save(tmp_path / "agent")
    loaded = load_agent(tmp_path / "agent")  # geometry comes from the file, no context needed
    assert np.array_equal(loaded.q, agent.q)
    assert [t.tolist() for t in loaded.trajectories] == [t.tolist() for t in agent.trajectories]
    for field in kp.PlannerArrays._fields[:9]:  # the table, velocities and the map
        assert np.array_equal(getattr(loaded.planner, field), getattr(agent.planner, field)), field
    twin = copy.deepcopy(env)
    train_agent_fast(agent, env, 3)
    train_agent_fast(loaded, twin, 3)
    assert np.array_equal(loaded.q, agent.q)
    assert loaded.planning_updates == agent.planning_updates


def test_kinematic_planning_only_with_a_discretization_and_kinematic_logs() -> None:
    # The size of the thesis grid alone is no geometry (e.g. any env with 12,500 states).
    guessed = make_agent("dyna-kinematic", 12_500, 4, None, np.random.default_rng(0))
    assert guessed.kinematic is None and guessed.discretization is None
    grid = Discretization()
    rng = np.random.default_rng(1)
    states = rng.integers(0, 200, (300, 2)).tolist()
    transitions = [
        (s, a, s2) for (s, s2), a in zip(states, rng.integers(0, 4, 300).tolist(), strict=True)
    ]
    unvisited_values = {}
    for logs in (False, True):
        agent = make_agent(
            "dyna-kinematic", grid.n_states, 4, {"planning_steps": 10}, np.random.default_rng(0),
            discretization=grid,
        )  # fmt: skip
        assert agent.kinematic is not None
        info = {"kinematic_log": np.zeros((0, 6))} if logs else {}
        for state, action, next_state in transitions:
            agent.observe(state, action, -1.0, next_state, False, False, info)
        visited = np.zeros(agent.q.size, dtype=bool)
        visited[agent.model.visited_pairs()] = True
        unvisited_values[logs] = int(np.count_nonzero(agent.q.ravel()[~visited]))
        assert agent.planner.counters[kp.USE_KINEMATIC] == int(logs)
    assert unvisited_values == {False: 0, True: unvisited_values[True]} and unvisited_values[True]


@pytest.fixture(scope="module")
def saved_dyna_full(tmp_path_factory: pytest.TempPathFactory) -> dict[str, np.ndarray]:
    env = small_env()
    agent = make("dyna-full", env, seed=2)
    train_agent_fast(agent, env, 12, seed=2)
    assert agent.trajectories and agent.planner.counters[kp.N_NEIGHBOURS] > 0
    folder = tmp_path_factory.mktemp("dyna-full")
    npz_path, json_path = agent.save(folder / "agent")
    with np.load(npz_path) as archive:
        arrays = {key: archive[key] for key in archive.files}
    return {"json": json_path.read_text(), **arrays}  # type: ignore[dict-item]


def _with(arrays: dict[str, Any], name: str, change: Any) -> dict[str, Any]:
    values = np.array(arrays[name])
    change(values)
    return {**arrays, name: values}


def _set(index: int, value: int) -> Any:
    return lambda values: values.__setitem__(index, value)


@pytest.mark.parametrize(
    ("name", "change", "problem"),
    [
        ("planner_counters", _set(kp.N_TRAJECTORY, 10**7), "N_TRAJECTORY"),
        ("planner_counters", _set(kp.TRAJECTORY_CURSOR, 10**7), "TRAJECTORY_CURSOR"),
        ("planner_counters", _set(kp.N_NEIGHBOURS, 0), "N_NEIGHBOURS"),
        ("planner_counters", _set(kp.NEIGHBOUR_CURSOR, -1), "NEIGHBOUR_CURSOR"),
        ("planner_counters", _set(kp.EPISODE_LENGTH, 10**6), "EPISODE_LENGTH"),
        ("planner_counters", _set(kp.USE_KINEMATIC, 2), "USE_KINEMATIC"),
        ("planner_trajectory_keys", _set(0, 10**9), "outside the Q table"),
        ("planner_neighbour_keys", _set(-1, -5), "outside the Q table"),
        ("trajectory_keys", _set(0, 4 * 810), "outside the Q table"),
        ("trajectory_lengths", _set(0, 1000), "trajectory lengths"),
        ("planner_reward_stats", _set(0, np.nan), "reward_stats"),
        ("planner_free_evidence", _set((0, 0), -1), "evidence are not counts"),
        ("planner_walls", lambda values: values.__setitem__((4, 4), ~values[4, 4]), "evidence"),
        ("model.entry_sibling", lambda values: values.fill(0), "model arrays"),
        ("kinematic_coefficients", _set(0, np.inf), "kinematic model coefficients"),
        ("kinematic_fitted_counts", _set(0, 10**6), "kinematic model sample counts"),
    ],
)
def test_files_with_valid_checksums_but_inconsistent_contents_are_rejected(
    saved_dyna_full: dict[str, Any], tmp_path: Path, name: str, change: Any, problem: str
) -> None:
    arrays = dict(saved_dyna_full)
    (tmp_path / "agent.json").write_text(arrays.pop("json"))
    np.savez_compressed(tmp_path / "agent.npz", **_with(arrays, name, change))
    with pytest.raises(CorruptFileError, match=problem):
        load_agent(tmp_path / "agent")
    np.savez_compressed(tmp_path / "agent.npz", **arrays)
    load_agent(tmp_path / "agent")  # the untouched file loads
