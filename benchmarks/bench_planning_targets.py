"""The expected planning update against the most-probable one, in the same planning loop.

Both rates time :func:`skidnav.agents.kinematic_planning.combined_planning` of one learned
``trajectory-prioritized`` agent (obstacles arena, :func:`bench_agents.arena_agent` after its
warm-up episodes at 1000 planning updates per real step), on fresh copies of its Q table and
planner and a generator of the same seed: the same pairs are drawn, only the target differs —
Σ_s′ p(s′|s, a) (r̄ + γ (1 − β) max_a′ Q(s′, a′)) over the model's outcomes, or the most probable
outcome's (Sutton & Barto (2018) §8.5; the model's outcomes per pair are ~1.03 on this arena).
``trajectory-prioritized`` because every one of its updates reads a model target (the kinematic
agents send half to the kinematic table), so the target's cost shows most.

The ratio is the speed guard's figure ``expected-planning``: the expected target went through a
compiled call that reference-counted the model's 21 arrays at every update, 9× the most-probable
update's time; inlined, the two cost about the same.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from bench_agents import REPEATS, WARM_UP, arena_agent

from skidnav.agents import kinematic_planning as kp
from skidnav.agents.tabular.fast_training import train_agent_fast
from skidnav.models.multinomial_targets import EXPECTED, MOST_PROBABLE

AGENT = "trajectory-prioritized"


def planning_seconds(agent: Any, mode: int, n_updates: int) -> float:
    """Seconds of ``n_updates`` updates of ``combined_planning`` with target ``mode`` on copies
    of ``agent``'s Q table and planner (the agent is left as it is)."""
    shares = agent.shares._replace(n_steps=n_updates, mode=mode)
    q = agent.q.copy()
    planner = kp.PlannerArrays(*(array.copy() for array in agent.planner))
    rng = np.random.default_rng(7)
    start = time.perf_counter()
    kp.combined_planning(q, agent.model.arrays, planner, shares, agent.kernel_grid, rng)
    return time.perf_counter() - start


def expected_and_most_probable(quick: bool) -> tuple[float, float]:
    """Planning updates/s of the expected and of the most-probable target, best of
    :data:`REPEATS` timings each, interleaved (load on the machine falls on both alike)."""
    agent, env = arena_agent(AGENT, 1000)
    train_agent_fast(agent, env, 2 if quick else WARM_UP, seed=1)
    n_updates = 500_000 if quick else 5_000_000
    modes = (EXPECTED, MOST_PROBABLE)
    for mode in modes:
        planning_seconds(agent, mode, 10)  # compile / warm up
    best = dict.fromkeys(modes, math.inf)
    for _ in range(REPEATS):
        for mode in modes:
            best[mode] = min(best[mode], planning_seconds(agent, mode, n_updates))
    return n_updates / best[EXPECTED], n_updates / best[MOST_PROBABLE]


def main() -> None:
    expected, most_probable = expected_and_most_probable(False)
    print(
        f"{AGENT} planning loop (combined_planning), obstacles arena: expected update "
        f"{expected / 1e6:6.2f} M/s, most-probable update {most_probable / 1e6:6.2f} M/s: "
        f"{expected / most_probable:4.2f} ×"
    )


if __name__ == "__main__":
    main()
