"""The continuous optimum of a world: the oracle on fine state grids, and the path length [m]
of its best policy — the reference of the discretization gap (docs/discretization-gap.md).

For each grid of ``[experiment] optimum_grids`` (n_x, n_y, n_headings; a refinement of the map's
cells, :mod:`skidnav.experiments.reference.finegrid`) the oracle's model of the world is sampled and
solved on that grid (:func:`skidnav.experiments.reference.oracle.solve`, the world's own goal cell
and start pose), which gives V*(start), the expected actions of the best policy over that grid's
states under the sampled model. Its greedy policy is then rolled out ``optimum_rollouts`` times in
the world itself (the env on poses, each rollout from a reset with its own seed, at most the run's
action limit), and the path length [m] of each rollout that reached the goal is measured as the
runs' final length is (:func:`skidnav.experiments.metrics.path_length`, through the poses after each
action).

V*(start) of a finer grid is not a bound on what a policy of the pose can do, and a finer grid's
policy is not always better in the world: a policy over cells can press the robot against a wall
from one exact pose where the cell's sampled poses went free, and stay there. Every rollout is a
feasible path, so the **continuous optimum** is taken as the best policy found over the grids:
the one whose rollouts reached the goal most often, among those the fewest mean actions
(:func:`best_optimum`); its mean actions bound the optimum of the pose from above (up to the
rollouts' noise). It minimizes actions, the agents' objective (−1 per action), not metres: its
length in metres is that of the fewest-actions policy. The same choice without the finest grid
(``optimum_check_*``) shows whether refining further still finds better paths.

Results are cached on disk beside the oracles (``$SKIDNAV_CACHE_DIR/optima``) under the oracle's
key of the fine grid.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np

from skidnav.agents.greedy import greedy_path
from skidnav.envs.wrappers import FineStates
from skidnav.errors import CorruptFileError
from skidnav.experiments.config import ExperimentConfig
from skidnav.experiments.metrics import path_length
from skidnav.experiments.reference.finegrid import TablePolicy, state_grid
from skidnav.experiments.reference.oracle import _key, cache_dir, solve, write_cache
from skidnav.files.saved import ArraySpec, SavedArchive
from skidnav.seeding import seed_int

logger = logging.getLogger(__name__)


class Optimum(NamedTuple):
    """The continuous optimum of one world on one grid (module docs).

    Attributes:
        actions: V*(start) on the grid [actions] (inf when the goal is unreachable).
        length_m: mean path length [m] of the rollouts of its policy that reached the goal
            (NaN if none did).
        rollout_actions: mean actions of those rollouts.
        success: share of the rollouts that reached the goal.
    """

    actions: float
    length_m: float
    rollout_actions: float
    success: float


def compute_optimum(
    env: Any,
    levels: tuple[int, ...],
    n_samples: int,
    seed: int,
    seeds: Sequence[int],
    max_steps: int,
) -> Optimum:
    """The optimum of ``env``'s world (a skid-steer env with ``observation="pose"``) on the
    grid ``levels``, sampled with ``seed``, its policy rolled out once per seed of ``seeds`` for
    at most ``max_steps`` actions; without the cache."""
    nav = env.unwrapped
    grid = state_grid(nav, levels)
    solution = solve(nav, n_samples, np.random.default_rng(seed), grid)
    policy, fine = TablePolicy(solution.q), FineStates(nav, grid)
    lengths, actions = [], []
    for rollout_seed in seeds:
        poses, reached = greedy_path(policy, fine, max_steps, seed=int(rollout_seed))
        if reached:
            lengths.append(path_length(poses))
            actions.append(len(poses) - 1)
    nan = float("nan")
    return Optimum(
        solution.start_value,
        float(np.mean(lengths)) if lengths else nan,
        float(np.mean(actions)) if actions else nan,
        len(lengths) / len(seeds),
    )


def load_or_compute_optimum(
    env: Any,
    levels: tuple[int, ...],
    n_samples: int,
    seed: int,
    seeds: Sequence[int],
    max_steps: int,
) -> Optimum:
    """:func:`compute_optimum`, read from the on-disk cache when it holds it (a damaged cache
    file is logged and computed again)."""
    grid = state_grid(env.unwrapped, levels)
    key = _key(env, n_samples, seed, seeds, max_steps, grid)
    path = cache_dir() / "optima" / f"{key}.npz"
    if path.is_file():
        try:
            with SavedArchive(path) as archive:
                data = archive.read_all({name: ArraySpec((), "<f8") for name in Optimum._fields})
            return Optimum(*(float(data[name]) for name in Optimum._fields))
        except CorruptFileError as error:
            logger.warning("optimum cache unreadable, computing it again: %s", error)
    logger.info("continuous optimum on %s × %s × %s states", *levels)
    optimum = compute_optimum(env, levels, n_samples, seed, seeds, max_steps)
    write_cache(path, optimum._asdict(), "optimum")
    return optimum


def best_optimum(optima: Sequence[Optimum]) -> int:
    """Index of the best policy among ``optima`` (module docs): the highest rollout success,
    then the fewest mean rollout actions; the first of equals.

    >>> best_optimum([Optimum(14.0, 0.5, 13.0, 1.0), Optimum(13.6, 0.7, 18.5, 0.9),
    ...               Optimum(13.8, 0.48, 12.9, 1.0)])
    2
    """

    def rank(index: int) -> tuple[float, float, int]:
        actions = optima[index].rollout_actions
        return (-optima[index].success, actions if actions == actions else math.inf, index)

    return min(range(len(optima)), key=rank)


def optimum_columns(optima: Sequence[Optimum]) -> dict[str, float]:
    """A run's summary columns of its world's optima, one per grid, coarse to fine:
    ``optimum_*`` of the best (:func:`best_optimum`) and ``optimum_grid``, its index among the
    grids; ``optimum_check_*`` of the best without the last grid (NaN with one grid)."""
    nan = float("nan")
    best = best_optimum(optima)
    columns = {f"optimum_{name}": float(value) for name, value in optima[best]._asdict().items()}
    columns["optimum_grid"] = float(best)
    check = optima[best_optimum(optima[:-1])] if len(optima) > 1 else Optimum(nan, nan, nan, nan)
    columns.update({f"optimum_check_{name}": float(v) for name, v in check._asdict().items()})
    return columns


def world_optima(
    config: ExperimentConfig, env: Any, stream: np.random.SeedSequence, max_steps: int
) -> dict[str, float]:
    """The summary columns of the continuous optimum of a run's world on each of ``config``'s
    ``optimum_grids`` (module docs): ``env`` is the run's skid-steer env on poses
    (:func:`skidnav.experiments.trial.trial_env` with ``observation="pose"``), the seeds are drawn
    from the world's oracle ``stream`` (its children: the sampling seed, then one per rollout), so
    they are the same for every agent of a world."""
    seeds = [seed_int(child) for child in stream.spawn(1 + config.optimum_rollouts)]
    optima = [
        load_or_compute_optimum(env, levels, config.optimum_samples, seeds[0], seeds[1:], max_steps)
        for levels in config.optimum_grids
    ]
    return optimum_columns(optima)
