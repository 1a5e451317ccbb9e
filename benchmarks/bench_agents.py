"""Tabular agents: planning throughput against a plain-Python Dyna-Q, and the Dyna Maze wall time.

Prints, all measured in this run on one core (planning rates: best of three timings each):
* Dyna-Q planning updates/s of the compiled kernel and of a dict-based plain-Python Dyna-Q,
  and their ratio (targets: ≥ 10 million/s and ≥ 50×);
* prioritized-sweeping value updates/s (queue, predecessors and model included);
* the wall time of the 30-run Dyna Maze experiment (Sutton & Barto (2018) Example 8.1).
"""

from __future__ import annotations

import math
import random
import tempfile
import time
from pathlib import Path

import numpy as np

from skidnav.agents.registry import make_agent
from skidnav.agents.training import train_agent
from skidnav.commands.reproduce import dyna_maze_experiment
from skidnav.envs.mazes import dyna_maze
from skidnav.kernels.multinomial import MOST_PROBABLE
from skidnav.kernels.planning import dyna_planning

SCALE = 3  # 486-state maze: a model with every pair seen
REPEATS = 3  # each rate is the best of this many timings (the machine is shared)


def trained_dyna_agent():  # type: ignore[no-untyped-def]
    env = dyna_maze(SCALE)
    agent = make_agent(
        "dyna-q", env.n_rows * env.n_cols, 4, {"planning_steps": 5}, np.random.default_rng(0)
    )
    train_agent(agent, env, 30, seed=0)
    return agent


def compiled_rate(agent, n_updates: int = 5_000_000) -> float:  # type: ignore[no-untyped-def]
    """Planning updates/s of the compiled kernel (one call, ``n_updates`` planning steps, the
    agent's default most-probable mode); best of :data:`REPEATS` timings."""
    model, q, rng = agent.model.arrays, agent.q.copy(), np.random.default_rng(1)
    dyna_planning(q, model, 10, 0.1, 0.95, MOST_PROBABLE, rng)  # compile / warm up
    best = math.inf
    for _ in range(REPEATS):
        start = time.perf_counter()
        done = dyna_planning(q, model, n_updates, 0.1, 0.95, MOST_PROBABLE, rng)
        best = min(best, time.perf_counter() - start)
    return done / best


def plain_python_rate(agent, n_updates: int = 200_000) -> float:  # type: ignore[no-untyped-def]
    """Best of :data:`REPEATS` timings of :func:`plain_python_planning`."""
    return n_updates / min(plain_python_planning(agent, n_updates) for _ in range(REPEATS))


def plain_python_planning(agent, n_updates: int) -> float:  # type: ignore[no-untyped-def]
    """Seconds taken by ``n_updates`` steps of the usual dict-based Dyna-Q planning loop
    (deterministic model: (s, a) → (r, s′, done); Q as a list of lists; only the loop timed)."""
    model: dict[tuple[int, int], tuple[float, int, bool]] = {}
    for key in agent.model.visited_pairs().tolist():
        state, action = divmod(key, 4)
        out = agent.model.outcomes(state, action)
        model[(state, action)] = (
            float(out.mean_rewards[0]),
            int(out.next_states[0]),
            bool(out.termination[0]),
        )
    q = agent.q.tolist()
    pairs = list(model)
    generator = random.Random(1)
    start = time.perf_counter()
    for _ in range(n_updates):
        state, action = pairs[int(generator.random() * len(pairs))]
        reward, next_state, done = model[(state, action)]
        target = reward if done else reward + 0.95 * max(q[next_state])
        q[state][action] += 0.1 * (target - q[state][action])
    return time.perf_counter() - start


def sweeping_rate() -> float:
    env = dyna_maze(SCALE)
    options = {"planning_steps": 200, "alpha": 0.5, "theta": 1e-6}
    agent = make_agent(
        "prioritized-sweeping", env.n_rows * env.n_cols, 4, options, np.random.default_rng(0)
    )
    train_agent(agent, dyna_maze(1), 1, seed=0)  # compile on a small maze first
    agent = make_agent(
        "prioritized-sweeping", env.n_rows * env.n_cols, 4, options, np.random.default_rng(0)
    )
    start = time.perf_counter()
    train_agent(agent, env, 30, seed=0)
    return agent.planning_updates / (time.perf_counter() - start)


def main() -> None:
    agent = trained_dyna_agent()
    compiled = compiled_rate(agent)
    plain = plain_python_rate(agent)
    print(f"dyna-q planning, compiled:      {compiled / 1e6:8.2f} M updates/s (target >= 10)")
    print(f"dyna-q planning, plain Python:  {plain / 1e6:8.2f} M updates/s")
    print(f"compiled / plain Python:        {compiled / plain:8.1f} × (target >= 50)")
    print(f"prioritized sweeping (whole agent): {sweeping_rate() / 1e6:8.2f} M updates/s")
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        dyna_maze_experiment(30, Path(folder))
        print(f"Dyna Maze, 30 runs × 3 n × 50 episodes: {time.perf_counter() - start:6.1f} s")


if __name__ == "__main__":
    main()
