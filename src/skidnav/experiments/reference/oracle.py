"""The oracle of a world: the best expected trajectory length, and the best expected cost,
under the true simulator, so that "optimal length", "optimality gap" and "converged" have an
absolute meaning.

For a skid-steer world (map, slip field, robot, discretization) the oracle

1. estimates the true transition model of the discretized MDP from the simulator itself,
   ``n_samples`` poses per state and action, with each action's expected cost
   (:func:`skidnav.sim.value_iteration.sample_outcomes`);
2. solves it by value iteration (:func:`skidnav.sim.value_iteration.expected_costs`) twice: for the
   expected number of actions to the goal, and for the expected **cost** to the goal, an
   action's cost being minus its reward without the goal bonus
   (:func:`skidnav.sim.navigation.action_cost`: 1 + 10·var for a free step, 10 for a
   collision, and the action that reaches the goal costs what a free step ending there would);
3. takes V*(start), the expected actions from the exact start pose, as the **reference length**
   L*, and the expected cost from the exact start pose as the **reference cost** C*: the optimum
   of the reward the agents maximise (−1 − 10·var per step, −10 per collision, +10 at the goal,
   undiscounted), up to the goal bonus, the same on every path. On a floor with var ≈ 0, C* is
   at most L* plus 9 per collision the action-optimal policy expects; on a slippery floor
   C* > L*, and the cheapest path may take more actions than the shortest;
4. for information, rolls each objective's greedy policy out in the simulator from the start,
   once per evaluation seed — the evaluation every agent gets after each of its episodes
   (:func:`skidnav.agents.tabular.fast_training.evaluate_q_fast`). A greedy policy over cells can
   loop
   from one exact pose (an action that works on average over a cell fails from that point), so
   these rollouts are a diagnostic, not the reference.

The oracle keeps both greedy policies: ``q``, the action-optimal one (L*, ``rollout_lengths``), and
``cost_q``, the cost-optimal one (C*, ``rollout_costs``), whose objective is the agents' own. Its
costs use the slip field's true variance η²/12 even when the env rewards the observed variance
(``variance="observed"``), which estimates it.

Results are cached on disk (``$SKIDNAV_CACHE_DIR``, default ``~/.cache/skidnav``) under a hash of
everything they depend on (the task's arrays, the start pose, the sample count and seed, the
evaluation seeds and limit, :data:`ORACLE_VERSION`), written atomically and read back only
after its arrays are checked against the world (a damaged file is computed again), so the runs
of every agent on one world compute it once, in any process. The slip field is sampled at time
0: with a drifting floor the oracle is that of the initial floor.

**On a finer state grid** (``grid``: an agent's ``discretization`` that refines the map's cells, or
a grid of the continuous optimum, :mod:`skidnav.experiments.reference.optimum`) the same steps run
on the world's task refined to that grid
(:func:`skidnav.experiments.reference.finegrid.refined_task`: the same walls in metres), and every
fine state inside the map's goal cell counts as the goal, so the task stays the world's own: only
the states a policy sees are finer.
"""

from __future__ import annotations

import hashlib
import logging
import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from skidnav.agents.greedy import greedy_run
from skidnav.agents.tabular.fast_training import evaluate_q_fast
from skidnav.envs.wrappers import fine_grid
from skidnav.errors import CorruptFileError, UserError
from skidnav.experiments.memory import check_oracle_memory
from skidnav.experiments.reference.finegrid import TablePolicy, goal_states, refined_task
from skidnav.files.atomic import remove_stale_temporaries, write_npz_atomic
from skidnav.files.saved import ArraySpec, SavedArchive
from skidnav.sim.navigation import NavigationTask
from skidnav.sim.value_iteration import (
    GOAL_STATE,
    UNREACHABLE,
    expected_costs,
    oracle_q,
    sample_outcomes,
    start_costs,
)
from skidnav.world.discretization import Discretization

logger = logging.getLogger(__name__)

ORACLE_VERSION = 2
"""Bumped whenever the oracle's procedure changes (part of the cache key)."""
MAX_SWEEPS = 100_000
"""Value-iteration sweeps before giving up (the tolerance is reached in a few hundred)."""
SWEEP_TOLERANCE = 1e-9
"""Value iteration stops when no value moves by more than this [actions, or cost]."""


class Oracle(NamedTuple):
    """The oracle of one world.

    Attributes:
        q: float64 (n_states, n_actions), minus the expected actions to the goal after each
            action: the action-optimal greedy policy.
        start_value: expected actions from the start pose under the sampled model, V*(start)
            (its first action simulated from the exact start pose; inf when the goal is
            unreachable): the **reference length** L*.
        rollout_lengths: int64 (n_seeds,), lengths of the greedy rollouts of ``q`` in the
            simulator, one per evaluation seed (−1: goal not reached).
        rollout_mean: mean of ``rollout_lengths`` [actions]; NaN if any rollout failed (the
            greedy policy of a model over cells can loop from one exact pose: a diagnostic, not
            the reference).
        sweeps: value-iteration sweeps made for the actions.
        cost_q: float64 (n_states, n_actions), minus the expected cost to the goal after each
            action: the cost-optimal greedy policy.
        start_cost: expected cost from the start pose, as ``start_value`` (inf when the goal is
            unreachable): the **reference cost** C*.
        cost_rollout_lengths: int64 (n_seeds,), lengths of the greedy rollouts of ``cost_q``
            (−1: goal not reached).
        rollout_costs: float64 (n_seeds,), costs of those rollouts (NaN: goal not reached).
        rollout_cost: mean of ``rollout_costs``; NaN if any rollout failed.
        cost_sweeps: value-iteration sweeps made for the costs.
    """

    q: np.ndarray
    start_value: float
    rollout_lengths: np.ndarray
    rollout_mean: float
    sweeps: int
    cost_q: np.ndarray
    start_cost: float
    cost_rollout_lengths: np.ndarray
    rollout_costs: np.ndarray
    rollout_cost: float
    cost_sweeps: int


def cache_dir() -> Path:
    """Where oracles are cached: ``$SKIDNAV_CACHE_DIR`` or ``~/.cache/skidnav``."""
    return Path(os.environ.get("SKIDNAV_CACHE_DIR") or Path.home() / ".cache" / "skidnav")


def _key(
    env: Any,
    n_samples: int,
    seed: int,
    seeds: Sequence[int],
    max_steps: int,
    grid: Discretization | None = None,
) -> str:
    """Hex digest of everything the oracle of ``env`` depends on (its world, its step limit, the
    sampling and evaluation settings, the finer state grid if any)."""
    digest = hashlib.sha256(f"oracle-v{ORACLE_VERSION}".encode())
    nav = env.unwrapped
    limit = env.spec.max_episode_steps if env.spec is not None else None
    task = nav.task
    for part in (task.robot, task.grid, task.goal_i, task.goal_j, task.drift_amplitude,
                 task.drift_period, task.rewards, limit):  # fmt: skip
        digest.update(repr(part).encode())
    for array in (task.occupancy, task.eta, task.x_icr, task.wheel_radius, task.half_track,
                  task.drift_phase, nav.start_pose()):  # fmt: skip
        digest.update(np.ascontiguousarray(array).tobytes())
    digest.update(repr((n_samples, seed, [int(s) for s in seeds], max_steps)).encode())
    if grid is not None:  # absent for the map's own grid: the keys cached before stay valid
        digest.update(repr(("grid", grid)).encode())
    return digest.hexdigest()[:32]


class Solution(NamedTuple):
    """The solved sampled model of a world (:func:`solve`).

    Attributes:
        q: float64 (n_states, n_actions), as :attr:`Oracle.q`.
        start_value: as :attr:`Oracle.start_value` [actions].
        sweeps: value-iteration sweeps made for the actions.
        cost_q: float64 (n_states, n_actions), as :attr:`Oracle.cost_q`.
        start_cost: as :attr:`Oracle.start_cost`.
        cost_sweeps: value-iteration sweeps made for the costs.
    """

    q: np.ndarray
    start_value: float
    sweeps: int
    cost_q: np.ndarray
    start_cost: float
    cost_sweeps: int


def solve(
    nav: Any, n_samples: int, rng: np.random.Generator, grid: Discretization | None = None
) -> Solution:
    """Steps 1–3 of the module docs for the unwrapped skid-steer env ``nav``: sample its model
    (on ``grid``, a refinement of its map, when given; module docs), solve it for the actions
    and for the costs, and evaluate the exact start pose; every draw from ``rng``."""
    task, goal = _true_variance(nav.task), None
    if grid is not None:
        task = _true_variance(refined_task(nav, grid))
        goal = goal_states(grid, nav.grid_map)
    n_states, n_actions = grid.n_states if grid else int(nav.observation_space.n), 4
    outcomes = np.empty((n_states, n_actions, n_samples), dtype=np.int32)
    step_costs = np.empty((n_states, n_actions))
    sample_outcomes(task, n_samples, rng, outcomes, step_costs)
    if goal is not None:
        _end_in_goal(outcomes, goal)
    unit = np.ones((n_states, n_actions))
    action_values, sweeps = expected_costs(outcomes, unit, MAX_SWEEPS, SWEEP_TOLERANCE)
    cost_values, cost_sweeps = expected_costs(outcomes, step_costs, MAX_SWEEPS, SWEEP_TOLERANCE)
    if goal is not None:  # the first action from the start may end there (start_costs)
        action_values[goal] = cost_values[goal] = 0.0
    first = start_costs(task, nav.start_pose(), action_values, cost_values, n_samples, rng)
    return Solution(
        oracle_q(outcomes, unit, action_values), _best(first[0]), int(sweeps),
        oracle_q(outcomes, step_costs, cost_values), _best(first[1]), int(cost_sweeps),
    )  # fmt: skip


def _best(first: np.ndarray) -> float:
    """The least of the expected values after each first action, inf if the goal is
    unreachable."""
    best = float(first.min())
    return best if best < UNREACHABLE / 2 else math.inf


def _true_variance(task: NavigationTask) -> NavigationTask:
    """``task`` scored with the slip field's true variance (module docs), which also leaves the
    env's observed wheel-speed statistics as they were."""
    return task._replace(rewards=task.rewards._replace(observed_variance=False))


def _end_in_goal(outcomes: np.ndarray, goal: np.ndarray, chunk: int = 65_536) -> None:
    """Make every sampled outcome in a ``goal`` state (bool (n_states,)) a goal arrival and the
    goal states no sources, in place, ``chunk`` source states at a time (no copy of the whole
    array)."""
    for first in range(0, len(outcomes), chunk):
        block = outcomes[first : first + chunk]
        block[goal[np.maximum(block, 0)] & (block >= 0)] = GOAL_STATE
    outcomes[goal] = -2


def compute_oracle(
    env: Any, n_samples: int, seed: int, seeds: Sequence[int], max_steps: int
) -> Oracle:
    """The oracle of ``env``'s world (module docs), without the cache.

    Args:
        env: a ``skidnav/SkidSteerNav-v0`` env (wrapped or not) with discrete observations, or a
            :class:`~skidnav.envs.wrappers.FineStates` view of one (the oracle on
            its finer grid); its evaluation resets are used for the rollouts.
        n_samples: sampled poses per state (each tries every action), ≥ 1.
        seed: seed of the sampling generator.
        seeds: evaluation seeds (one rollout each).
        max_steps: action limit of each rollout.
    """
    if n_samples < 1:
        raise ValueError(f"expected n_samples >= 1, got {n_samples}")
    grid = fine_grid(env)
    n_states = grid.n_states if grid is not None else int(env.observation_space.n)
    try:  # a world's config is checked when read; this is the last guard before allocating
        check_oracle_memory("the world", n_states, n_samples)
    except ValueError as error:
        raise UserError(str(error)) from None
    solution = solve(env.unwrapped, n_samples, np.random.default_rng(seed), grid)
    lengths, _ = _rollouts(env, solution.q, seeds, max_steps, grid)
    cost_lengths, costs = _rollouts(env, solution.cost_q, seeds, max_steps, grid)
    return Oracle(
        solution.q, solution.start_value, lengths, _mean_if_all(lengths, lengths),
        solution.sweeps, solution.cost_q, solution.start_cost, cost_lengths, costs,
        _mean_if_all(costs, cost_lengths), solution.cost_sweeps,
    )  # fmt: skip


def _rollouts(
    env: Any, q: np.ndarray, seeds: Sequence[int], max_steps: int, grid: Discretization | None
) -> tuple[np.ndarray, np.ndarray]:
    """(lengths int64, costs float64), each (n_seeds,), of the greedy rollouts of ``q`` on
    ``env``, one per seed: compiled on the map's own grid, else on the finer states (−1 and NaN:
    goal not reached)."""
    if grid is None:
        return evaluate_q_fast(q, env, seeds, max_steps)
    policy = TablePolicy(q)
    rollouts = [greedy_run(policy, env, max_steps, seed=int(seed)) for seed in seeds]
    return (
        np.array([rollout.length for rollout in rollouts], np.int64),
        np.array([rollout.cost for rollout in rollouts], np.float64),
    )


def _mean_if_all(values: np.ndarray, lengths: np.ndarray) -> float:
    """Mean of ``values`` when every rollout of ``lengths`` reached the goal, else NaN."""
    return float(values.mean()) if (lengths > 0).all() else float("nan")


def load_or_compute_oracle(
    env: Any, n_samples: int, seed: int, seeds: Sequence[int], max_steps: int
) -> Oracle:
    """:func:`compute_oracle`, read from the on-disk cache when it holds this world's oracle (a
    damaged cache file is logged and computed again)."""
    grid = fine_grid(env)
    key = _key(env, n_samples, seed, seeds, max_steps, grid)
    path = cache_dir() / "oracles" / f"{key}.npz"
    shape = (int(env.observation_space.n), int(env.action_space.n))
    if path.is_file():
        try:
            return _load(path, shape, len(seeds))
        except CorruptFileError as error:
            logger.warning("oracle cache unreadable, computing it again: %s", error)
    oracle = compute_oracle(env, n_samples, seed, seeds, max_steps)
    write_cache(path, oracle._asdict(), "oracle")
    return oracle


def _load(path: Path, shape: tuple[int, int], n_seeds: int) -> Oracle:
    """The cached oracle at ``path``, its arrays checked against the world's ``shape``
    (n_states, n_actions) and the ``n_seeds`` evaluation seeds before they are read."""
    scalar, count = ArraySpec((), "<f8"), ArraySpec((), "<i8")
    specs = {
        "q": ArraySpec(shape, "<f8"),
        "start_value": scalar,
        "rollout_lengths": ArraySpec((n_seeds,), "<i8"),
        "rollout_mean": scalar,
        "sweeps": count,
        "cost_q": ArraySpec(shape, "<f8"),
        "start_cost": scalar,
        "cost_rollout_lengths": ArraySpec((n_seeds,), "<i8"),
        "rollout_costs": ArraySpec((n_seeds,), "<f8"),
        "rollout_cost": scalar,
        "cost_sweeps": count,
    }
    with SavedArchive(path) as archive:
        data = archive.read_all(specs)
    # the scalars back as Python floats and ints, as computed
    values: dict[str, Any] = {
        name: data[name] if data[name].ndim else data[name].item() for name in specs
    }
    return Oracle(**values)


def write_cache(path: Path, arrays: Mapping[str, Any], what: str) -> None:
    """Write ``arrays`` to the cache file ``path`` atomically (a failure to cache is only logged,
    naming ``what``); first remove the temporaries of cache writers that died."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        remove_stale_temporaries(path.parent)
        write_npz_atomic(path, {name: np.asarray(value) for name, value in arrays.items()})
    except OSError as error:
        logger.warning("could not cache the %s in %s: %s", what, path, error)
