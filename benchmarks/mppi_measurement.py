"""A first measurement of mppi-kinematic with the learned model (docs/agents/mppi-kinematic.md):
per map, agent seeds 0..S−1, each trained for E episodes of at most 2000 actions of 0.1 s
(200 s, the continuity study's budget of 200 one-second actions) on world 3 with the slippery
floor; after each episode its frozen planner is rolled out on two evaluation seeds. Prints one
JSON line per run (with the learned turn rate: the model's yaw rate for a full-speed turn in
place, median over the slip regions it has samples of, against the nominal robot's) and a
summary per map and setting. ``--dynamics mujoco`` runs it on the MuJoCo robot
(docs/physics.md), whose wheels' lateral friction resists a turn.

    python benchmarks/mppi_measurement.py [--seeds 5] [--episodes 5] [--settings default]
        [--dynamics kinematic|mujoco]
"""

from __future__ import annotations

import argparse
import json
import time
from typing import Any

import gymnasium
import numpy as np

import skidnav  # noqa: F401  (registers the env)
from skidnav.agents.mpc.agent import MPPIKinematicAgent
from skidnav.agents.mpc.config import MPPIConfig
from skidnav.agents.mpc.training import train_mppi
from skidnav.agents.training import NO_EVALUATION, Evaluation
from skidnav.models.kinematic import KinematicModel
from skidnav.robot.kinematics import ACTION_NAMES

SETTINGS: dict[str, dict[str, Any]] = {
    "default": {},
    "horizon-20": {"horizon": 20},
    "cells": {"cost_to_go": "cells"},
    "single-duration": {"lattice_durations": (1.0,)},
    "control-cost": {"control_cost": 1.0},
}
MAX_STEPS = 2000
EVALUATION_SEEDS = (1001, 1002)
TURN_LEFT = ACTION_NAMES.index("left")


def world(map_kind: str, dynamics: str = "kinematic") -> gymnasium.Env[Any, Any]:
    """World 3 of ``map_kind``, slippery floor, wheel speeds every 0.1 s, pose observations, on
    ``dynamics``."""
    return gymnasium.make(
        "skidnav/SkidSteerNav-v0", map_kind=map_kind, world_seed=3, slip="slippery",
        action="continuous", observation="pose", control_period=0.1,
        max_episode_steps=MAX_STEPS, dynamics=dynamics,
    )  # fmt: skip


def turn_rates(agent: MPPIKinematicAgent) -> tuple[float, float]:
    """(learned, nominal) yaw rate [rad/s] of a full-speed turn in place: the model's, median
    over the regions with samples of their own, and the nominal robot's."""
    nominal = KinematicModel(agent.robot, agent.discretization).velocities[0, TURN_LEFT, 2]
    seen = agent.model.counts > 0
    learned = np.median(agent.model.velocities[seen, TURN_LEFT, 2]) if seen.any() else np.nan
    return float(learned), float(nominal)


def run(
    map_kind: str, setting: str, seed: int, episodes: int, evaluate: bool, dynamics: str
) -> dict[str, Any]:
    """One agent's run: its per-episode lengths, successes, collisions and evaluations."""
    env, evaluation = world(map_kind, dynamics), world(map_kind, dynamics)
    config = MPPIConfig(**SETTINGS[setting])
    agent = MPPIKinematicAgent.from_env(env, config, np.random.default_rng(seed))
    start = time.perf_counter()
    measured = Evaluation(evaluation, EVALUATION_SEEDS) if evaluate else NO_EVALUATION
    log = train_mppi(agent, env, episodes, max_steps=MAX_STEPS, evaluation=measured, seed=seed)
    successes = log.successes.tolist()
    learned_turn, nominal_turn = turn_rates(agent)
    return {
        "map": map_kind, "setting": setting, "dynamics": dynamics, "seed": seed,
        "lengths": log.lengths.tolist(), "successes": successes,
        "collisions": log.collisions.tolist(),
        "first_success": successes.index(True) + 1 if any(successes) else None,
        "evaluations_reached": (log.greedy_lengths > 0).sum(axis=1).tolist() if evaluate else None,
        "refits": agent.model.refits, "blocked": int(agent.evidence.cost_map.blocked.sum()),
        "turn_rate": round(learned_turn, 3), "nominal_turn_rate": round(nominal_turn, 3),
        "wall_time": round(time.perf_counter() - start, 1),
    }  # fmt: skip


def summary(runs: list[dict[str, Any]]) -> str:
    """Success rate, episodes to the first success (median over the runs that succeeded), mean
    length of the successful episodes and the frozen planner's share of evaluations reached."""
    successes = np.array([r["successes"] for r in runs], dtype=bool)
    lengths = np.array([r["lengths"] for r in runs])
    firsts = [r["first_success"] for r in runs if r["first_success"] is not None]
    text = (
        f"{runs[0]['map']} {runs[0]['setting']} ({runs[0]['dynamics']}): success "
        f"{successes.mean():.0%} of {successes.size} episodes; first success in episode "
        f"{sorted(firsts)} ({len(firsts)} of {len(runs)} runs); mean length of successes "
        f"{lengths[successes].mean() if successes.any() else float('nan'):.0f} actions"
    )
    if runs[0]["evaluations_reached"] is not None:
        reached = np.array([r["evaluations_reached"] for r in runs])
        text += f"; frozen planner reached {reached.sum()} of {reached.size * 2} evaluations"
        text += f" (after the last episode: {reached[:, -1].sum()} of {2 * len(runs)})"
    turns = [r["turn_rate"] for r in runs]
    return text + (
        f"; learned turn rate {min(turns):.2f}–{max(turns):.2f} rad/s (nominal "
        f"{runs[0]['nominal_turn_rate']:.2f})"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--episodes", type=int, default=5)
    parser.add_argument("--maps", nargs="+", default=["free", "obstacles"])
    parser.add_argument("--settings", nargs="+", default=["default"], choices=list(SETTINGS))
    parser.add_argument("--no-evaluation", action="store_true")
    parser.add_argument("--dynamics", choices=("kinematic", "mujoco"), default="kinematic")
    options = parser.parse_args()
    lines = []
    for setting in options.settings:
        for map_kind in options.maps:
            runs = []
            for seed in range(options.seeds):
                result = run(map_kind, setting, seed, options.episodes,
                             not options.no_evaluation, options.dynamics)  # fmt: skip
                print(json.dumps(result), flush=True)
                runs.append(result)
            lines.append(summary(runs))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
