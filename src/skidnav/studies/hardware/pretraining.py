"""Pre-training in simulation before a hardware-in-the-loop run (``[study] sim_episodes``,
docs/realtime.md, "From simulation to the robot in a study").

An arm with N > 0 simulator episodes trains its new agent, before the robot moves, in the
kinematic simulator ``skidnav/SkidSteerNav-v0`` on the run's world: the run's map, the
discretization and nominal robot of the run, and the slip field the sim server draws from the
same root seed (the preset's ``[sim] slip``, ``drift`` and ``drift_period``: the env's and the
server's ``world_seed`` streams are the same, :data:`~skidnav.seeding.ARENA_ROLES`). What
differs is what moves the robot: the simulator's ICR model with the preset's wheel-speed loss,
where the server may run the MuJoCo robot (``[sim] physics = "mujoco"``), which turns about half
as far per action (docs/physics.md). The reward is the robot's: the observed wheel-speed variance
(``variance = "observed"``, as the real-time loop measures it), and an episode ends at the goal
or after the run's ``[run] max_actions``.

Training is the agent family's own (the catalog's :meth:`~skidnav.agents.catalog.AgentEntry.bind`
… ``train``: the compiled trainer for a tabular agent, as :func:`skidnav.api.train`); the first
episode resets with the seed of the run stream's ``episodes`` child
(:data:`~skidnav.seeding.RUN_ROLES`), the agent keeps drawing from its own generator. After each
episode the greedy policy is rolled out :data:`SIM_ROLLOUTS` times in the simulator from the
seeds of the world stream's ``evaluation`` child (the same for every arm of a world), as an
experiment measures it: measurement only, nothing is learned from it.
"""

from __future__ import annotations

import math
import time
from typing import Any

import gymnasium

from skidnav.agents.catalog import entry
from skidnav.agents.training import Evaluation
from skidnav.envs.registration import ENV_ID
from skidnav.experiments.metrics import (
    SUSTAINED_WINDOW,
    evaluation_summary,
    window_success_episode,
)
from skidnav.experiments.runs import RunSpec
from skidnav.realtime.config import RealtimeConfig
from skidnav.robot.params import RobotParams
from skidnav.seeding import RUN_ROLES, WORLD_ROLES, child_sequences, seed_int
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap

SIM_ROLLOUTS = 5
"""Greedy rollouts in the simulator after each pre-training episode."""
SIM_COLUMNS = (
    "sim_episodes",
    "sim_success_last10",
    "sim_episodes_to_success90",
    "sim_greedy_success",
    "sim_seconds",
)
"""A study run's pre-training columns: simulator episodes; share of the last 10 of them that
reached the goal; the first one ending 10 consecutive simulator episodes with at least 9 goals
(:func:`~skidnav.experiments.metrics.window_success_episode`, the rule of sustained success on
the robot; NaN: never); the share of the greedy rollouts of the last 10 evaluations that reached
the goal; wall seconds of pre-training. NaN but ``sim_episodes`` for an arm without
pre-training."""


def simulator(
    config: RealtimeConfig, robot: RobotParams, grid: Discretization, grid_map: GridMap
) -> gymnasium.Env[Any, Any]:
    """The kinematic simulator of the run ``config`` (module doc), episodes cut at its
    ``[run] max_actions``."""
    return gymnasium.make(
        ENV_ID,
        max_episode_steps=config.run.max_actions,
        grid_map=grid_map,
        world_seed=config.run.seed,
        slip=config.sim.slip,
        drift_amplitude=config.sim.drift,
        drift_period=config.sim.drift_period,
        robot=robot,
        discretization=grid,
        variance="observed",
    )


def pretrain(
    agent: Any,
    spec: RunSpec[Any],
    config: RealtimeConfig,
    world: tuple[RobotParams, Discretization, GridMap],
    episodes: int,
) -> dict[str, float]:
    """Train ``agent`` (new, of ``spec``'s agent) for ``episodes`` episodes in the simulator of
    the run ``config`` on ``world`` (nominal robot, discretization, map); returns the
    :data:`SIM_COLUMNS` (module doc). Nothing happens with 0 episodes."""
    if episodes == 0:
        return dict.fromkeys(SIM_COLUMNS, math.nan) | {"sim_episodes": 0.0}
    started = time.perf_counter()
    env, eval_env = (simulator(config, *world) for _ in range(2))
    world_streams = child_sequences(spec.world_seed.sequence(), WORLD_ROLES)
    seeds = [seed_int(s) for s in world_streams["evaluation"].spawn(SIM_ROLLOUTS)]
    episodes_seed = seed_int(child_sequences(spec.run_seed.sequence(), RUN_ROLES)["episodes"])
    log = (
        entry(spec.agent.name)
        .bind(agent)
        .train(
            env.unwrapped,
            episodes,
            max_steps=config.run.max_actions,
            evaluation=Evaluation(eval_env.unwrapped, seeds),
            seed=episodes_seed,
        )
    )
    share = evaluation_summary(log.greedy_lengths)[1]
    return {
        "sim_episodes": float(episodes),
        "sim_success_last10": float(log.successes[-SUSTAINED_WINDOW:].mean()),
        "sim_episodes_to_success90": window_success_episode(log.successes),
        "sim_greedy_success": float(share[-SUSTAINED_WINDOW:].mean()),
        "sim_seconds": time.perf_counter() - started,
    }
