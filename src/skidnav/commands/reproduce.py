"""``skidnav study reproduce sutton-barto``: the textbook checks of Sutton & Barto (2018) ch. 8.

Writes per-episode (or per-step) CSV files and PNG plots to ``--out``, each atomically, and prints
a summary:

* ``dyna_maze.csv/.png`` — Example 8.1: steps per episode of Dyna-Q with n = 0, 5, 50 planning
  steps (γ = 0.95, α = 0.1, ε = 0.1), ``--runs`` runs of 50 episodes;
* ``blocking_maze.*``, ``shortcut_maze.*`` — Examples 8.2/8.3: cumulative reward of Dyna-Q vs
  Dyna-Q+;
* ``prioritized_sweeping.csv/.png`` — Example 8.4: value updates until the greedy path is optimal,
  Dyna-Q vs prioritized sweeping on Dyna Mazes scaled ×1, ×2, ×3.
"""

from __future__ import annotations

import argparse
import csv
import io
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from skidnav.agents.fast_training import train_agent_fast, train_for_steps_fast
from skidnav.agents.tabular.registry import make_agent
from skidnav.atomicfile import write_user_file
from skidnav.envs.mazes import GridMazeEnv, blocking_maze, dyna_maze, shortcut_maze
from skidnav.errors import UserError
from skidnav.outputs import make_output_dir

BOOK = {"alpha": 0.1, "gamma": 0.95, "epsilon": 0.1}
CHANGING = {"alpha": 1.0, "gamma": 0.95, "epsilon": 0.1, "planning_steps": 10}
SWEEP = {"alpha": 1.0, "gamma": 0.95, "epsilon": 0.1, "planning_steps": 5}
NEAR_OPTIMAL = 18.0
PATH_TOLERANCE = 1.2


def add_parser(subparsers: Any) -> None:
    """Register ``skidnav study reproduce``."""
    parser = subparsers.add_parser("reproduce", help="reproduce reference results")
    parser.add_argument("target", choices=["sutton-barto"], help="which results")
    parser.add_argument("--runs", type=int, default=30, help="independent runs (seeds 0..N-1)")
    parser.add_argument("--out", type=Path, default=Path("runs/sutton-barto"), help="output folder")
    parser.set_defaults(func=run)


def _write_csv(path: Path, header: Sequence[str], rows: list[Sequence[Any]]) -> None:
    text = io.StringIO()
    writer = csv.writer(text)
    writer.writerow(header)
    writer.writerows(rows)
    write_user_file(path, text.getvalue().encode("utf-8"), "CSV file")


def _plot(path: Path, curves: dict[str, np.ndarray], xlabel: str, ylabel: str, x0: int = 1) -> None:
    from skidnav.experiments.report.plots import line_plot  # matplotlib only when a figure is drawn

    write_user_file(path, line_plot(curves, xlabel, ylabel, x0), "plot")


PLANNING_STEPS = (0, 5, 50)
"""The planning steps n compared in Example 8.1."""


def dyna_maze_runs(
    runs: int, first_seed: int = 0, planning_steps: Sequence[int] = PLANNING_STEPS
) -> dict[int, np.ndarray]:
    """Example 8.1 without output files: steps per episode, int64 (runs, 50), of Dyna-Q for each
    n, run k seeded ``first_seed + k`` (agent generator and first env reset)."""
    lengths = {}
    for n in planning_steps:
        per_run = []
        for seed in range(first_seed, first_seed + runs):
            agent = make_agent(
                "dyna-q", 54, 4, {**BOOK, "planning_steps": n}, np.random.default_rng(seed)
            )
            per_run.append(train_agent_fast(agent, dyna_maze(), 50, seed=seed).lengths)
        lengths[n] = np.array(per_run, dtype=np.int64)
    return lengths


def dyna_maze_experiment(runs: int, out: Path, first_seed: int = 0) -> dict[int, np.ndarray]:
    """Example 8.1 (writes ``dyna_maze.csv/.png``); returns mean steps per episode for each n."""
    lengths = dyna_maze_runs(runs, first_seed)
    rows: list[Sequence[Any]] = [
        (n, first_seed + run, episode + 1, int(steps))
        for n, per_run in lengths.items()
        for run, run_lengths in enumerate(per_run)
        for episode, steps in enumerate(run_lengths)
    ]
    means = {n: per_run.mean(axis=0) for n, per_run in lengths.items()}
    _write_csv(out / "dyna_maze.csv", ("planning_steps", "run", "episode", "steps"), rows)
    curves = {f"n = {n}": values[1:] for n, values in means.items()}
    _plot(out / "dyna_maze.png", curves, "episode", "steps per episode", x0=2)
    return means


def first_episode_below(mean_steps: np.ndarray, level: float = NEAR_OPTIMAL) -> int:
    """First episode (1-based) whose mean steps are ≤ ``level``; −1 if none."""
    below = np.nonzero(mean_steps <= level)[0]
    return int(below[0]) + 1 if below.size else -1


CHANGING_AGENTS: tuple[tuple[str, dict[str, Any]], ...] = (
    ("dyna-q", {}),
    ("dyna-q-plus", {"kappa": 1e-3}),
)
"""The agents of Examples 8.2/8.3 and their options beyond :data:`CHANGING`."""


def changing_maze_runs(
    make_env: Any, n_steps: int, runs: int, first_seed: int = 0
) -> dict[str, np.ndarray]:
    """Examples 8.2/8.3 without output files: cumulative reward after each step, float64
    (runs, n_steps), for each agent; run k seeded ``first_seed + k``."""
    curves = {}
    for agent_name, extra in CHANGING_AGENTS:
        per_run = []
        for seed in range(first_seed, first_seed + runs):
            agent = make_agent(
                agent_name, 54, 4, {**CHANGING, **extra}, np.random.default_rng(seed)
            )
            per_run.append(train_for_steps_fast(agent, make_env(), n_steps, seed=seed))
        curves[agent_name] = np.array(per_run)
    return curves


def changing_maze_experiment(
    name: str, make_env: Any, n_steps: int, runs: int, out: Path, first_seed: int = 0
) -> dict[str, np.ndarray]:
    """Examples 8.2/8.3 (writes ``<name>.csv/.png``); returns the mean cumulative reward per step
    for each agent."""
    means = {
        agent: curves.mean(axis=0)
        for agent, curves in changing_maze_runs(make_env, n_steps, runs, first_seed).items()
    }
    rows: list[Sequence[Any]] = [
        (agent, step + 1, value) for agent, mean in means.items() for step, value in enumerate(mean)
    ]
    _write_csv(out / f"{name}.csv", ("agent", "step", "mean_cumulative_reward"), rows)
    _plot(out / f"{name}.png", means, "time step", "cumulative reward")
    return means


def updates_until_optimal(name: str, scale: int, seed: int, max_episodes: int = 300) -> int:
    """Value updates (real + planning) until the greedy path is first within
    :data:`PATH_TOLERANCE` of the shortest path (−1 if not within ``max_episodes``). The tolerance
    is needed because ε-greedy exploration may never try the pairs of the one optimal path."""
    env: GridMazeEnv = dyna_maze(scale)
    optimal = env.shortest_path_length()
    options = {**SWEEP, "theta": 1e-4} if name == "prioritized-sweeping" else SWEEP
    n_states = env.n_rows * env.n_cols
    agent = make_agent(name, n_states, 4, options, np.random.default_rng(seed))
    for episode in range(max_episodes):
        log = train_agent_fast(
            agent, env, 1, greedy_eval_env=dyna_maze(scale), greedy_max_steps=4 * optimal,
            seed=seed if episode == 0 else None,
        )  # fmt: skip
        length = int(log.greedy_lengths[0, 0])
        if 0 < length <= PATH_TOLERANCE * optimal:
            real = 0 if name == "prioritized-sweeping" else agent.steps
            return real + agent.planning_updates
    return -1


def sweeping_experiment(runs: int, out: Path) -> dict[tuple[str, int], float]:
    """Example 8.4; returns the median updates until near-optimal per (agent, scale)."""
    rows: list[Sequence[Any]] = []
    medians: dict[tuple[str, int], float] = {}
    for name in ("dyna-q", "prioritized-sweeping"):
        for scale in (1, 2, 3):
            counts = [updates_until_optimal(name, scale, seed) for seed in range(runs)]
            rows.extend(
                (name, 54 * scale * scale, seed, count) for seed, count in enumerate(counts)
            )
            # A run that never got there counts as infinitely many updates.
            medians[(name, scale)] = float(np.median([c if c >= 0 else np.inf for c in counts]))
    _write_csv(out / "prioritized_sweeping.csv", ("agent", "n_states", "run", "updates"), rows)
    curves = {
        name: np.array([medians[(name, scale)] for scale in (1, 2, 3)])
        for name in ("dyna-q", "prioritized-sweeping")
    }
    _plot(out / "prioritized_sweeping.png", curves, "maze scale", "updates until optimal")
    return medians


def _report_dyna_maze(runs: int, out: Path) -> None:
    means = dyna_maze_experiment(runs, out)
    print(f"Dyna Maze (Example 8.1), {runs} runs; optimum 14 steps")
    for n, values in means.items():
        print(
            f"  n = {n:2d}: episode 2 {values[1]:6.1f} steps, last 10 {values[-10:].mean():5.1f},"
            f" first mean <= {NEAR_OPTIMAL:g} at episode {first_episode_below(values)}"
        )


def _report_changing_mazes(runs: int, out: Path) -> None:
    for name, make_env, n_steps, change in (
        ("blocking_maze", blocking_maze, 3000, 1000),
        ("shortcut_maze", shortcut_maze, 6000, 3000),
    ):
        curves = changing_maze_experiment(name, make_env, n_steps, runs, out)
        gains = {agent: curve[-1] - curve[change - 1] for agent, curve in curves.items()}
        print(
            f"{name}, {runs} runs: mean reward after the change at step {change}: "
            + ", ".join(f"{agent} {gain:.1f}" for agent, gain in gains.items())
        )


def _report_sweeping(runs: int, out: Path) -> None:
    medians = sweeping_experiment(runs, out)
    print(f"Updates until the greedy path is within {PATH_TOLERANCE:g}× optimal, median of {runs}:")
    for scale in (1, 2, 3):
        dyna, sweep = medians[("dyna-q", scale)], medians[("prioritized-sweeping", scale)]
        print(
            f"  {54 * scale * scale:4d} states: dyna-q {dyna:9.0f}, prioritized {sweep:9.0f}"
            f" (×{dyna / sweep:.1f} fewer)"
        )


def run(args: argparse.Namespace) -> int:
    """Run every textbook check and print the summary."""
    if args.runs < 1:
        raise UserError(f"expected --runs >= 1, got {args.runs}")
    out: Path = make_output_dir(args.out)
    start = time.perf_counter()
    _report_dyna_maze(args.runs, out)
    _report_changing_mazes(args.runs, out)
    _report_sweeping(min(args.runs, 10), out)
    print(f"wrote CSV and PNG files to {out} in {time.perf_counter() - start:.0f} s")
    return 0
