"""mppi-kinematic gives the same actions and numbers with and without numba
(NUMBA_DISABLE_JIT=1): the sampling (the Generator's normals, the smoothing and the clip; white
noise and an unsampled model too), the rollouts (two model draws per sequence in one mode), the
cost maps, the lattice, the model's refits, the lidar's evidence; and so does its fast path
(``precision = "float32"``: its sampling, rollouts, a footprint's collisions, its update)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tests.nojit_support import script_arrays

TRAINING = """
import dataclasses
import sys
import gymnasium
import numpy as np
import skidnav
from skidnav.agents.mpc.agent import MPPIKinematicAgent
from skidnav.agents.mpc.config import MPPIConfig
from skidnav.agents.mpc.planner import MPPIPlanner
from skidnav.world.discretization import Discretization
from skidnav.world.mapfile import parse_map

MAP = '''skidnav-map 1
width 9
height 7
map
#########
#.......#
#...#...#
#S..#.G.#
#...#...#
#...#...#
#########
'''
grid = Discretization(n_x=9, n_y=7, n_headings=8, regions_x=3, regions_y=3)
results = {}
for mode, draws, precision in (("states", 2, "float64"), ("cells", 1, "float64"),
                               ("states", 2, "float32")):
    env = gymnasium.make(
        "skidnav/SkidSteerNav-v0", grid_map=parse_map(MAP), discretization=grid,
        slip="slippery", world_seed=1, action="continuous",
        observation="features" if mode == "states" else "pose",
        control_period=0.1,
    )
    nav = env.unwrapped
    config = MPPIConfig(
        samples=16, horizon=15, cost_to_go=mode, lattice_durations=(2.0,),
        kinematic_min_samples=5, kinematic_refit_every=20, model_draws=draws, risk="worst",
        precision=precision,
    )
    label = mode if precision == "float64" else f"{mode}_{precision}"
    agent = MPPIKinematicAgent(
        nav.robot, nav.discretization, nav.grid_map.goal, config, np.random.default_rng(4),
        lidar_rays=nav.features.lidar_rays, lidar_range=nav.features.lidar_range,
    )
    observation, _ = env.reset(seed=4)
    actions = []
    for _ in range(150):
        action = agent.act(observation)
        next_observation, reward, terminated, truncated, info = env.step(action)
        agent.observe(observation, action, reward, next_observation, terminated, truncated, info)
        observation = next_observation
        actions.append(action)
    results[f"{label}_actions"] = np.array(actions)
    results[f"{label}_costs"] = agent.planner.costs
    results[f"{label}_refits"] = np.array([agent.model.refits, agent.evidence.hits.sum()])
    for name, array in {**agent.state_arrays(), **agent.evidence.cost_map._asdict()}.items():
        results[f"{label}_{name}"] = array
for beta, sampled, precision in ((0.0, True, "float64"), (0.9, False, "float64"),
                                 (0.0, True, "float32"), (0.9, False, "float32")):
    planner = MPPIPlanner(  # the compiled sampling's other branches
        dataclasses.replace(
            config, noise_correlation=beta, sample_uncertainty=sampled, precision=precision
        ),
        agent.kernel_robot, agent.kernel_grid, np.random.default_rng(5),
    )
    planner.plan[...] = np.linspace(-2.0, 2.0, planner.plan.size).reshape(planner.plan.shape)
    controls, perturbation, draws = planner.sample()
    for name, array in (("controls", controls), ("perturbation", perturbation),
                        ("model", draws.model), ("noise", draws.noise)):
        results[f"sample_{beta}_{precision}_{name}"] = array
    results[f"sample_{beta}_{precision}_next"] = planner.rng.standard_normal(3)
# the fast rollouts of a robot with a footprint, beside two wall cells
from tests.agents.mpc.test_mppi_footprint import NARROW, ROBOT, agent_on
from tests.agents.mpc.test_mppi_single import fast_costs
jackal = agent_on(ROBOT, NARROW, precision="float32")
sequences = np.random.default_rng(6).uniform(-0.5, 1.0, (12, 10, 2)) * ROBOT.wheel_speed
results["footprint_costs"] = fast_costs(jackal, np.array([1.5, 0.95, 1.5]), sequences)
np.savez(sys.argv[1], **results)
"""


def run(out: Path, disable_jit: bool) -> dict[str, np.ndarray]:
    return script_arrays(TRAINING, out, disable_jit=disable_jit, timeout=600)


def test_same_actions_and_numbers_without_jit(tmp_path: Path) -> None:
    compiled = run(tmp_path / "jit.npz", disable_jit=False)
    interpreted = run(tmp_path / "nojit.npz", disable_jit=True)
    assert compiled.keys() == interpreted.keys()
    for key in compiled:
        assert compiled[key].tobytes() == interpreted[key].tobytes(), key
    assert compiled["footprint_costs"].max() > 100.0  # the Jackal met the walls
    for mode in ("states", "cells", "states_float32"):
        refits, hits = compiled[f"{mode}_refits"]
        assert refits >= 2  # the ridge refits ran
        # the robot ran into the wall (over poses) or saw it (over features)
        assert hits >= 1 or compiled[f"{mode}_ray_ends"].sum() >= 1
        assert np.abs(compiled[f"{mode}_actions"]).max() > 0.5  # it drove
