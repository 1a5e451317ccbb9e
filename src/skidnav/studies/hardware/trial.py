"""The trial function of a hardware-in-the-loop study (:mod:`skidnav.studies.hardware.study`):
one real-time run.

:class:`RealtimeTrial` is what :func:`skidnav.experiments.runner.run_experiment` calls for every
run of a :class:`~skidnav.studies.hardware.grid.StudyGrid`: a new agent, drawing from the run
stream, acts in real time (:class:`~skidnav.realtime.control.loop.RealtimeLoop`) on the ``sim``
driver, which starts its own server on a free loopback port with the root seed drawn from the
run's world stream (its :data:`~skidnav.seeding.ARENA_ROLES` children: map, slip field, robot
noise, dropped poses; the same for every agent of a preset and seed). The agent draws from the
``agent`` child of the run stream (:data:`~skidnav.seeding.RUN_ROLES`), as in an experiment; an
arm with pre-training trains it in the kinematic simulator first
(:mod:`skidnav.studies.hardware.pretraining`). The loop's files (``run.jsonl``,
``checkpoints/``, ``sim-server.jsonl``) go to ``OUT/runs/AGENT/PRESET/seed-N/`` (AGENT: the
arm's label); the per-episode results (:data:`EPISODE_COLUMNS`) and the run's metrics
(:func:`run_summary` and the pre-training's :data:`~skidnav.studies.hardware.pretraining.
SIM_COLUMNS`) go back to the runner, which stores them.
"""

from __future__ import annotations

import dataclasses
import shutil
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from skidnav.experiments.metrics import training_driving_metrics
from skidnav.experiments.runs import RunSpec
from skidnav.experiments.store import TrialResult
from skidnav.realtime.arena import arena_map
from skidnav.realtime.config import RealtimeConfig
from skidnav.realtime.control.loop import EXIT_INTERRUPTED
from skidnav.realtime.control.records import EpisodeResult
from skidnav.realtime.control.run import agent_context, drive, new_agent, warm_up_agent
from skidnav.robot.params import RobotParams
from skidnav.seeding import RUN_ROLES, child_sequences, seed_int
from skidnav.statistics.formatting import readable
from skidnav.studies.hardware.grid import StudyGrid
from skidnav.studies.hardware.pretraining import pretrain
from skidnav.world.discretization import Discretization

EPISODE_COLUMNS = ("return", "length", "success", "collisions", "aborted", "wall_time")
"""Per-episode arrays of a study run: undiscounted return, actions, goal reached (and not
aborted), collisions, aborted by the safety layer, wall time [s]."""


def ignore(line: str) -> None:
    """A callback that drops its line."""


def run_config(spec: RunSpec[StudyGrid]) -> RealtimeConfig:
    """The config of one run: its preset's, on the grid's map, with the world's root seed."""
    grid = spec.config
    config = grid.configs[grid.presets.index(spec.preset)]
    return dataclasses.replace(
        config,
        run=dataclasses.replace(
            config.run,
            map=spec.map.kind or spec.map.file,
            seed=seed_int(spec.world_seed.sequence()),
        ),
    )


def run_directory(out: Path, spec: RunSpec[Any]) -> Path:
    """Where the real-time files of run ``spec`` of a study in ``out`` go."""
    return out / "runs" / spec.agent.label / spec.preset / f"seed-{spec.seed}"


@dataclass(frozen=True)
class RealtimeTrial:
    """The runner's trial function of a study in ``out``: one real-time run (module docs).

    Serial backend only: the run keeps wall-clock pace and installs signal handlers. ``progress``
    gets the loop's status lines, ``announce`` one line per finished run.
    """

    out: Path
    progress: Callable[[str], None] = ignore
    announce: Callable[[str], None] = ignore

    def __call__(self, spec: RunSpec[StudyGrid]) -> TrialResult:
        """Run ``spec`` from scratch; KeyboardInterrupt if the run was interrupted (its partial
        files stay until the run starts over)."""
        directory = run_directory(self.out, spec)
        if directory.exists():
            shutil.rmtree(directory)  # left by an unfinished run
        directory.mkdir(parents=True)
        code, results, pretraining = realtime_run(spec, directory, self.progress)
        if code == EXIT_INTERRUPTED:
            raise KeyboardInterrupt
        episodes = episode_arrays(results)
        run = run_config(spec).run
        summary = run_summary(episodes, code, run.period * run.substeps) | pretraining
        self.announce(
            f"{spec.agent.label} {spec.preset} seed {spec.seed}: {summary['successes']}/"
            f"{summary['episodes']} goals, {readable(summary['mean_length'], 1)} actions/episode, "
            f"{summary['aborted']} aborted"
        )
        return TrialResult(spec.run_id, spec.coordinates, episodes, summary, {})


class RealtimeOutcome(NamedTuple):
    """What :func:`realtime_run` did: the loop's exit code, the robot episodes' results, and
    the pre-training's :data:`~skidnav.studies.hardware.pretraining.SIM_COLUMNS`."""

    code: int
    results: list[EpisodeResult]
    pretraining: dict[str, float]


def realtime_run(
    spec: RunSpec[StudyGrid], out: Path, progress: Callable[[str], None]
) -> RealtimeOutcome:
    """One real-time run of a new agent (drawing from the run stream's ``agent`` child) on the
    ``sim`` driver, its files in ``out``, after the arm's pre-training in the simulator (none
    for an arm from scratch)."""
    config = run_config(spec)
    robot, grid = RobotParams(), Discretization()
    grid_map = arena_map(config.run.map, config.run.seed, grid)
    name = spec.agent.name
    context = agent_context(name, robot, grid)
    rng = np.random.default_rng(child_sequences(spec.run_seed.sequence(), RUN_ROLES)["agent"])
    agent = new_agent(name, config, context, grid, rng)
    warm_up_agent(name, config, context, grid.n_states)
    episodes = spec.config.pretraining(spec.agent.label)
    pretraining = pretrain(agent, spec, config, (robot, grid, grid_map), episodes)
    code, loop = drive(
        "sim", agent, grid_map, config, out, robot=robot, grid=grid, progress=progress
    )
    return RealtimeOutcome(code, loop.results, pretraining)


def episode_arrays(results: Sequence[EpisodeResult]) -> dict[str, np.ndarray]:
    """The :data:`EPISODE_COLUMNS` of a run's episode results, each shape (N,)."""
    return {
        "return": np.array([r.return_ for r in results], dtype=np.float64),
        "length": np.array([r.actions for r in results], dtype=np.int64),
        "success": np.array([r.reached_goal and not r.aborted for r in results], dtype=bool),
        "collisions": np.array([r.collisions for r in results], dtype=np.int64),
        "aborted": np.array([r.aborted for r in results], dtype=bool),
        "wall_time": np.array([r.wall_time for r in results], dtype=np.float64),
    }


def _mean(values: np.ndarray) -> float:
    return float(values.mean()) if values.size else float("nan")


def run_summary(
    episodes: Mapping[str, np.ndarray], code: int, action_duration: float = float("nan")
) -> dict[str, float]:
    """A study run's metrics: episodes, successes, success rate (all episodes; the last half,
    the odd middle one included, where the agent has learned most), mean episode length
    [actions], return and collisions per episode (goal, truncated at ``max_actions`` and aborted
    episodes alike), aborted episodes, wall time [s], the loop's exit code (3: ended by a
    safety trip it could not recover from; 4: every episode aborted), and the episodes and
    seconds of driving (actions × ``action_duration`` [s], homing not counted) to the first
    success and to sustained success
    (:func:`~skidnav.experiments.metrics.training_driving_metrics`: 9 goals in 10 consecutive
    episodes; NaN when not reached). Rates are NaN without episodes."""
    success = episodes["success"]
    late = success[len(success) // 2 :]
    return {
        "episodes": len(success),
        "successes": int(success.sum()),
        "success_rate": _mean(success),
        "late_episodes": len(late),
        "late_successes": int(late.sum()),
        "success_rate_last_half": _mean(late),
        "mean_length": _mean(episodes["length"]),
        "mean_return": _mean(episodes["return"]),
        "collisions_per_episode": _mean(episodes["collisions"]),
        "aborted": int(episodes["aborted"].sum()),
        "wall_time": float(episodes["wall_time"].sum()),
        "exit_code": code,
    } | training_driving_metrics(dict(episodes), action_duration)
