"""mppi-kinematic's fast path (``precision = "float32"``): its sampling and rollouts give the
numbers of their NumPy twin (``benchmarks/bench_mppi_single.py``) bit for bit — the normals, the
sequences, the Generator's state after them, every rollout's poses and costs — and its control
step the twin's wheel speeds; it collides as the default path does, footprint included, and it
drives to a goal behind a wall."""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np
import pytest

from skidnav.agents.mpc.config import MPPIConfig
from skidnav.agents.mpc.costmap import terminal_value
from skidnav.agents.mpc.rollouts import RolloutDraws
from skidnav.agents.mpc.single import (
    box_muller,
    counter_uniform,
    float_parts,
    sin_cos,
    stream_key,
    uniform_halves,
)
from skidnav.agents.mpc.single_rollouts import BLOCK, single_rollout_costs
from skidnav.agents.mpc.training import train_mppi
from tests.agents.mpc.support import SealedEnv, agent_for, nav_env
from tests.agents.mpc.test_mppi_footprint import NARROW, POINT, ROBOT, WIDE, agent_on
from tests.benchmark_scripts import benchmark

twin = benchmark("bench_mppi_single")  # the fast path as NumPy arrays

FAST = {"precision": "float32"}


@pytest.mark.parametrize(
    "options",
    [
        {},
        {"noise_correlation": 0.0},
        {"noise_correlation": 0.9, "model_draws": 3, "noise_std": 2.0},
        {"sample_uncertainty": False, "samples": 5},
    ],
)
def test_the_fast_sampling_draws_its_twins_numbers(options: dict[str, Any]) -> None:
    agent = agent_for(nav_env(), **{"samples": 70, "horizon": 12, **FAST, **options})
    planner, limit = agent.planner, agent.robot.wheel_speed
    for _ in range(2):  # the second batch reuses the planner's arrays
        planner.plan[...] = np.random.default_rng(1).uniform(-1.2 * limit, 1.2 * limit, (12, 2))
        generator = copy.deepcopy(planner.rng)
        drawn = planner.sample()
        expected = twin.numpy_single_batch(planner, generator)
        for name, got, wanted in (
            ("controls", drawn[0], expected[0]), ("perturbation", drawn[1], expected[1]),
            ("model", drawn[2].model, expected[2].model),
            ("noise", drawn[2].noise, expected[2].noise),
        ):  # fmt: skip
            assert got.dtype == np.float32 and got.tobytes() == wanted.tobytes(), name
        assert planner.rng.bit_generator.state == generator.bit_generator.state
    controls, bound = drawn[0], np.float32(limit)
    assert np.array_equal(
        controls[:, :, 0], np.clip(planner.plan.astype(np.float32), -bound, bound)
    )
    assert controls.max() == bound and controls.min() == -bound  # some clipped
    if options.get("sample_uncertainty", True):
        assert 2.0 < np.abs(drawn[2].noise).max() < 6.0  # normals, not zeros


def test_the_normals_and_the_sine_are_close_to_the_exact_ones() -> None:
    """Box–Muller's normals from a million uniforms: mean 0, variance 1 and the tails of a
    normal to the sampling error; the polynomial sine and cosine within 2 · 10⁻⁷ of the C
    library's on |angle| ≤ 100 rad."""
    count, fraction = uniform_halves(np.random.default_rng(0).random(500_000))
    mantissa, exponent = float_parts(count.view(np.int32))
    normals = np.concatenate(box_muller(mantissa.view(np.float32), exponent, fraction))
    assert abs(normals.mean()) < 0.005 and abs(normals.var() - 1.0) < 0.005
    assert abs((np.abs(normals) > 2.0).mean() - 0.0455) < 0.001
    angles = np.linspace(-100.0, 100.0, 200_001).astype(np.float32)
    sine, cosine = sin_cos(angles)
    exact = angles.astype(np.float64)
    assert np.abs(sine - np.sin(exact)).max() < 2e-7
    assert np.abs(cosine - np.cos(exact)).max() < 2e-7


def splitmix64(state: int) -> int:
    """SplitMix64's output mix of a 64-bit state, in Python's integers (Steele et al. 2014)."""
    mask = (1 << 64) - 1
    state = ((state ^ (state >> 30)) * 0xBF58476D1CE4E5B9) & mask
    state = ((state ^ (state >> 27)) * 0x94D049BB133111EB) & mask
    return state ^ (state >> 31)


def test_the_counter_uniforms_are_splitmix64_and_look_uniform() -> None:
    """Each uniform is the high 53 bits of SplitMix64's output at key + index · γ (checked in
    Python's integers, with wrap-around); a stream of 10⁶ fills 1,000 bins as uniforms do, its
    neighbours are uncorrelated, and streams of two keys drawn one after the other too."""
    rng = np.random.default_rng(3)
    key = stream_key(rng)
    for index in (1, 2, 3, 1_000_003, 2**40 + 7):
        state = (int(key) + index * 0x9E3779B97F4A7C15) & ((1 << 64) - 1)
        wanted = (splitmix64(state) >> 11) * 2.0**-53
        assert counter_uniform(key, np.uint64(index)) == wanted
    indices = np.arange(1, 1_000_001, dtype=np.uint64)
    first, second = counter_uniform(key, indices), counter_uniform(stream_key(rng), indices)
    assert first.min() >= 0.0 and first.max() < 1.0
    counts = np.bincount((first * 1000).astype(np.int64), minlength=1000)
    chi_square = ((counts - 1000.0) ** 2 / 1000.0).sum()  # 999 degrees of freedom
    assert 880.0 < chi_square < 1120.0  # mean ± 2.7 standard deviations (√1998 ≈ 44.7)
    for a, b in ((first[:-1], first[1:]), (first, second)):
        assert abs(np.corrcoef(a, b)[0, 1]) < 0.004  # 4 standard errors of 10⁻³


def kernel_terminal_values(agent: Any, x: Any, y: Any, heading: Any, running: Any) -> Any:
    """The twin's terminal values through the kernel's own function, pose by pose."""
    grid, cost_map = agent.kernel_grid, agent.evidence.cost_map
    return np.array([
        terminal_value(float(a), float(b), float(c), cost_map, agent.costs, grid) if run else 0.0
        for a, b, c, run in zip(x, y, heading, running, strict=True)
    ])  # fmt: skip


@pytest.mark.parametrize("corner", [False, True])
def test_the_fast_rollouts_cost_what_their_twin_costs(
    corner: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Two blocks and a partial one, two model draws per sequence, a known wall cell beside the
    goal; from the cell before the goal (some rollouts end in it) and from a corner of four
    slip regions (the blocks span several): the same costs bit for bit, the terminal values
    aside; with the kernel's terminal value, all of them."""
    env = nav_env()
    agent = agent_for(env, samples=150, horizon=25, model_draws=2, **FAST)
    agent.evidence.hits[6, 6] = 2
    agent.evidence.reweigh(agent.dynamics.mean)
    grid = env.unwrapped.discretization
    x, y = grid.cell_centre(9, 5)
    if corner:  # the regions' second corner in x and in y
        x, y = (
            2 * grid.arena_width / (grid.regions_x - 1),
            2 * grid.arena_height / (grid.regions_y - 1),
        )
    pose = np.array([x, y, 0.3])
    agent.act(pose)  # a plan to sample around
    controls, _, draws = agent.planner.sample()
    wheels = np.repeat(controls, 2, axis=2)
    assert wheels.shape[2] > 2 * BLOCK and wheels.shape[2] % BLOCK != 0
    got = twin.kernel_costs(agent, pose, wheels, draws)
    expected = twin.numpy_single_rollout_costs(agent, pose, wheels, draws)
    assert np.allclose(got, expected, rtol=0.0, atol=1e-9)
    monkeypatch.setattr(twin, "terminal_values", kernel_terminal_values)
    expected = twin.numpy_single_rollout_costs(agent, pose, wheels, draws)
    assert got.tobytes() == expected.tobytes()
    if not corner:
        reached = got == np.round(got)  # whole control steps: no terminal value
        assert reached.any() and not reached.all()


@pytest.mark.parametrize(
    "options",
    [{}, {"control_cost": 0.5}, {"model_draws": 3, "risk": "worst", "noise_correlation": 0.0}],
)
def test_a_fast_control_step_commands_what_its_twin_commands(options: dict[str, Any]) -> None:
    env = nav_env(observation="features")
    agent = agent_for(env, samples=100, horizon=20, **FAST | options)
    pose = np.array([*env.unwrapped.discretization.cell_centre(3, 5), 0.0])
    for _ in range(3):
        twin.single_twin_checked(agent, pose)  # asserts it
        agent.act(pose)


def fast_costs(agent: Any, start: np.ndarray, controls: np.ndarray) -> np.ndarray:
    """The fast rollouts' costs of the sequences ``controls`` (K, H, 2) [rad/s] from
    ``start``, without model draws."""
    samples, horizon = controls.shape[:2]
    wheels = np.ascontiguousarray(controls.transpose(1, 2, 0), dtype=np.float32)
    draws = RolloutDraws(
        np.zeros((5, samples), np.float32), np.zeros((horizon, 3, samples), np.float32), 0.0, 1
    )
    out = np.zeros(samples)
    single_rollout_costs(
        start, wheels, draws, agent.dynamics, agent.evidence.cost_map, agent.costs,
        agent.kernel_robot, agent.kernel_grid, out,
    )  # fmt: skip
    return out


def test_the_fast_rollouts_collide_by_the_footprint() -> None:
    """The default path's footprint case (test_mppi_footprint): straight through a gap
    narrower than the Jackal, the point robot reaches the goal cell in 9 control steps, the
    Jackal pays the collision and stays stuck, and through the wide gap it is as fast."""
    start = np.array([1.5, 0.95, math.pi / 2])
    ahead = np.full((1, 10, 2), ROBOT.wheel_speed)
    point = fast_costs(agent_on(POINT, NARROW, **FAST), start, ahead)[0]
    jackal = fast_costs(agent_on(ROBOT, NARROW, **FAST), start, ahead)[0]
    assert point == 9.0
    assert jackal > 100.0
    assert fast_costs(agent_on(ROBOT, WIDE, **FAST), start, ahead)[0] == point


def test_the_fast_path_reaches_a_goal_behind_a_wall_in_its_first_episode() -> None:
    env = nav_env()
    agent = agent_for(env, seed=0, true=True, **FAST)
    log = train_mppi(agent, SealedEnv(env), 1, max_steps=600, seed=0)
    assert log.successes[0] and log.lengths[0] < 600
    assert log.collisions[0] >= 1  # it found the wall by running into it


def test_the_precision_is_checked_and_float64_by_default() -> None:
    assert MPPIConfig().precision == "float64"
    assert MPPIConfig.from_mapping({"precision": "float32"}).precision == "float32"
    for value in ("float16", "single", 32):
        with pytest.raises(ValueError, match="expected precision in"):
            MPPIConfig(precision=value)  # type: ignore[arg-type]
