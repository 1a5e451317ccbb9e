"""Tabular agents against plain-Python equivalents, all measured in this run on one core.

Prints (planning rates: best of three timings each):
* Dyna-Q planning updates/s of the compiled kernel and of a dict-based plain-Python Dyna-Q, and
  their ratio (targets: ≥ 10 million/s and ≥ 50×);
* prioritized-sweeping value updates/s of the whole agent (queue, predecessors, model and the
  episode loop included), trained by the fused maze trainer (``train_agent_fast``) and step by
  step from Python (``train_agent`` on the Gymnasium maze), against a plain-Python prioritized
  sweeping on the same maze;
* per model-based agent, planning updates/s inside the fused trainer (``train_agent_fast``) on
  the 25 × 25 × 20 obstacles arena at a large planning budget (:data:`ARENA_BUDGETS` updates per
  real step, everything of the trainer timed: simulation, real steps, end-of-episode refits),
  each agent with its default planning target (named on its line; the expected update of
  ``dyna-kinematic``, ``trajectory-prioritized``, ``dyna-full`` and ``dyna-sweep``, whose lines
  compare their rate at 1000 with the target of 10 M updates/s),
  against the identical kernels as plain Python (``NUMBA_DISABLE_JIT=1`` in a subprocess, on
  the budget :data:`PLAIN_ARENA` and a short episode), and for prioritized sweeping, whose
  queue empties before the budget, its updates per second of planning time alone
  (:func:`sweeping_planning_time_rate`), and its rate later in learning, once the queue no
  longer empties (:func:`sweeping_long_run`);
* the wall time of the 30 Dyna Maze runs of ``skidnav study reproduce`` (Sutton & Barto (2018)
  Example 8.1, n = 0, 5, 50, without writing files; fused maze trainer) against the same runs of
  the plain-Python Dyna-Q (a few runs, scaled to 30).

The plain-Python agents are the usual textbook code: Q as a list of lists, the model as a dict
(s, a) → (r, s′, terminated) (the mazes are deterministic), ``random.Random``, ``heapq``. They run
through the plain training loop (``train_agent``) on the Gymnasium mazes.
"""

from __future__ import annotations

import heapq
import math
import random
import time
from collections import defaultdict
from typing import Any

import numpy as np
from plain_python import interpreted

from skidnav.agents.tabular.fast_training import train_agent_fast
from skidnav.agents.tabular.planning import dyna_planning
from skidnav.agents.tabular.registry import make_agent, make_config
from skidnav.agents.training import train_agent
from skidnav.envs.mazes import dyna_maze
from skidnav.models.multinomial_targets import MOST_PROBABLE
from skidnav.studies.sutton_barto.grid import BOOK, TextbookChecks
from skidnav.studies.sutton_barto.trial import dyna_maze_run

SCALE = 3  # 486-state maze: a model with every pair seen
REPEATS = 3  # each rate is the best of this many timings (the machine is shared)
SWEEP = {"planning_steps": 200, "alpha": 0.5, "gamma": 0.95, "epsilon": 0.1, "theta": 1e-6}
SWEEP_EPISODES = 30
ARENA_AGENTS = (
    "dyna-q", "dyna-kinematic", "trajectory-prioritized", "dyna-full", "prioritized-sweeping",
    "dyna-sweep",
)  # fmt: skip
ARENA_BUDGETS = (1000, 10_000)  # planning updates per real step
EXPECTED_TARGET = 10e6  # expected planning updates/s at 1000 updates per real step
ARENA_EPISODES = {1000: 6, 10_000: 2}  # timed, after 4 warm-up episodes at the same budget
PLAIN_ARENA = (200, 40)  # plain Python: planning updates per real step, real steps
MAZE_RUNS = 30
PLAIN_MAZE_RUNS = 3


class PlainDynaQ:
    """Dict-based tabular Dyna-Q (Sutton & Barto (2018) §8.2) in plain Python."""

    def __init__(self, n_states: int, n_actions: int, planning_steps: int, seed: int) -> None:
        self.q = [[0.0] * n_actions for _ in range(n_states)]
        self.model: dict[tuple[int, int], tuple[float, int, bool]] = {}
        self.pairs: list[tuple[int, int]] = []
        self.planning_steps = planning_steps
        self.alpha, self.gamma, self.epsilon = BOOK["alpha"], BOOK["gamma"], BOOK["epsilon"]
        self.random = random.Random(seed)
        self.planning_updates = 0

    def act(self, state: int) -> int:
        values = self.q[state]
        if self.random.random() < self.epsilon:
            return self.random.randrange(len(values))
        best = max(values)
        return self.random.choice([a for a, value in enumerate(values) if value == best])

    def greedy_action(self, state: int) -> int:
        values = self.q[state]
        return values.index(max(values))

    def observe(self, state: int, action: int, reward: float, next_state: int,
                terminated: bool, truncated: bool = False, info: Any = None) -> None:  # fmt: skip
        q = self.q
        target = reward if terminated else reward + self.gamma * max(q[next_state])
        q[state][action] += self.alpha * (target - q[state][action])
        if (state, action) not in self.model:
            self.pairs.append((state, action))
        self.model[(state, action)] = (reward, next_state, terminated)
        self.plan(self.planning_steps)

    def plan(self, n_updates: int) -> None:
        q, model, pairs, generator = self.q, self.model, self.pairs, self.random
        alpha, gamma = self.alpha, self.gamma
        for _ in range(n_updates):
            state, action = pairs[int(generator.random() * len(pairs))]
            reward, next_state, done = model[(state, action)]
            target = reward if done else reward + gamma * max(q[next_state])
            q[state][action] += alpha * (target - q[state][action])
        self.planning_updates += n_updates

    def end_episode(self) -> None:
        pass


class PlainPrioritizedSweeping(PlainDynaQ):
    """Dict-based prioritized sweeping (Sutton & Barto (2018) §8.4) with ``heapq``: a pair is
    queued at most once, at its highest priority (older heap entries are skipped when popped)."""

    def __init__(self, n_states: int, n_actions: int, options: dict[str, Any], seed: int) -> None:
        super().__init__(n_states, n_actions, options["planning_steps"], seed)
        self.alpha, self.gamma = options["alpha"], options["gamma"]
        self.epsilon, self.theta = options["epsilon"], options["theta"]
        self.predecessors: defaultdict[int, set[tuple[int, int]]] = defaultdict(set)
        self.heap: list[tuple[float, tuple[int, int]]] = []
        self.queued: dict[tuple[int, int], float] = {}

    def _queue(self, pair: tuple[int, int]) -> None:
        reward, next_state, done = self.model[pair]
        target = reward if done else reward + self.gamma * max(self.q[next_state])
        priority = abs(target - self.q[pair[0]][pair[1]])
        if priority > self.theta and priority > self.queued.get(pair, 0.0):
            self.queued[pair] = priority
            heapq.heappush(self.heap, (-priority, pair))

    def observe(self, state: int, action: int, reward: float, next_state: int,
                terminated: bool, truncated: bool = False, info: Any = None) -> None:  # fmt: skip
        self.model[(state, action)] = (reward, next_state, terminated)
        self.predecessors[next_state].add((state, action))
        self._queue((state, action))
        q, updates = self.q, 0
        while self.heap and updates < self.planning_steps:
            negative, pair = heapq.heappop(self.heap)
            if self.queued.get(pair) != -negative:
                continue  # superseded by a higher priority
            del self.queued[pair]
            reward_, next_, done = self.model[pair]
            target = reward_ if done else reward_ + self.gamma * max(q[next_])
            q[pair[0]][pair[1]] += self.alpha * (target - q[pair[0]][pair[1]])
            updates += 1
            for predecessor in self.predecessors[pair[0]]:
                self._queue(predecessor)
        self.planning_updates += updates


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
    """Seconds taken by ``n_updates`` steps of :meth:`PlainDynaQ.plan` on the compiled agent's
    model and Q table (only the loop timed)."""
    plain = PlainDynaQ(agent.n_states, agent.n_actions, 0, seed=1)
    for key in agent.model.visited_pairs().tolist():
        state, action = divmod(key, 4)
        out = agent.model.outcomes(state, action)
        plain.pairs.append((state, action))
        plain.model[(state, action)] = (
            float(out.mean_rewards[0]),
            int(out.next_states[0]),
            bool(out.termination[0]),
        )
    plain.q = agent.q.tolist()
    plain.alpha, plain.gamma = 0.1, 0.95
    start = time.perf_counter()
    plain.plan(n_updates)
    return time.perf_counter() - start


def sweeping_rates() -> tuple[float, float, float]:
    """Value updates/s of the compiled prioritized-sweeping agent (fused trainer, then step by
    step) and of :class:`PlainPrioritizedSweeping`, :data:`SWEEP_EPISODES` episodes each on the
    ×:data:`SCALE` Dyna Maze, training loop and env included (both compiled runs make the same
    updates)."""
    env = dyna_maze(SCALE)
    n_states = env.n_rows * env.n_cols
    for trainer in (train_agent_fast, train_agent):  # compile on a small maze first
        warm_up = make_agent("prioritized-sweeping", 54, 4, SWEEP, np.random.default_rng(0))
        trainer(warm_up, dyna_maze(1), 1, seed=0)
    runs: list[tuple[Any, Any]] = [
        (make_agent("prioritized-sweeping", n_states, 4, SWEEP, np.random.default_rng(0)), trainer)
        for trainer in (train_agent_fast, train_agent)
    ]
    runs.append((PlainPrioritizedSweeping(n_states, 4, SWEEP, seed=0), train_agent))
    rates: list[float] = []
    for agent, trainer in runs:
        start = time.perf_counter()
        trainer(agent, dyna_maze(SCALE), SWEEP_EPISODES, seed=0)
        rates.append(agent.planning_updates / (time.perf_counter() - start))
    return rates[0], rates[1], rates[2]


DYNA_MAZE = TextbookChecks(examples=("dyna-maze",))
"""Example 8.1's checks: Dyna-Q with n = 0, 5, 50 on the Dyna Maze."""
PLANNING_STEPS = DYNA_MAZE.planning_steps


def dyna_maze_runs(runs: int) -> None:
    """``runs`` runs of every Example 8.1 check (the study's run, compiled), run k seeded k."""
    for check in DYNA_MAZE.checks():
        for seed in range(runs):
            dyna_maze_run(check, np.random.default_rng(seed), seed)


def plain_dyna_maze_seconds(runs: int) -> float:
    """Wall time of ``runs`` runs of :func:`dyna_maze_runs` with :class:`PlainDynaQ`."""
    start = time.perf_counter()
    for n in PLANNING_STEPS:
        for seed in range(runs):
            train_agent(PlainDynaQ(54, 4, n, seed), dyna_maze(), 50, seed=seed)
    return time.perf_counter() - start


def arena_agent(name: str, budget: int, epsilon: float = 0.1) -> tuple[Any, Any]:
    """(agent ``name``, the obstacles arena it learns on): α 0.5, γ 0.95, θ 1e-6, ``budget``
    planning updates per real step, the agent's default planning target
    (:func:`default_planning_mode`); the kernels of its first goal compiled beforehand."""
    import gymnasium as gym

    import skidnav.envs  # noqa: F401  (registers the env)

    env = gym.make("skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=3, slip="slippery")
    config = {"alpha": 0.5, "gamma": 0.95, "epsilon": epsilon, "planning_steps": budget}
    if name == "prioritized-sweeping":
        config["theta"] = 1e-6
    context = {} if name in ("dyna-q", "prioritized-sweeping") else {"task": env.unwrapped.task}
    agent = make_agent(name, 12_500, 4, config, np.random.default_rng(5), **context)
    compile_trajectory_kernels(env.unwrapped.task.grid)
    return agent, env


def timed_episodes(
    agent: Any, env: Any, episodes: int, max_steps: int = 500
) -> tuple[int, int, float]:
    """(planning updates, real steps, seconds) of ``episodes`` more episodes of
    ``train_agent_fast``, all the trainer's time included."""
    updates, steps = agent.planning_updates, agent.steps
    start = time.perf_counter()
    train_agent_fast(agent, env, episodes, max_steps=max_steps)
    seconds = time.perf_counter() - start
    return agent.planning_updates - updates, agent.steps - steps, seconds


def arena_run(
    name: str, budget: int, episodes: int, max_steps: int = 500, epsilon: float = 0.1
) -> tuple[int, int, float]:
    """:func:`timed_episodes` of :func:`arena_agent` after :data:`WARM_UP` episodes at the same
    budget (compilation, first model, first refits)."""
    agent, env = arena_agent(name, budget, epsilon)
    train_agent_fast(agent, env, WARM_UP if max_steps >= 500 else 1, max_steps=max_steps, seed=1)
    return timed_episodes(agent, env, episodes, max_steps)


def arena_planning_rate(name: str, budget: int, episodes: int, max_steps: int = 500) -> float:
    """Planning updates/s of :func:`arena_run` at ε 0.1, all the trainer's time included."""
    updates, _, seconds = arena_run(name, budget, episodes, max_steps)
    return updates / seconds


def sweeping_planning_time_rate(budget: int, episodes: int) -> tuple[float, float]:
    """Prioritized sweeping's updates per second of planning time on the arena, and its updates
    per real step: :func:`arena_run` at ε 1 with ``budget`` and with no planning, best of
    :data:`REPEATS` timings each. A most-probable sweep draws no random number and ε 1 acts
    without reading ``q``, so both runs make the same real steps (checked); the difference of
    their times is the planning's."""
    pairs = [
        tuple(arena_run("prioritized-sweeping", n, episodes, epsilon=1.0) for n in (budget, 0))
        for _ in range(REPEATS)
    ]  # interleaved, so that load on the machine falls on both alike
    planned, plain = [pair[0] for pair in pairs], [pair[1] for pair in pairs]
    updates, steps, _ = planned[0]
    if {run[1] for run in planned + plain} != {steps}:
        raise RuntimeError("the runs with and without planning made different real steps")
    seconds = min(run[2] for run in planned) - min(run[2] for run in plain)
    return updates / seconds, updates / steps


WARM_UP = 4
SWEEPING_LONG_RUN = (100, 6)  # episodes learned, then timed, at 1000 updates per real step


def sweeping_long_run() -> tuple[float, float, float]:
    """Prioritized sweeping's planning updates/s over the whole trainer later in learning: after
    :data:`SWEEPING_LONG_RUN` episodes at ε 0.1 and 1000 updates per real step, (updates/s,
    updates per real step, predecessor outcomes of the state a model outcome leads to, on
    average: Σ n² / Σ n over the states' predecessor counts n). Each pop computes the priority
    of every predecessor outcome of its state, which the rate does not count."""
    learned, timed = SWEEPING_LONG_RUN
    agent, env = arena_agent("prioritized-sweeping", 1000)
    train_agent_fast(agent, env, learned, seed=1)
    updates, steps, seconds = timed_episodes(agent, env, timed)
    model = agent.model.arrays
    predecessors = np.bincount(model.entry_next_state[: model.counters[1]])
    per_target = float((predecessors**2).sum() / predecessors.sum())
    return updates / seconds, updates / steps, per_target


def compile_trajectory_kernels(grid: Any) -> None:
    """Compile (or load from the cache) the kernels a model-based agent first calls when an
    episode reaches the goal, which the warm-up episodes may not do: otherwise a cold cache puts
    their compilation (~1.4 s) inside the timed episodes."""
    from skidnav.agents.trajectory_keys import loop_erase, neighbourhood_keys

    trajectory = loop_erase(np.zeros(2, dtype=np.int64), 4, 12_500)
    neighbourhood_keys(trajectory, np.zeros((grid.n_x, grid.n_y), np.bool_), grid, 4, True)


def plain_arena_rate(name: str) -> float:
    """:func:`arena_planning_rate` as plain Python (:func:`plain_python.interpreted`):
    :data:`PLAIN_ARENA` (budget, steps per episode), one timed episode."""
    budget, steps = PLAIN_ARENA
    return interpreted("bench_agents", f"arena_planning_rate({name!r}, {budget}, 1, {steps})")


def default_planning_mode(name: str) -> str:
    """The planning target agent ``name`` plans with by default (``planning_mode``; "" for an
    agent without a model)."""
    return str(getattr(make_config(name, None), "planning_mode", ""))


def expected_target_note(name: str, rate: float) -> str:
    """For an agent that plans with the expected update by default, its rate at 1000 updates
    per real step [updates/s] against the target of 10 M/s; nothing for the others."""
    if default_planning_mode(name) != "expected":
        return ""
    verdict = "met" if rate >= EXPECTED_TARGET else "MISSED"
    return f"; expected update at 1000 updates/step, target >= 10 M/s: {verdict}"


def print_arena_rates() -> None:
    """One line per model-based agent: its planning target, fused-trainer planning rate per
    budget and the ratio to plain Python, and for the expected update the 10 M/s target."""
    budget, steps = PLAIN_ARENA
    print(
        "fused trainer, obstacles arena 25×25×20 (12,500 states × 4 actions), α 0.5, γ 0.95, "
        f"ε 0.1, each agent's default planning target; plain Python = same kernels, "
        f"NUMBA_DISABLE_JIT=1, {budget} updates/step, {steps}-step episode"
    )
    for name in ARENA_AGENTS:
        plain = plain_arena_rate(name)
        rates = [arena_planning_rate(name, n, ARENA_EPISODES[n]) for n in ARENA_BUDGETS]
        figures = ", ".join(
            f"{n} updates/step {rate / 1e6:6.2f} M/s ({rate / plain:6.0f} ×)"
            for n, rate in zip(ARENA_BUDGETS, rates, strict=True)
        )
        note = expected_target_note(name, rates[ARENA_BUDGETS.index(1000)])
        print(
            f"  {name:24s} {default_planning_mode(name):13s} plain {plain / 1e3:6.1f} k/s; "
            f"{figures}{note}",
            flush=True,
        )
    figures = []
    for n in ARENA_BUDGETS:
        rate, per_step = sweeping_planning_time_rate(n, ARENA_EPISODES[n])
        figures.append(f"{n} updates/step {rate / 1e6:6.2f} M/s ({per_step:5.1f} per real step)")
    print(
        "  prioritized-sweeping, planning time only (ε 1: the same real steps with and without "
        f"planning; the queue empties before the budget): {', '.join(figures)}",
        flush=True,
    )
    rate, per_step, per_target = sweeping_long_run()
    learned, _ = SWEEPING_LONG_RUN
    print(
        f"  prioritized-sweeping after {learned} episodes, 1000 updates/step: {rate / 1e6:6.2f} "
        f"M/s ({per_step:5.1f} per real step; a state reached has {per_target:4.1f} predecessor "
        "outcomes, each a target computed for its priority when it is popped, not counted)",
        flush=True,
    )


def main() -> None:
    print_arena_rates()
    agent = trained_dyna_agent()
    compiled = compiled_rate(agent)
    plain = plain_python_rate(agent)
    print(f"dyna-q planning, compiled:      {compiled / 1e6:8.2f} M updates/s (target >= 10)")
    print(f"dyna-q planning, plain Python:  {plain / 1e6:8.2f} M updates/s")
    print(f"compiled / plain Python:        {compiled / plain:8.1f} × (target >= 50)")
    fused, stepped, plain_sweep = sweeping_rates()
    print(
        f"prioritized sweeping (whole agent), M updates/s: fused {fused / 1e6:6.2f}, "
        f"step by step {stepped / 1e6:6.3f}, plain Python {plain_sweep / 1e6:6.3f}: "
        f"{fused / plain_sweep:5.1f} × and {stepped / plain_sweep:4.1f} ×"
    )
    dyna_maze_runs(1)  # compile / warm up
    start = time.perf_counter()
    dyna_maze_runs(MAZE_RUNS)
    seconds = time.perf_counter() - start
    plain_seconds = plain_dyna_maze_seconds(PLAIN_MAZE_RUNS) * MAZE_RUNS / PLAIN_MAZE_RUNS
    print(
        f"Dyna Maze, {MAZE_RUNS} runs × 3 n × 50 episodes: {seconds:6.1f} s compiled, "
        f"{plain_seconds:6.1f} s plain Python (from {PLAIN_MAZE_RUNS} runs): "
        f"{plain_seconds / seconds:5.1f} ×"
    )


if __name__ == "__main__":
    main()
