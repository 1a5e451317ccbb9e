"""mppi-kinematic's compiled sampling draws NumPy's numbers — the sequences, the model draws,
the noise and the Generator's state after them are those of NumPy's ``standard_normal`` with the
AR(1) smoothing and the clip as NumPy expressions (the planner before they were compiled) — and
the rollouts, advanced side by side in blocks, cost each rollout as it costs alone."""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
import pytest

from skidnav.agents.mpc.rollouts import BLOCK, RolloutDraws, rollout_costs
from tests.agents.mpc.support import agent_for, nav_env
from tests.benchmark_scripts import benchmark

bench_mppi = benchmark("bench_mppi")  # its NumPy twin: the sampling as NumPy does it


@pytest.mark.parametrize(
    "options",
    [
        {},
        {"noise_correlation": 0.0},
        {"noise_correlation": 0.9, "model_draws": 3, "noise_std": 2.0},
        {"sample_uncertainty": False},
        {"plan_update": "drawn"},
        {"plan_update": "drawn", "noise_correlation": 0.0},
    ],
)
def test_the_compiled_sampling_draws_numpys_numbers(options: dict[str, Any]) -> None:
    agent = agent_for(nav_env(), samples=70, horizon=12, **options)
    planner, limit = agent.planner, agent.robot.wheel_speed
    for _ in range(2):  # the second batch reuses the planner's arrays
        planner.plan[...] = np.random.default_rng(1).uniform(-1.2 * limit, 1.2 * limit, (12, 2))
        twin = copy.deepcopy(planner.rng)
        drawn = planner.sample()
        sampled = (drawn[0], drawn[1], drawn[2].model, drawn[2].noise)
        controls, perturbation, draws = bench_mppi.numpy_batch(planner, twin)
        for name, got, expected in zip(
            ("controls", "perturbation", "model", "noise"), sampled,
            (controls, perturbation, draws.model, draws.noise), strict=True,
        ):  # fmt: skip
            assert got.tobytes() == expected.tobytes(), name
        assert planner.rng.bit_generator.state == twin.bit_generator.state
    controls = drawn[0]
    assert np.array_equal(controls[0], np.clip(planner.plan, -limit, limit))  # the plan itself
    assert controls.max() == limit and controls.min() == -limit  # some clipped
    if options.get("sample_uncertainty", True):
        assert np.abs(drawn[2].noise).max() > 2.0  # normals, not zeros
    clipped = controls - planner.plan
    if options.get("plan_update") == "drawn":  # ε as drawn: beyond the limit where clipped
        assert np.abs(drawn[1] - clipped).max() > 0.1
        assert np.array_equal(drawn[1][0], np.zeros_like(drawn[1][0]))
    else:
        assert np.array_equal(drawn[1], clipped)


def test_rollouts_in_blocks_cost_each_rollout_as_alone() -> None:
    """Rollouts of a batch of several blocks and a partial one, two model draws per sequence,
    beside a known wall, some ending in the goal cell and some not, cost what each costs rolled
    out alone."""
    env = nav_env()
    samples, horizon, draws_per_sequence = 150, 25, 2
    agent = agent_for(env, samples=samples, horizon=horizon, model_draws=draws_per_sequence)
    grid = env.unwrapped.discretization
    agent.evidence.hits[6, 6] = 2  # a known wall cell beside the goal's row
    agent.evidence.reweigh(agent.dynamics.mean)
    x, y = grid.cell_centre(9, 5)  # the cell before the goal (10, 5)
    pose = np.array([x, y, 0.0])
    agent.act(pose)  # a plan to sample around
    controls, _, draws = agent.planner.sample()
    rollouts = samples * draws_per_sequence
    assert rollouts > 4 * BLOCK and rollouts % BLOCK != 0
    out = np.zeros(rollouts)
    arguments = (agent.dynamics, agent.evidence.cost_map, agent.costs, agent.kernel_robot)
    rollout_costs(pose, controls, draws, *arguments, agent.kernel_grid, out)
    for k in range(samples):
        rows = slice(k * draws_per_sequence, (k + 1) * draws_per_sequence)
        alone = RolloutDraws(
            draws.model[rows], draws.noise[rows], draws.noise_scale, draws_per_sequence
        )
        cost = np.zeros(draws_per_sequence)
        rollout_costs(pose, controls[k : k + 1], alone, *arguments, agent.kernel_grid, cost)
        assert cost.tobytes() == out[rows].tobytes(), k
    reached = out == np.round(out)  # whole control steps, no terminal value
    assert reached.any() and not reached.all()
