"""The references of one world, behind one entry point: what the best computable policy achieves
where a run's agent is evaluated, and the summary columns a run records of them.

:func:`world_reference` computes, in this order (each one draws only from its own seeds):

1. the **oracle** (:mod:`~skidnav.experiments.reference.oracle`): value iteration on the
   simulator's transition model estimated by sampling, its V*(start) = L* and C*, and its own
   rollouts from the evaluation seeds — on the skid-steer env with kinematic dynamics and the
   discrete actions only (a physics run, or one of wheel-speed actions, has none: its L* is
   NaN);
2. L* without an oracle: a grid maze's breadth-first shortest path, exact there; else NaN;
3. the **start plan** (:mod:`~skidnav.experiments.reference.start_plan`): the fewest actions from
   the exact start pose, replayed from every evaluation seed;
4. the **continuous optimum** on each of the config's ``optimum_grids``
   (:mod:`~skidnav.experiments.reference.optimum`).

The envs the references need are built by the caller (the trial owns how a run's envs are made)
and handed in as functions, so this package never imports the trial.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

import gymnasium
import numpy as np

from skidnav.experiments.config import ExperimentConfig
from skidnav.experiments.metrics import ConvergenceRule, evaluation_summary, within_tolerance
from skidnav.experiments.reference.optimum import world_optima
from skidnav.experiments.reference.oracle import Oracle, compute_oracle, load_or_compute_oracle
from skidnav.experiments.reference.start_plan import StartPlan, start_plan
from skidnav.seeding import seed_int

EnvFactory = Callable[[], gymnasium.Env[Any, Any]]
"""Builds one env of the run's world on demand (the oracle's discrete twin, the pose env)."""


class WorldReference(NamedTuple):
    """The references of one world (module docs).

    Attributes:
        length: L* [actions] (NaN where there is none).
        oracle: the oracle, or None (not the skid-steer env, or physics dynamics).
        plan: the start plan, or None (no oracle).
        optima: the continuous optimum's summary columns (empty without ``optimum_grids``).
    """

    length: float
    oracle: Oracle | None
    plan: StartPlan | None
    optima: dict[str, float]

    def optimum(self, objective: str) -> float:
        """What convergence is measured against: L*, or with the "cost" objective the oracle's
        C* (L* where there is no oracle: a grid maze's moves cost one each)."""
        if objective == "cost" and self.oracle is not None:
            return self.oracle.start_cost
        return self.length

    def summary_columns(self, rule: ConvergenceRule | None) -> dict[str, float]:
        """The run summary's columns of every reference (the oracle's, the start plan's judged
        by the run's convergence ``rule``, the optimum's)."""
        oracle = _oracle_columns(self.length, self.oracle)
        return {**oracle, **_plan_columns(self.plan, rule), **self.optima}


def has_oracle(env: gymnasium.Env[Any, Any]) -> bool:
    """True unless the skid-steer env runs on physics (``[env] dynamics = "mujoco"``) or takes
    wheel speeds (``[env] action = "continuous"``): the oracle solves the kinematic MDP of the
    thesis's four actions, so the L* and optimality gap of such a run are NaN."""
    nav = env.unwrapped
    kinematic = getattr(nav, "dynamics", "kinematic") == "kinematic"
    return kinematic and getattr(nav, "action_kind", "discrete") == "discrete"


def world_reference(
    config: ExperimentConfig,
    eval_env: gymnasium.Env[Any, Any],
    envs: tuple[EnvFactory, EnvFactory] | None,
    stream: np.random.SeedSequence,
    eval_seeds: Sequence[int],
    max_steps: int,
) -> WorldReference:
    """The references of a run's world (module docs).

    Args:
        config: the experiment (oracle samples, optimum grids).
        eval_env: the run's evaluation env (the start plan replays in it).
        envs: (the oracle's env on the discrete state, the pose env) of a skid-steer world, or
            None for an env without a map (a grid maze).
        stream: the world's oracle stream (the oracle's sampling seed and the optimum's).
        eval_seeds: the evaluation rollouts' reset seeds.
        max_steps: the action limit of an evaluation rollout.
    """
    oracle = None
    kinematic = envs is not None and has_oracle(eval_env)
    if kinematic and envs is not None:
        oracle = load_or_compute_oracle(
            envs[0](), config.oracle_samples, seed_int(stream), eval_seeds, max_steps
        )
    plan = start_plan(eval_env, eval_seeds, max_steps) if oracle is not None else None
    optima: dict[str, float] = {}
    if kinematic and envs is not None and config.optimum_grids:
        optima = world_optima(config, envs[1](), stream, max_steps)
    return WorldReference(_reference_length(oracle, eval_env), oracle, plan, optima)


def warm_up_references(
    eval_env: gymnasium.Env[Any, Any], oracle_env: EnvFactory, seed: int, max_steps: int
) -> None:
    """Compile the references' kernels on a throwaway world (the trial's warm-up)."""
    if has_oracle(eval_env):
        compute_oracle(oracle_env(), 1, 0, [seed], max_steps)
        start_plan(eval_env, [seed], max_steps)


def _reference_length(oracle: Oracle | None, env: gymnasium.Env[Any, Any]) -> float:
    """L*: the oracle's V*(start) on the skid-steer env; on a deterministic grid maze its
    breadth-first shortest path (``shortest_path_length``, exact there); else NaN."""
    if oracle is not None:
        return oracle.start_value
    shortest = getattr(env.unwrapped, "shortest_path_length", None)
    length = int(shortest()) if callable(shortest) else -1
    return float(length) if length > 0 else math.nan


def _oracle_columns(reference: float, oracle: Oracle | None) -> dict[str, float]:
    """L* and C* (without an oracle, C* = L*: a grid maze's moves cost one each, and elsewhere
    both are NaN); the means of the oracle's own rollouts (the action-optimal policy's lengths,
    NaN when any of them failed, and the cost-optimal policy's costs), the share of the
    action-optimal rollouts that reached the goal and the mean length of those that did: from
    one exact pose a greedy policy over cells can loop (an action that works on average over the
    cell hits a wall from that point, and is chosen again), so the oracle's expected length is a
    reference, not a policy every agent could follow."""
    nan = math.nan
    if oracle is None:
        return {
            "oracle_length": reference, "oracle_rollout_length": nan,
            "oracle_cost": reference, "oracle_rollout_cost": nan,
            "oracle_rollout_success": nan, "oracle_reached_length": nan,
        }  # fmt: skip
    lengths = oracle.rollout_lengths
    reached = lengths[lengths > 0]
    return {
        "oracle_length": reference, "oracle_rollout_length": oracle.rollout_mean,
        "oracle_cost": oracle.start_cost, "oracle_rollout_cost": oracle.rollout_cost,
        "oracle_rollout_success": float(reached.size / lengths.size),
        "oracle_reached_length": float(reached.mean()) if reached.size else nan,
    }  # fmt: skip


def _plan_columns(plan: StartPlan | None, rule: ConvergenceRule | None) -> dict[str, float]:
    """The start plan's length [actions] (NaN when none was found), the share of its replays
    that reached the goal, and whether its replays pass the run's convergence test (1.0 / 0.0;
    NaN when the test is measured in cost, which the replays do not record)."""
    nan = math.nan
    if plan is None or not len(plan.actions):
        return {"start_plan_length": nan, "start_plan_success": nan, "start_plan_passes": nan}
    mean, share = evaluation_summary(plan.rollout_lengths[None, :])
    passes = nan
    if rule is not None and rule.measure == "greedy_length":
        passes = float(within_tolerance(mean, share, rule)[0])
    return {
        "start_plan_length": float(len(plan.actions)),
        "start_plan_success": float(share[0]),
        "start_plan_passes": passes,
    }
