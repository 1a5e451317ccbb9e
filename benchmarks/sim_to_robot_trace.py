"""Why a simulator's pre-training helps or not on the robot (docs/robot-learning.md, "From
simulation to the robot, measured"), read from a hardware-in-the-loop study with
``[study] sim_episodes`` (``configs/hil-sim-to-robot.toml``), one line per run:

* the goals in each block of 10 robot episodes;
* how far a turn action turned: on the robot, the median |Δheading| [rad] of the run's turn
  actions that met no wall (from the run log's poses), and in the simulator of its world
  (:func:`skidnav.studies.hardware.pretraining.simulator`), the median of 40 turns in place
  from the start;
* what the agent's kinematic model says at its last checkpoint: the turn of a 1-s turn action
  [rad] and the ICR offset x_ICR [m] (means over the regions with samples), with the samples it
  had at its last refit and those it had before the robot (all its samples minus the robot's):
  a model whose last refit came before the robot never learned the robot's turning.

    python benchmarks/sim_to_robot_trace.py runs/hil-sim-to-robot
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from skidnav.experiments.runs import expand_runs
from skidnav.experiments.store import ResultStore
from skidnav.realtime.arena import arena_map
from skidnav.robot.kinematics import wrap_angle
from skidnav.robot.params import RobotParams
from skidnav.studies.hardware.pretraining import simulator
from skidnav.studies.hardware.study import STUDY_LAYOUT
from skidnav.studies.hardware.trial import run_config, run_directory
from skidnav.world.discretization import Discretization

TURNS = (2, 3)
"""The discrete actions that turn in place (left, right)."""


def robot_turns(log: Path) -> tuple[list[int], float, int]:
    """(goals per episode, median |Δheading| of the turn actions that met no wall [rad], rows
    of the kinematic log) of a run log."""
    goals: list[int] = []
    turns: list[float] = []
    rows, previous = 0, None
    for line in log.read_text(encoding="utf-8").splitlines():
        record = json.loads(line)
        event = record.get("event")
        if event == "episode_start":
            previous = None
        elif event == "transition":
            heading = record["pose"][2]
            if previous is not None and record["action"] in TURNS and not record["collision"]:
                turns.append(abs(wrap_angle(heading - previous)))
            previous, rows = heading, rows + record["log_rows"]
        elif event == "episode_end":
            goals.append(int(record["reached_goal"]))
    return goals, float(np.median(turns)) if turns else float("nan"), rows


def simulated_turn(config: object) -> float:
    """Median |Δheading| [rad] of 40 turns in place from the start in the run's simulator."""
    robot, grid = RobotParams(), Discretization()
    grid_map = arena_map(config.run.map, config.run.seed, grid)  # type: ignore[attr-defined]
    env = simulator(config, robot, grid, grid_map)  # type: ignore[arg-type]
    env.reset(seed=0)
    turns = []
    for k in range(40):
        before = env.unwrapped.pose[2]
        env.step(TURNS[k % 2])
        turns.append(abs(wrap_angle(env.unwrapped.pose[2] - before)))
    return float(np.median(turns))


def model_turn(directory: Path) -> tuple[float, float, int, int]:
    """(turn of a 1-s turn action [rad], x_ICR [m], samples at the last refit, samples in all)
    of the agent in the run's newest checkpoint."""
    latest = max((directory / "checkpoints").glob("ep-*/agent.npz"))
    saved = np.load(latest)
    robot = RobotParams()
    counts, coefficients = saved["kinematic_counts"], saved["kinematic_coefficients"]
    fitted = coefficients[counts > 0]
    yaw_rate = (fitted[:, 4] - fitted[:, 3]) * robot.wheel_speed  # turn left: (−ω, +ω)
    turn = float(np.mean(yaw_rate)) * robot.action_duration
    return turn, float(-fitted[:, 6].mean()), int(saved["kinematic_refits"][1]), int(counts.sum())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run_dir", type=Path)
    out = parser.parse_args().run_dir
    grid = ResultStore(out, STUDY_LAYOUT).config()
    print(
        "arm | preset | seed | goals per 10 episodes | robot turn | simulator turn | model "
        "turn | model x_ICR | samples at last refit | samples before the robot"
    )
    for spec in expand_runs(grid):
        directory = run_directory(out, spec)
        if not (directory / "run.jsonl").exists():
            continue
        goals, turn, rows = robot_turns(directory / "run.jsonl")
        blocks = " ".join(str(sum(goals[k : k + 10])) for k in range(0, len(goals), 10))
        modelled, x_icr, at_refit, samples = model_turn(directory)
        print(
            f"{spec.agent.label} | {spec.preset} | {spec.seed} | {blocks} | {turn:.3f} "
            f"| {simulated_turn(run_config(spec)):.3f} | {modelled:.3f} | {x_icr:.4f} "
            f"| {at_refit} | {samples - rows}"
        )


if __name__ == "__main__":
    main()
