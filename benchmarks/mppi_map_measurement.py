"""mppi-kinematic on the maze and obstacle worlds (docs/agents/mppi-kinematic.md, "Measured on
the maze and obstacle worlds"): per world, one agent (seed 0) trained for E episodes of at most
200 actions of 1 s on the slippery floor, feature observations (pose, goal, 8 lidar ranges), a
horizon of 4 actions (4 s, as in the continuity study); ``--period 0.1`` makes the actions 0.1 s
long, ten times as many per episode and in the horizon (the same 200 s and 4 s; ``--set
horizon=N`` sets it in actions instead); after every
episode its frozen planner
is rolled out greedily on R evaluation seeds (``skidnav.train``). Prints one JSON line per world
(success, episodes and seconds of driving to the first success, collisions per episode, greedy
successes) and a summary.

``--goal-tracker`` also rolls the goal tracker (``goal-tracker``, the reference wheel-speed
policy) out greedily from the same R evaluation starts (``skidnav.evaluate``, the seeds of the
training's evaluations) and compares the seconds of driving to the goal of the frozen planner
after the last episode with the tracker's, start by start.

    python benchmarks/mppi_map_measurement.py [--worlds maze:3 maze:100 obstacles:0-9]
        [--episodes 30] [--rollouts 2] [--slip slippery] [--set name=value ...]
        [--goal-tracker] [--period 1.0]
"""

from __future__ import annotations

import argparse
import json
import time
from typing import Any

import numpy as np

import skidnav

EPISODE_SECONDS = 200.0
"""Seconds of driving per episode at most (training and evaluation): the continuity study's."""
HORIZON_SECONDS = 4.0
"""Seconds each sequence looks ahead (4 control steps of 1 s)."""


def worlds(specs: list[str]) -> list[tuple[str, int]]:
    """``kind:seed`` or ``kind:first-last`` as (kind, seed) pairs."""
    pairs = []
    for spec in specs:
        kind, seeds = spec.split(":")
        first, _, last = seeds.partition("-")
        pairs += [(kind, seed) for seed in range(int(first), int(last or first) + 1)]
    return pairs


def parsed(value: str) -> Any:
    """A ``--set`` value: JSON if it parses, else the string."""
    try:
        return json.loads(value)
    except json.JSONDecodeError:
        return value


def run(
    kind: str,
    world: int,
    episodes: int,
    rollouts: int,
    slip: str,
    params: dict[str, Any],
    goal_tracker: bool = False,
    period: float = 1.0,
) -> dict[str, Any]:
    """One world's training run, seed 0, and what it measured (with ``goal_tracker``, also
    :func:`against_goal_tracker`), at actions of ``period`` seconds."""
    max_steps, horizon = round(EPISODE_SECONDS / period), round(HORIZON_SECONDS / period)
    env = skidnav.make_env(
        kind, seed=world, slip=slip, observation="features", action="continuous",
        control_period=period, max_episode_steps=max_steps,
    )  # fmt: skip
    agent = skidnav.make_agent("mppi-kinematic", env, seed=0, **{"horizon": horizon, **params})
    start = time.perf_counter()
    log = skidnav.train(agent, env, episodes, seed=0, max_steps=max_steps, rollouts=rollouts)
    wall_time = time.perf_counter() - start
    successes = log.successes.astype(bool)
    first = int(np.argmax(successes)) if successes.any() else None
    reached = log.greedy_lengths > 0
    return {
        "world": f"{kind}:{world}", "slip": slip, "params": params,
        "success": round(float(successes.mean()), 3),
        "first_success": None if first is None else first + 1,
        "seconds_to_first": None
        if first is None else float(log.lengths[: first + 1].sum() * period),
        "collisions_per_episode": round(float(log.collisions.mean()), 2),
        "first_episode_collisions": int(log.collisions[0]),
        "greedy_success": round(float(reached.mean()), 3),
        "greedy_success_last": round(float(reached[-1].mean()), 3),
        "lengths": log.lengths.tolist(), "collisions": log.collisions.tolist(),
        "wall_time": round(wall_time, 1),
        **(
            against_goal_tracker(env, log.greedy_lengths[-1], rollouts, max_steps, period)
            if goal_tracker else {}
        ),
    }  # fmt: skip


def against_goal_tracker(
    env: Any, lengths: np.ndarray, rollouts: int, max_steps: int, period: float
) -> dict[str, Any]:
    """The goal tracker's greedy rollouts from the evaluation starts of ``skidnav.train`` (seed
    0, ``rollouts`` of them, at most ``max_steps`` actions of ``period`` seconds) against the
    trained planner's last ``lengths`` [actions] (−1: not reached): both in seconds of driving,
    and the ratio of their means over the starts both reached (NaN if none)."""
    tracker = skidnav.make_agent("goal-tracker", env, seed=0)
    reference = np.array(
        [r.length for r in skidnav.evaluate(tracker, env, rollouts=rollouts, max_steps=max_steps)]
    )
    both = (lengths > 0) & (reference > 0)
    ratio = lengths[both].mean() / reference[both].mean() if both.any() else float("nan")
    return {
        "greedy_seconds": (lengths * period).tolist(),
        "goal_tracker_seconds": (reference * period).tolist(),
        "time_ratio": round(float(ratio), 3),
    }


def summary(results: list[dict[str, Any]]) -> str:
    """Means over the worlds."""
    firsts = [r["first_success"] for r in results if r["first_success"] is not None]
    return (
        f"{len(results)} worlds: success {np.mean([r['success'] for r in results]):.0%}, "
        f"greedy {np.mean([r['greedy_success'] for r in results]):.0%} "
        f"(after the last episode {np.mean([r['greedy_success_last'] for r in results]):.0%}), "
        f"first success in {len(firsts)} worlds, median episode "
        f"{np.median(firsts) if firsts else float('nan')}, collisions per episode "
        f"{np.mean([r['collisions_per_episode'] for r in results]):.2f}, first episode "
        f"{np.mean([r['first_episode_collisions'] for r in results]):.1f}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--worlds", nargs="+", default=["maze:3", "maze:100", "obstacles:0-9"])
    parser.add_argument("--episodes", type=int, default=30)
    parser.add_argument("--rollouts", type=int, default=2)
    parser.add_argument("--slip", default="slippery")
    parser.add_argument("--set", nargs="*", default=[], metavar="NAME=VALUE")
    parser.add_argument(
        "--goal-tracker", action="store_true", help="compare the time to goal with goal-tracker"
    )
    parser.add_argument("--period", type=float, default=1.0, help="seconds per action")
    options = parser.parse_args()
    params = {name: parsed(value) for name, value in (each.split("=", 1) for each in options.set)}
    results = []
    for kind, world in worlds(options.worlds):
        result = run(
            kind, world, options.episodes, options.rollouts, options.slip, params,
            options.goal_tracker, options.period,
        )  # fmt: skip
        print(json.dumps(result), flush=True)
        results.append(result)
    print(summary(results))
    ratios = [r["time_ratio"] for r in results if "time_ratio" in r]
    if ratios:
        print(f"time to goal against the goal tracker: {', '.join(map(str, ratios))}")


if __name__ == "__main__":
    main()
