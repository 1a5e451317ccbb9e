"""mppi-kinematic: planning time per control step on one core, against the 0.1-s control period
(real time) and against the same step in plain NumPy, both measured in this run.

The agent first drives 150 actions of 0.1 s on world 3's obstacles arena (slippery floor), so
its model has refitted and it has met the wall; then, from that pose, with a planner of each size
(K sequences × H steps, its own Generator), one control step is timed whole
(:meth:`MPPIKinematicAgent.act`: the compiled sampling, the compiled K × H batch, the weights
and the plan's update) and in its parts (the profile), each the median of :data:`REPEATS`
timings. Its NumPy twin (:func:`numpy_control_step`) is the same step with NumPy's normals,
the AR(1) smoothing and clip as NumPy expressions, and the rollouts vectorised over the K
sequences (:func:`numpy_rollout_costs`, loop over the horizon and sub-steps), from the same
plan and Generator state: its costs are checked against the kernel's and its action against
the compiled step's. Also timed: what a change of the learned map costs (the lattice's local
refresh and its values), a refit's full refresh, and the lattice's values over the drive,
repaired where wall probabilities changed against searched again at every update.

``--grid`` times instead MPPI-Generic's grid (K = 128 … 16,384, H = 100; Vlahov et al. 2024)
and prints it as the Markdown table of docs/speed.md.
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import math
import statistics
import time
from collections.abc import Callable
from typing import Any, NamedTuple

import gymnasium
import numpy as np

import skidnav  # noqa: F401  (registers the env)
from skidnav.agents.mpc.agent import MPPIKinematicAgent
from skidnav.agents.mpc.config import MPPIConfig
from skidnav.agents.mpc.evidence import MapEvidence
from skidnav.agents.mpc.planner import MPPIPlanner
from skidnav.agents.mpc.rollouts import RolloutDraws, rollout_costs
from skidnav.agents.training import run_episode

CONTROL_PERIOD = 0.1
SETTINGS = ((256, 20), (256, 40), (1024, 40))  # (K, H)
GRID_SAMPLES = (128, 256, 512, 1024, 2048, 4096, 8192, 16384)
GRID_HORIZON = 100
REPEATS = 21
TARGET_REAL_TIME = 10.0  # control steps planned per control period


def median_seconds(call: Callable[[], Any], repeats: int = REPEATS) -> float:
    """The median wall time [s] of ``call`` over ``repeats`` calls (one warm-up call first)."""
    call()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def driven_agent(
    samples: int, horizon: int, actions: int = 150, **options: Any
) -> tuple[MPPIKinematicAgent, np.ndarray]:
    """An agent (config ``options`` besides K and H) that drove ``actions`` actions on world
    3's obstacles arena over its default observation (the features), and its pose."""
    env = gymnasium.make(
        "skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=3, slip="slippery",
        action="continuous", observation="features", control_period=CONTROL_PERIOD,
    )  # fmt: skip
    config = MPPIConfig(samples=samples, horizon=horizon, **options)
    agent = MPPIKinematicAgent.from_env(env, config, np.random.default_rng(0))
    observation, _ = env.reset(seed=0)
    run_episode(agent, env, observation, actions)
    return agent, np.asarray(env.unwrapped.pose, dtype=np.float64)


def resized(agent: MPPIKinematicAgent, samples: int, horizon: int) -> MPPIKinematicAgent:
    """``agent`` (model and map as they are) with a fresh planner of K = ``samples``,
    H = ``horizon`` and its own Generator (seed 0); the agent is changed in place."""
    agent.config = dataclasses.replace(agent.config, samples=samples, horizon=horizon)
    agent.planner = MPPIPlanner(
        agent.config, agent.kernel_robot, agent.kernel_grid, np.random.default_rng(0)
    )
    return agent


def batch(agent: MPPIKinematicAgent) -> tuple[np.ndarray, RolloutDraws]:
    """One control step's sequences (clipped) and draws, as the planner makes them (copied)."""
    controls, _, draws = agent.planner.sample()
    model, noise = draws.model.copy(), draws.noise.copy()
    return controls.copy(), RolloutDraws(model, noise, draws.noise_scale, draws.per_sequence)


def kernel_costs(agent: MPPIKinematicAgent, pose: np.ndarray, controls: np.ndarray,
                 draws: RolloutDraws) -> np.ndarray:  # fmt: skip
    """The compiled batch's costs, one per rollout (M per sequence)."""
    out = np.zeros(controls.shape[0] * draws.per_sequence)
    rollout_costs(
        pose, controls, draws, agent.dynamics, agent.evidence.cost_map, agent.costs,
        agent.kernel_robot, agent.kernel_grid, out,
    )  # fmt: skip
    return out


def numpy_batch(
    planner: MPPIPlanner, rng: np.random.Generator | None = None
) -> tuple[np.ndarray, np.ndarray, RolloutDraws]:
    """Steps 1–2 of :mod:`skidnav.agents.mpc.planner` and the draws in NumPy, from ``rng``
    (default: the planner's Generator): the sequences, their perturbations and the rollouts'
    draws, the numbers of :meth:`MPPIPlanner.sample` (the tests hold the two equal)."""
    config, limit = planner.config, planner.robot.wheel_speed
    rng = planner.rng if rng is None else rng
    white = rng.standard_normal((config.samples, config.horizon_steps, 2))
    white *= config.noise_std
    beta = config.noise_correlation
    if beta > 0.0:
        innovation = math.sqrt(1.0 - beta * beta)
        for t in range(1, config.horizon_steps):
            white[:, t] = beta * white[:, t - 1] + innovation * white[:, t]
    white[0] = 0.0
    controls = np.clip(planner.plan + white, -limit, limit)
    rollouts = config.samples * config.model_draws
    shape = ((rollouts, 5), (rollouts, config.horizon_steps, 3))
    if config.sample_uncertainty:
        model, noise = (rng.standard_normal(each) for each in shape)
        scale = 1.0 / math.sqrt(planner.robot.substeps)
    else:
        (model, noise), scale = (np.zeros(each) for each in shape), 0.0
    draws = RolloutDraws(model, noise, scale, config.model_draws)
    perturbation = white if config.plan_update == "drawn" else controls - planner.plan
    return controls, perturbation, draws


def numpy_control_step(agent: MPPIKinematicAgent, pose: np.ndarray) -> tuple[float, float]:
    """The twin of one :meth:`MPPIKinematicAgent.act` at ``pose``: :func:`numpy_batch`, the
    rollouts in NumPy (:func:`numpy_rollout_costs`) and the planner's own update."""
    planner = agent.planner
    controls, perturbation, draws = numpy_batch(planner)
    planner.draw_costs[...] = numpy_rollout_costs(agent, pose, controls, draws)
    return planner.update(perturbation)


def twin_checked(agent: MPPIKinematicAgent, pose: np.ndarray) -> None:
    """Assert that a control step and its NumPy twin, from the same plan and Generator state,
    draw the same sequences and command the same wheel speeds (to 10⁻⁹: the twin's rollouts
    sum in another order)."""
    planner = agent.planner
    saved = copy.deepcopy((planner.plan, planner.rng))
    compiled = agent.act(pose)
    planner.plan[...], planner.rng = copy.deepcopy(saved)
    twin_controls = numpy_batch(planner)[0]
    planner.plan[...], planner.rng = copy.deepcopy(saved)
    assert np.array_equal(planner.sample()[0], twin_controls)
    planner.plan[...], planner.rng = copy.deepcopy(saved)
    assert np.allclose(compiled, numpy_control_step(agent, pose), rtol=1e-9, atol=1e-9)


def numpy_rollout_costs(
    agent: MPPIKinematicAgent, pose: np.ndarray, controls: np.ndarray, draws: RolloutDraws
) -> np.ndarray:
    """The same costs as :func:`~skidnav.agents.mpc.rollouts.rollout_costs`, vectorised over
    the K sequences in NumPy (the states' terminal value, Euler or exact integration)."""
    robot, grid, costs, cost_map = (
        agent.kernel_robot,
        agent.kernel_grid,
        agent.costs,
        agent.evidence.cost_map,
    )
    controls = np.repeat(controls, draws.per_sequence, axis=0)  # rollout r: sequence r // M
    n = controls.shape[0]
    x, y, heading = np.full(n, pose[0]), np.full(n, pose[1]), np.full(n, pose[2])
    ci, cj = cells(x, y, grid)
    cost, active = np.zeros(n), np.ones(n, dtype=bool)
    for t in range(controls.shape[1]):
        moving = active.copy()
        for _ in range(robot.substeps):
            twist = numpy_twist(agent, x, y, controls[:, t], draws.model, draws.noise[:, t],
                                draws.noise_scale)  # fmt: skip
            nx, ny, nh = numpy_step(robot, x, y, heading, *twist)
            i, j = cells(nx, ny, grid)
            entered = moving & ((i != ci) | (j != cj))
            cost += np.where(entered, costs.collision_cost * cost_map.wall_probability[i, j], 0.0)
            hit = entered & cost_map.blocked[i, j]
            heading = np.where(moving, nh, heading)
            advance = moving & ~hit
            x, y = np.where(advance, nx, x), np.where(advance, ny, y)
            ci, cj = np.where(advance, i, ci), np.where(advance, j, cj)
            moving = advance
        cost += active
        active &= ~((ci == costs.goal_i) & (cj == costs.goal_j))
    return cost + np.where(active, numpy_state_value(agent, x, y, heading), 0.0)


def cells(x: np.ndarray, y: np.ndarray, grid: Any) -> tuple[np.ndarray, np.ndarray]:
    """Cells (i, j) of positions (the discretization's rule, vectorised)."""
    i = np.clip(np.floor(x / grid.arena_width * (grid.n_x - 1)), 0, grid.n_x - 1).astype(int)
    j = np.clip(np.floor(y / grid.arena_height * (grid.n_y - 1)), 0, grid.n_y - 1).astype(int)
    return i, j


def numpy_twist(
    agent: MPPIKinematicAgent,
    x: np.ndarray,
    y: np.ndarray,
    wheels: np.ndarray,
    z: np.ndarray,
    noise: np.ndarray,
    scale: float,
) -> tuple[np.ndarray, ...]:
    """:func:`~skidnav.agents.mpc.dynamics.sampled_twist`, vectorised."""
    grid = agent.kernel_grid
    ri = np.clip(np.floor(x / grid.arena_width * (grid.regions_x - 1)), 0, grid.regions_x - 1)
    rj = np.clip(np.floor(y / grid.arena_height * (grid.regions_y - 1)), 0, grid.regions_y - 1)
    region = (ri * grid.regions_y + rj).astype(int)
    m, f, o, s = (array[region] for array in agent.dynamics)
    left, right = wheels[:, 0], wheels[:, 1]
    v_x = m[:, 0] * left + m[:, 1] * right + m[:, 2]
    v_x += f[:, 0] * z[:, 0] * (left - o[:, 0]) + (f[:, 1] * z[:, 0] + f[:, 2] * z[:, 1]) * (
        right - o[:, 1]
    )
    yaw = m[:, 3] * left + m[:, 4] * right + m[:, 5]
    yaw += f[:, 3] * z[:, 2] * (left - o[:, 2]) + (f[:, 4] * z[:, 2] + f[:, 5] * z[:, 3]) * (
        right - o[:, 3]
    )
    yaw += scale * s[:, 2] * noise[:, 2]
    v_y = m[:, 6] * yaw + m[:, 7] + f[:, 6] * z[:, 4] * (yaw - o[:, 4])
    return v_x + scale * s[:, 0] * noise[:, 0], v_y + scale * s[:, 1] * noise[:, 1], yaw


def numpy_step(robot: Any, x: np.ndarray, y: np.ndarray, heading: np.ndarray, v_x: np.ndarray,
               v_y: np.ndarray, yaw: np.ndarray) -> tuple[np.ndarray, ...]:  # fmt: skip
    """One sub-step of the robot's scheme (:func:`skidnav.robot.kinematics.pose_step`) with
    the arena clip, vectorised."""
    dt = robot.dt
    if robot.exact_integration:
        turn = yaw * dt
        small = np.abs(turn) < 1e-9
        safe = np.where(small, 1.0, turn)
        sinc = np.where(small, 1.0, np.sin(turn) / safe)
        cosc = np.where(small, 0.0, (1.0 - np.cos(turn)) / safe)
        forward, lateral = (v_x * sinc - v_y * cosc) * dt, (v_x * cosc + v_y * sinc) * dt
    else:
        forward, lateral, turn = v_x * dt, v_y * dt, yaw * dt
    cos_h, sin_h = np.cos(heading), np.sin(heading)
    nx = np.clip(x + forward * cos_h - lateral * sin_h, 0.0, robot.arena_width)
    ny = np.clip(y + forward * sin_h + lateral * cos_h, 0.0, robot.arena_height)
    return nx, ny, heading + turn


def numpy_state_value(agent: MPPIKinematicAgent, x: np.ndarray, y: np.ndarray,
                      heading: np.ndarray) -> np.ndarray:  # fmt: skip
    """:func:`~skidnav.agents.mpc.costmap.interpolated_state_value`, vectorised."""
    grid, cost_map = agent.kernel_grid, agent.evidence.cost_map

    def corner(position: np.ndarray, extent: float, levels: int) -> tuple[np.ndarray, np.ndarray]:
        scaled = position / extent * (levels - 1) - 0.5
        lower = np.clip(np.floor(scaled), 0, levels - 2).astype(int)
        return lower, np.clip(scaled - lower, 0.0, 1.0)

    i0, fx = corner(x, grid.arena_width, grid.n_x)
    j0, fy = corner(y, grid.arena_height, grid.n_y)
    wrapped = np.arctan2(np.sin(heading), np.cos(heading))
    turns = (wrapped + np.pi) / (2 * np.pi) * grid.n_headings - 0.5
    k0 = np.floor(turns).astype(int)
    fh = turns - k0
    total, weights = np.zeros_like(x), np.zeros_like(x)
    for di in (0, 1):
        for dj in (0, 1):
            open_cell = ~cost_map.blocked[i0 + di, j0 + dj]
            w_cell = np.where(di, fx, 1 - fx) * np.where(dj, fy, 1 - fy) * open_cell
            for dk in (0, 1):
                k = (k0 + dk) % grid.n_headings
                weight = w_cell * np.where(dk, fh, 1 - fh)
                state = ((i0 + di) * grid.n_y + j0 + dj) * grid.n_headings + k
                total += weight * cost_map.state_value[state]
                weights += weight
    return total / weights  # the arena's interior: never all 8 blocked here


def profile(agent: MPPIKinematicAgent, pose: np.ndarray) -> dict[str, float]:
    """Median seconds of the parts of one control step."""
    planner = agent.planner
    controls, draws = batch(agent)
    perturbation = controls - planner.plan
    parts = {
        "sampling (normals, AR(1) smoothing, clip; compiled)": planner.sample,
        "compiled K x H rollouts": lambda: kernel_costs(agent, pose, controls, draws),
        "weights and plan update (NumPy)": lambda: planner.update(perturbation),
    }
    return {name: median_seconds(call) for name, call in parts.items()}


def map_change_seconds(agent: MPPIKinematicAgent) -> dict[str, float]:
    """What a change of the learned map and a refit cost: a new blocked cell (local refresh of
    the lattice and a search of its values), a refit (full)."""
    evidence, mean = agent.evidence, agent.dynamics.mean

    def new_wall() -> None:
        refreshes = evidence.table_refreshes
        evidence.hits[12, 14] += 5  # a cell beside the route, no ray across it: blocked, cleared
        evidence.reweigh(mean)
        evidence.hits[12, 14] -= 5
        evidence.reweigh(mean)
        assert evidence.table_refreshes == refreshes + 2  # became, then stopped being, lethal

    return {
        "new blocked cell (local lattice refresh + values), x2": median_seconds(new_wall, 5),
        "refit: full lattice refresh + values": median_seconds(
            lambda: evidence.reweigh(mean, model_changed=True), 3
        ),
    }


def value_update_rates(quick: bool) -> tuple[float, float]:
    """Updates of the lattice's values per second over :func:`driven_agent`'s drive (K = 256,
    H = 40; 150 actions of 0.1 s, quick 60), those after wall probabilities changed alone (not
    the lattice, whose change is searched either way): repaired around the cells that changed
    (the default), and searched again, on the same drive (the values are equal bit for bit, so
    the drives are too)."""
    spent = {False: 0.0, True: 0.0}
    calls = {False: 0, True: 0}
    update_values = MapEvidence.update_values
    driven_agent(256, 40, 20)  # compiled (or read from numba's cache) before it is timed
    for search in (False, True):

        def timed(evidence: MapEvidence, refreshed: bool, search: bool = search) -> int:
            if refreshed:  # a new lattice or new costs: searched either way
                return update_values(evidence, refreshed)
            start = time.perf_counter()
            work = update_values(evidence, search)
            spent[search] += time.perf_counter() - start
            calls[search] += 1
            return work

        MapEvidence.update_values = timed  # type: ignore[method-assign]
        try:
            driven_agent(256, 40, 60 if quick else 150)
        finally:
            MapEvidence.update_values = update_values  # type: ignore[method-assign]
    assert calls[False] == calls[True], calls
    return calls[False] / spent[False], calls[True] / spent[True]


def rollout_rates(quick: bool) -> tuple[float, float]:
    """Sequences/s of the compiled K × H batch and of its NumPy twin on the same sequences and
    draws (K = 256, H = 40; their costs checked equal): a key figure of ``make bench``
    (:mod:`key_figures`) and of the speed guard."""
    agent, pose = driven_agent(256, 40)
    controls, draws = batch(agent)
    compiled = kernel_costs(agent, pose, controls, draws)
    assert np.allclose(compiled, numpy_rollout_costs(agent, pose, controls, draws), atol=1e-9)
    kernel = median_seconds(lambda: kernel_costs(agent, pose, controls, draws), 7 if quick else 21)
    twin = median_seconds(
        lambda: numpy_rollout_costs(agent, pose, controls, draws), 3 if quick else 7
    )
    return controls.shape[0] / kernel, controls.shape[0] / twin


def step_rates(quick: bool) -> tuple[float, float]:
    """Control steps/s of one whole :meth:`MPPIKinematicAgent.act` (K = 256, H = 40) and of
    its NumPy twin (:func:`numpy_control_step`, checked to command the same wheel speeds): a
    key figure of ``make bench`` and of the speed guard."""
    agent, pose = driven_agent(256, 40)
    twin_checked(agent, pose)
    step = median_seconds(lambda: agent.act(pose), 7 if quick else REPEATS)
    twin = median_seconds(lambda: numpy_control_step(agent, pose), 3 if quick else 7)
    return 1.0 / step, 1.0 / twin


def real_time_rates(quick: bool) -> tuple[float, float]:
    """Control steps planned per second (one whole :meth:`MPPIKinematicAgent.act`, K = 256,
    H = 40) and the 10 per second of the 0.1-s control period: a key figure of ``make bench``,
    against a fixed period, so not one the speed guard checks."""
    agent, pose = driven_agent(256, 40)
    step = median_seconds(lambda: agent.act(pose), 7 if quick else REPEATS)
    return 1.0 / step, 1.0 / CONTROL_PERIOD


def report(agent: MPPIKinematicAgent, pose: np.ndarray, samples: int, horizon: int) -> None:
    """Print the figures of K = ``samples``, H = ``horizon`` planned by ``agent`` from ``pose``
    (and, for the default, the profile and the map changes)."""
    resized(agent, samples, horizon)
    twin_checked(agent, pose)
    step = median_seconds(lambda: agent.act(pose))
    twin = median_seconds(lambda: numpy_control_step(agent, pose), 5)
    controls, draws = batch(agent)
    compiled = kernel_costs(agent, pose, controls, draws)
    twin_costs = numpy_rollout_costs(agent, pose, controls, draws)
    assert np.allclose(compiled, twin_costs, rtol=1e-9, atol=1e-9), np.abs(
        compiled - twin_costs
    ).max()
    kernel = median_seconds(lambda: kernel_costs(agent, pose, controls, draws))
    numpy_time = median_seconds(lambda: numpy_rollout_costs(agent, pose, controls, draws), 5)
    steps = samples * horizon
    print(
        f"K={samples} H={horizon} ({horizon * CONTROL_PERIOD:g} s): one control step "
        f"{step * 1e3:.2f} ms ({steps / step / 1e6:.1f} M sample-steps/s) = "
        f"{CONTROL_PERIOD / step:.0f}x faster than real time (target >= {TARGET_REAL_TIME:g}x), "
        f"its NumPy twin {twin * 1e3:.1f} ms: {twin / step:.1f}x; compiled rollouts "
        f"{kernel * 1e3:.2f} ms ({steps / kernel / 1e6:.1f} M sample-steps/s), the same "
        f"rollouts in vectorised NumPy {numpy_time * 1e3:.1f} ms: {numpy_time / kernel:.0f}x"
    )
    if (samples, horizon) == (256, 40):
        for name, seconds in profile(agent, pose).items():
            print(f"  profile, {name}: {seconds * 1e3:.3f} ms ({seconds / step:.0%} of a step)")
        for name, seconds in map_change_seconds(agent).items():
            print(f"  map change, {name}: {seconds * 1e3:.1f} ms")
        repaired, searched = value_update_rates(False)
        print(
            f"  map change, the values after a wall probability changed, over the drive: "
            f"repaired {1e3 / repaired:.2f} ms, searched again {1e3 / searched:.2f} ms: "
            f"{repaired / searched:.0f}x"
        )


class PlannerPath(NamedTuple):
    """How :func:`grid_table` measures one path of the planner: ``checked(agent, pose)`` asserts
    it equals its NumPy twin, ``twin(agent, pose)`` runs the twin's control step, and
    ``profile(agent, pose)`` times its parts (sampling, rollouts, update) [s]."""

    checked: Callable[[MPPIKinematicAgent, np.ndarray], None]
    twin: Callable[[MPPIKinematicAgent, np.ndarray], Any]
    profile: Callable[[MPPIKinematicAgent, np.ndarray], dict[str, float]]


def grid_table(agent: MPPIKinematicAgent, pose: np.ndarray, path: PlannerPath | None = None) -> str:
    """MPPI-Generic's grid (K of :data:`GRID_SAMPLES`, H = :data:`GRID_HORIZON`) planned by
    ``agent`` from ``pose``, as a Markdown table: a whole control step, its rate, its parts and
    its NumPy twin, medians; ``path`` (default: the double-precision path) names the twin and
    the profile."""
    path = path or PlannerPath(twin_checked, numpy_control_step, profile)
    lines = [
        "| K | one control step | sample-steps/s | sampling | rollouts | update | "
        "NumPy twin | ratio |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for samples in GRID_SAMPLES:
        resized(agent, samples, GRID_HORIZON)
        path.checked(agent, pose)
        repeats = REPEATS if samples <= 4096 else 7
        step = median_seconds(lambda: agent.act(pose), repeats)
        twin = median_seconds(lambda: path.twin(agent, pose), 3)
        parts = path.profile(agent, pose).values()
        cells = " | ".join(f"{seconds * 1e3:.3g} ms" for seconds in parts)
        rate = samples * GRID_HORIZON / step / 1e6
        lines.append(
            f"| {samples:,} | **{step * 1e3:.3g} ms** | {rate:.1f} M | {cells} | "
            f"{twin * 1e3:.3g} ms | {twin / step:.1f}× |"
        )
        print(lines[-1], flush=True)
    return "\n".join(lines)


def grid_parser(description: str) -> argparse.ArgumentParser:
    """A benchmark's command line with ``--grid``: time MPPI-Generic's grid instead."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument(
        "--grid", action="store_true",
        help=f"time MPPI-Generic's grid (K = {GRID_SAMPLES[0]} to {GRID_SAMPLES[-1]:,}, "
        f"H = {GRID_HORIZON}) instead, printed as a Markdown table",
    )  # fmt: skip
    return parser


def main() -> None:
    arguments = grid_parser(__doc__.splitlines()[0]).parse_args()
    agent, pose = driven_agent(256, 40)
    if arguments.grid:
        print(grid_table(agent, pose))
        return
    for samples, horizon in SETTINGS:
        report(agent, pose, samples, horizon)


if __name__ == "__main__":
    main()
