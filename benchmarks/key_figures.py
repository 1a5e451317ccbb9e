"""The key ratios of ``make bench``: each compiled path's rate against its twin's (the same work
as plain Python, or as a ``SyncVectorEnv`` of single envs; for the expected planning update, the
same planning loop with the most-probable target), both measured in the same process,
one after the other, on one core. A ratio, not a time, is what is compared: both sides slow down
alike on a loaded machine.

Each figure is measured here and nowhere else, by the functions of the ``bench_*`` scripts, for
three readers:

* the speed guard of ``make test`` (``tests/test_speed_guard.py``): the quick sizes, each ratio
  of a twin measured in the same process against its :attr:`KeyFigure.floor`
  (:attr:`KeyFigure.guarded`);
* the history (``benchmarks/tracked``, recorded per commit by airspeed velocity);
* the speed table of ``docs/speed.md``, written by ``make bench`` from that record.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import bench_agents
import bench_env
import bench_mppi
import bench_mppi_single
import bench_planning_targets
import bench_sim
import bench_training
import bench_vector


class KeyFigure(NamedTuple):
    """One key ratio.

    Attributes:
        compiled: the compiled path measured (a row of the speed table).
        twin: the path it is compared with.
        unit: what its rates count per second.
        floor: the guard fails below this ratio: about a third of the lowest ratio measured on
            the 2-core CI machine (also with the other core busy), so that noise passes and a
            slowdown of 3× or more does not.
        measure: ``measure(quick)`` → (compiled rate, twin rate) [unit/s]; ``quick`` the
            guard's sizes (a few seconds), else ``make bench``'s.
        guarded: the speed guard checks it. A figure against a fixed rate (the control period
            of a real robot), not against a twin measured in the same process, is recorded and
            tabled but not guarded: on a loaded machine only one side slows down.
    """

    compiled: str
    twin: str
    unit: str
    floor: float
    measure: Callable[[bool], tuple[float, float]]
    guarded: bool = True


def vector_rates(kwargs: dict[str, str]) -> Callable[[bool], tuple[float, float]]:
    """:func:`bench_vector.native_and_sync` of the case ``kwargs``, 256 sub-envs."""
    return lambda quick: bench_vector.native_and_sync(kwargs, *((100, 10) if quick else (400, 20)))


def simulator_rates(quick: bool) -> tuple[float, float]:
    """The batch kernel's actions/s (:mod:`bench_sim`) and the same kernel's as plain Python."""
    compiled = bench_sim.batch_actions_per_second(50_000 if quick else 400_000, 3)
    return compiled, bench_sim.interpreted_actions_per_second()


def env_step_rates(quick: bool) -> tuple[float, float]:
    """``env.step`` through ``gymnasium.make`` (:mod:`bench_env`), compiled and plain Python."""
    return bench_env.median_rate(10_000 if quick else 50_000), bench_env.interpreted_rate()


def planning_rates(quick: bool) -> tuple[float, float]:
    """Dyna-Q planning updates/s (:mod:`bench_agents`): the compiled kernel and a dict-based
    plain-Python Dyna-Q on the same learned model."""
    agent = bench_agents.trained_dyna_agent()
    n_updates = (1_000_000, 50_000) if quick else (5_000_000, 200_000)
    return (
        bench_agents.compiled_rate(agent, n_updates[0]),
        bench_agents.plain_python_rate(agent, n_updates[1]),
    )


def training_rates(quick: bool) -> tuple[float, float]:
    """Dyna-Q's real steps/s in the fused trainer and as plain Python (:mod:`bench_training`)."""
    episodes = 5 if quick else bench_training.EPISODES
    compiled = bench_training.best_rate("dyna-q", True, episodes)
    return compiled, bench_training.plain_python_rate("dyna-q")


WHEEL_SPEEDS = {"action": "continuous", "observation": "features"}
FIGURES = {
    "vector-wheel-speeds": KeyFigure(
        "native vector env, 256 sub-envs, wheel speeds, features", "SyncVectorEnv",
        "sub-env steps", 4.0, vector_rates(WHEEL_SPEEDS),
    ),
    "vector-discrete": KeyFigure(
        "native vector env, 256 sub-envs, discrete", "SyncVectorEnv", "sub-env steps", 6.0,
        vector_rates({}),
    ),
    "simulator-batch": KeyFigure(
        "batch simulator (10 sub-steps per action)", "plain Python", "actions", 50.0,
        simulator_rates,
    ),
    "env-step": KeyFigure(
        "env.step through gymnasium.make", "plain Python", "steps", 2.0, env_step_rates
    ),
    "dyna-q-planning": KeyFigure(
        "Dyna-Q planning kernel", "dict-based plain-Python Dyna-Q", "updates", 12.0,
        planning_rates,
    ),
    "expected-planning": KeyFigure(
        "model-based planning loop, expected update (trajectory-prioritized, obstacles arena)",
        "the same loop, most-probable update", "updates", 0.3,
        bench_planning_targets.expected_and_most_probable,
    ),
    "fused-training": KeyFigure(
        "fused trainer, dyna-q, obstacles arena", "plain Python", "real steps", 10.0,
        training_rates,
    ),
    "mppi-rollouts": KeyFigure(
        "mppi-kinematic's rollouts, 256 sequences × 40 steps of 0.1 s",
        "the same in vectorised NumPy", "sequences", 5.0, bench_mppi.rollout_rates,
    ),
    "mppi-step": KeyFigure(
        "mppi-kinematic, one whole control step (256 × 40: sampling, rollouts, update)",
        "the same step in NumPy", "control steps", 2.0, bench_mppi.step_rates,
    ),
    "mppi-real-time": KeyFigure(
        "mppi-kinematic, one whole control step (256 × 40)", "the 0.1-s control period",
        "control steps", 10.0, bench_mppi.real_time_rates, guarded=False,
    ),
    "mppi-step-float32": KeyFigure(
        "mppi-kinematic's fast path (precision float32), one whole control step (256 × 40)",
        "the same step in NumPy", "control steps", 5.0, bench_mppi_single.step_rates,
    ),
    "mppi-target-float32": KeyFigure(
        "mppi-kinematic's fast path, one whole control step (256 × 40)",
        "the target, 0.3 ms (35 M sample-steps/s)", "control steps", 1.0,
        bench_mppi_single.target_rates, guarded=False,
    ),
}  # fmt: skip
"""The key figures by name (the history's and the guard's parameter)."""
