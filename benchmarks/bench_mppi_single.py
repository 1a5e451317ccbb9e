"""mppi-kinematic's fast path (``precision = "float32"``, :mod:`skidnav.agents.mpc.single`)
against its NumPy twin: the same control step with the counter-based uniforms computed by
NumPy over all indices at once (the stream's key drawn from the Generator), the Box–Muller
normals, the AR(1) smoothing and the clip, the slip regions, twists, poses and cells as float32
NumPy arrays over all rollouts at once — the same float32 formulas
(:mod:`~skidnav.agents.mpc.single`), run on arrays — then the weights and the plan's update in
NumPy (:func:`numpy_single_update`). The twin draws the same sequences
and rolls out the same poses bit for bit; its terminal value is
:func:`bench_mppi.numpy_state_value`'s (double precision, summed in another order) and its
update's sums are NumPy's, so its costs agree to 10⁻⁹ and its wheel speeds to 10⁻⁹.

Run alone (``make bench`` runs it), it prints the fast path's control step at K = 256, H = 40
against its twin, against the default path and against the 0.3-ms target of 35 M
sample-steps/s (:data:`TARGET_STEP`), with a profile; ``--grid`` times MPPI-Generic's grid
(K = 128 … 16,384, H = 100) instead, printed as the Markdown table of docs/speed.md.
"""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np
from bench_mppi import (
    CONTROL_PERIOD,
    REPEATS,
    PlannerPath,
    cells,
    driven_agent,
    grid_parser,
    median_seconds,
    numpy_state_value,
)
from bench_mppi import (
    grid_table as bench_mppi_grid_table,
)

from skidnav.agents.mpc.agent import MPPIKinematicAgent
from skidnav.agents.mpc.planner import MPPIPlanner
from skidnav.agents.mpc.rollouts import RolloutDraws
from skidnav.agents.mpc.single import (
    box_muller,
    counter_uniform,
    float_parts,
    level,
    pose_step,
    sampled_twist,
    stream_key,
    uniform_halves,
)
from skidnav.agents.mpc.single_rollouts import single_rollout_costs
from skidnav.agents.mpc.single_sampling import normal_count

F32 = np.float32
FAST = {"precision": "float32"}
TARGET_STEP = 0.3e-3
"""The target [s] of one control step at K = 256, H = 40: 35 M sample-steps/s, the rate of
Nav2's CPU MPPI controller (256 × 100 in 0.729 ms on an i9-13900K)."""


def numpy_single_batch(
    planner: MPPIPlanner, rng: np.random.Generator | None = None
) -> tuple[np.ndarray, np.ndarray, RolloutDraws]:
    """:meth:`MPPIPlanner.sample_single` in NumPy from ``rng`` (default: the planner's
    Generator): the sequences and perturbations float32 (H, 2, K), the draws (float32 (5, R)
    and (H, 3, R))."""
    config, limit = planner.config, F32(planner.robot.wheel_speed)
    rng = planner.rng if rng is None else rng
    samples, horizon = config.samples, config.horizon_steps
    rollouts = samples * config.model_draws
    words = (normal_count(samples, horizon, rollouts, config.sample_uncertainty) + 1) // 2
    indices = np.arange(1, words + 1, dtype=np.uint64)
    count, fraction = uniform_halves(counter_uniform(stream_key(rng), indices))
    mantissa_bits, exponent = float_parts(count.view(np.int32))
    cosines, sines = box_muller(mantissa_bits.view(np.float32), exponent, fraction)
    normals = np.concatenate([cosines, sines])
    white = normals[: 2 * samples * horizon].reshape(horizon, 2, samples)
    beta = config.noise_correlation
    innovation, sigma = F32(math.sqrt(1.0 - beta * beta)), F32(config.noise_std)
    plan = planner.plan.astype(np.float32)[:, :, None]
    smoothed = np.empty_like(white)
    smoothed[0] = white[0] * sigma
    for t in range(1, horizon):
        smoothed[t] = F32(beta) * smoothed[t - 1] + innovation * (white[t] * sigma)
    smoothed[:, :, 0] = 0.0
    controls = np.clip(plan + smoothed, -limit, limit)
    if config.sample_uncertainty:
        start = 2 * samples * horizon
        model = normals[start : start + 5 * rollouts].reshape(5, rollouts)
        noise = normals[start + 5 * rollouts : start + (5 + 3 * horizon) * rollouts]
        scale = 1.0 / math.sqrt(planner.robot.substeps)
        draws = RolloutDraws(model, noise.reshape(horizon, 3, rollouts), scale, config.model_draws)
    else:
        zeros = np.zeros((5, rollouts), F32), np.zeros((horizon, 3, rollouts), F32)
        draws = RolloutDraws(*zeros, 0.0, config.model_draws)
    return controls, controls - plan, draws


def numpy_single_rollout_costs(
    agent: MPPIKinematicAgent, pose: np.ndarray, wheels: np.ndarray, draws: RolloutDraws
) -> np.ndarray:
    """:func:`~skidnav.agents.mpc.single_rollouts.single_rollout_costs` vectorised over the
    R rollouts in NumPy (a point robot, the states' terminal value)."""
    robot, grid, costs, cost_map = (
        agent.kernel_robot, agent.kernel_grid, agent.costs, agent.evidence.cost_map,
    )  # fmt: skip
    assert robot.footprint_length == 0.0 and costs.use_states
    tables = [table.astype(np.float32) for table in agent.dynamics]
    count = wheels.shape[2]
    x, y, heading = (np.full(count, F32(value)) for value in pose)
    i, j = levels(x, y, grid, (grid.n_x, grid.n_y))
    cost, running = np.zeros(count), np.ones(count, dtype=bool)
    dt, arena = F32(robot.dt), (F32(robot.arena_width), F32(robot.arena_height))
    for t in range(wheels.shape[0]):
        moving = running.copy()
        for _ in range(robot.substeps):
            ri, rj = levels(x, y, grid, (grid.regions_x, grid.regions_y))
            region = (ri * F32(grid.regions_y) + rj).astype(np.int64)
            twist = sampled_twist(
                tuple(table[region].T for table in tables), (wheels[t, 0], wheels[t, 1]),
                tuple(draws.model), tuple(draws.noise[t]), F32(draws.noise_scale),
            )  # fmt: skip
            new_x, new_y, new_heading = pose_step(
                (x, y, heading), twist, dt, robot.exact_integration, arena
            )
            new_i, new_j = levels(new_x, new_y, grid, (grid.n_x, grid.n_y))
            entered = moving & ((new_i != i) | (new_j != j))
            cell = new_i.astype(np.int64), new_j.astype(np.int64)
            cost += np.where(entered, costs.collision_cost * cost_map.wall_probability[cell], 0.0)
            heading = np.where(moving, new_heading, heading)
            moving &= ~(entered & cost_map.blocked[cell])
            x, y = np.where(moving, new_x, x), np.where(moving, new_y, y)
            i, j = np.where(moving, new_i, i), np.where(moving, new_j, j)
        cost += running
        running &= ~((i == F32(costs.goal_i)) & (j == F32(costs.goal_j)))
    return cost + terminal_values(agent, x, y, heading, running)


def levels(
    x: np.ndarray, y: np.ndarray, grid: Any, counts: tuple[int, int]
) -> tuple[np.ndarray, np.ndarray]:
    """⌊x (n − 1)/W⌋ and ⌊y (m − 1)/H⌋ of ``counts`` (n, m) levels, clipped, float32."""
    scale_x = F32((counts[0] - 1) / grid.arena_width)
    scale_y = F32((counts[1] - 1) / grid.arena_height)
    return level(x, scale_x, F32(counts[0] - 1)), level(y, scale_y, F32(counts[1] - 1))


def terminal_values(agent: MPPIKinematicAgent, x: np.ndarray, y: np.ndarray,
                    heading: np.ndarray, running: np.ndarray) -> np.ndarray:  # fmt: skip
    """The states' terminal value of the running rollouts' final poses in double precision (0
    in the goal cell and for the others)."""
    x, y, heading = (value.astype(np.float64) for value in (x, y, heading))
    grid, costs = agent.kernel_grid, agent.costs
    i, j = cells(x, y, grid)
    goal = (i == costs.goal_i) & (j == costs.goal_j)
    return np.where(running & ~goal, numpy_state_value(agent, x, y, heading), 0.0)


def numpy_single_update(planner: MPPIPlanner, perturbation: np.ndarray) -> tuple[float, float]:
    """:func:`~skidnav.agents.mpc.single_update.update_plan` in NumPy (its sums NumPy's) from
    the planner's :attr:`~MPPIPlanner.draw_costs`: the plan moved and shifted in place; the
    wheel speeds to command now."""
    config, limit = planner.config, planner.robot.wheel_speed
    per_sequence = planner.draw_costs.reshape(config.samples, config.model_draws)
    costs = per_sequence.max(axis=1) if config.risk == "worst" else per_sequence.mean(axis=1)
    if config.control_cost > 0.0:
        control_cost = np.einsum("ha,hak->k", planner.plan, perturbation.astype(np.float64))
        costs = costs + config.control_cost / config.noise_std**2 * control_cost
    weights = np.exp(-(costs - costs.min()) / planner.temperature)
    weights /= weights.sum()
    planner.plan += np.einsum("k,hak->ha", weights, perturbation.astype(np.float64))
    np.clip(planner.plan, -limit, limit, out=planner.plan)
    left, right = float(planner.plan[0, 0]), float(planner.plan[0, 1])
    planner.plan[:-1] = planner.plan[1:].copy()
    return left, right


def numpy_single_control_step(agent: MPPIKinematicAgent, pose: np.ndarray) -> tuple[float, float]:
    """The twin of one :meth:`MPPIKinematicAgent.act` of the fast path at ``pose``."""
    planner = agent.planner
    controls, perturbation, draws = numpy_single_batch(planner)
    wheels = np.repeat(controls, draws.per_sequence, axis=2)
    planner.draw_costs[...] = numpy_single_rollout_costs(agent, pose, wheels, draws)
    return numpy_single_update(planner, perturbation)


def single_twin_checked(agent: MPPIKinematicAgent, pose: np.ndarray) -> None:
    """Assert that a fast control step and its NumPy twin, from the same plan and Generator
    state, draw the same sequences bit for bit and command the same wheel speeds (to 10⁻⁹)."""
    planner = agent.planner
    saved = copy.deepcopy((planner.plan, planner.rng))
    compiled = agent.act(pose)
    planner.plan[...], planner.rng = copy.deepcopy(saved)
    twin_controls = numpy_single_batch(planner)[0]
    planner.plan[...], planner.rng = copy.deepcopy(saved)
    assert planner.sample()[0].tobytes() == twin_controls.tobytes()
    planner.plan[...], planner.rng = copy.deepcopy(saved)
    assert np.allclose(compiled, numpy_single_control_step(agent, pose), rtol=1e-9, atol=1e-9)


def kernel_costs(agent: MPPIKinematicAgent, pose: np.ndarray, wheels: np.ndarray,
                 draws: RolloutDraws) -> np.ndarray:  # fmt: skip
    """The compiled fast batch's costs, one per rollout."""
    out = np.zeros(wheels.shape[2])
    single_rollout_costs(
        pose, wheels, draws, agent.dynamics, agent.evidence.cost_map, agent.costs,
        agent.kernel_robot, agent.kernel_grid, out,
    )  # fmt: skip
    return out


def step_rates(quick: bool) -> tuple[float, float]:
    """Control steps/s of one whole :meth:`MPPIKinematicAgent.act` of the fast path
    (K = 256, H = 40) and of its NumPy twin (checked to command the same wheel speeds): a key
    figure of ``make bench`` and of the speed guard."""
    agent, pose = driven_agent(256, 40, **FAST)
    single_twin_checked(agent, pose)
    step = median_seconds(lambda: agent.act(pose), 7 if quick else REPEATS)
    twin = median_seconds(lambda: numpy_single_control_step(agent, pose), 3 if quick else 7)
    return 1.0 / step, 1.0 / twin


def target_rates(quick: bool) -> tuple[float, float]:
    """Control steps/s of one whole fast :meth:`MPPIKinematicAgent.act` (K = 256, H = 40) and
    the 1 / 0.3 ms of the target (:data:`TARGET_STEP`): a key figure of ``make bench``, against
    a fixed rate, so not one the speed guard checks."""
    agent, pose = driven_agent(256, 40, **FAST)
    return 1.0 / median_seconds(lambda: agent.act(pose), 21 if quick else 101), 1.0 / TARGET_STEP


def profile(agent: MPPIKinematicAgent, pose: np.ndarray) -> dict[str, float]:
    """Median seconds of the parts of one fast control step, on one batch's copy."""
    planner = agent.planner
    controls, perturbation, draws = planner.sample()
    wheels = np.repeat(controls, draws.per_sequence, axis=2)
    draws = RolloutDraws(draws.model.copy(), draws.noise.copy(), draws.noise_scale,
                         draws.per_sequence)  # fmt: skip
    perturbation = perturbation.copy()
    plan = planner.plan.copy()

    def update() -> None:
        planner.plan[...] = plan
        planner.update(perturbation)

    parts = {
        "sampling (uniforms, Box-Muller, AR(1) smoothing, clip; compiled)": planner.sample,
        "compiled K x H rollouts": lambda: kernel_costs(agent, pose, wheels, draws),
        "weights and plan update (compiled)": update,
    }
    return {name: median_seconds(call) for name, call in parts.items()}


def grid_table(agent: MPPIKinematicAgent, pose: np.ndarray) -> str:
    """:func:`bench_mppi.grid_table` for the fast path: MPPI-Generic's grid planned by
    ``agent`` (``precision = "float32"``) from ``pose``, as a Markdown table."""
    path = PlannerPath(single_twin_checked, numpy_single_control_step, profile)
    return bench_mppi_grid_table(agent, pose, path)


def main() -> None:
    arguments = grid_parser(__doc__.splitlines()[0]).parse_args()
    agent, pose = driven_agent(256, 40, **FAST)
    if arguments.grid:
        print(grid_table(agent, pose))
        return
    single_twin_checked(agent, pose)
    step = median_seconds(lambda: agent.act(pose), 101)
    twin = median_seconds(lambda: numpy_single_control_step(agent, pose), 7)
    default, default_pose = driven_agent(256, 40)
    double = median_seconds(lambda: default.act(default_pose), 101)
    rate = 256 * 40 / step / 1e6
    print(
        f"fast path (precision float32), K=256 H=40: one control step {step * 1e3:.3f} ms "
        f"({rate:.1f} M sample-steps/s, {CONTROL_PERIOD / step:.0f}x faster than real time); "
        f"target <= {TARGET_STEP * 1e3:g} ms (35 M sample-steps/s): "
        f"{'reached' if step <= TARGET_STEP else 'not reached'}; its NumPy twin "
        f"{twin * 1e3:.2f} ms: {twin / step:.1f}x; the default path (float64) "
        f"{double * 1e3:.3f} ms: {double / step:.2f}x"
    )
    for name, seconds in profile(agent, pose).items():
        print(f"  profile, {name}: {seconds * 1e3:.3f} ms ({seconds / step:.0%} of a step)")


if __name__ == "__main__":
    main()
