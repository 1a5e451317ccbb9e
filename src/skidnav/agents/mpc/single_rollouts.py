"""The K × H rollouts of the fast path (``MPPIConfig.precision = "float32"``): the rules of
:mod:`~skidnav.agents.mpc.rollouts` (the slip region's sampled twist, the robot's scheme
clipped to the arena, the collision cost C · p on entering a cell, a blocked cell or a
footprint's contact stopping the motion for the rest of the control step, 1 per control step,
the goal cell ending a rollout, the terminal value), in single precision and in another loop
order: a block of rollouts advances one sub-step together, in passes over the block, and every
block takes its control step t before any takes step t + 1 (the inputs then read in order).

The passes of plain arithmetic (:mod:`~skidnav.agents.mpc.single`: the slip region, the twist,
the sine and cosine, the new pose and its cell) read and write one scratch array at offsets
fixed when compiling (row · :data:`BLOCK` + b), which lets the compiler prove the rows apart and
vectorise the loop over the block; the twist is computed once per slip region present in the
block (a rollout takes its own region's), so no loop gathers. A scalar pass then keeps the new
pose of the rollouts still moving and pays the cells entered (a cell changes every few steps,
so its branches are predicted). A position's cell and region are ⌊x · (n − 1)/W⌋ in float32
(at most n − 1), the terminal value the double-precision one of the final pose
(:func:`~skidnav.agents.mpc.costmap.terminal_value`), costs summed in float64. The same numbers
compiled and interpreted (``NUMBA_DISABLE_JIT=1``)."""

from __future__ import annotations

import numpy as np

from skidnav._jit import vector_inline_jit, vector_jit
from skidnav.agents.mpc.costmap import CostMap, MapCosts, terminal_value
from skidnav.agents.mpc.dynamics import SampledDynamics
from skidnav.agents.mpc.rollouts import RolloutDraws
from skidnav.agents.mpc.single import choose, level, pose_step, sampled_twist
from skidnav.robot.params import KinematicConstants
from skidnav.sim.footprint import footprint_collides
from skidnav.world.discretization import GridShape

F32 = np.float32
BLOCK = 128
"""Rollouts advanced together: their scratch rows (28 × 128 float32, 14 kB) stay in the
first-level cache."""
X, Y, HEADING, NEW_X, NEW_Y, NEW_HEADING, NEW_I, NEW_J, CELL_I, CELL_J = range(10)
RUNNING, MOVING, STOP, REGION, V_X, V_Y, YAW, LEFT, RIGHT = range(10, 19)
MODEL, NOISE, ENTERED = 19, 24, 27  # 5 rows, 3 rows, 1 row
ROWS = 28
"""Rows of the scratch: the pose, the new pose, its cell and the cell (whole float32 numbers),
whether running (out of the goal cell), moving (within this control step) and stopped (this
sub-step) as float32 1 or 0, the slip region, the twist, the wheel speeds, the 5 model draws,
the step's 3 noise normals, and whether moving into another cell (1 or 0)."""


@vector_jit
def single_rollout_costs(
    pose: np.ndarray,
    wheels: np.ndarray,
    draws: RolloutDraws,
    dynamics: SampledDynamics,
    cost_map: CostMap,
    costs: MapCosts,
    robot: KinematicConstants,
    grid: GridShape,
    out: np.ndarray,
) -> None:
    """The cost of every rollout (module doc).

    Args:
        pose: float64 (3,) the start (x [m], y [m], heading [rad]).
        wheels: float32 (H, 2, R) the wheel speeds (ω_L, ω_R) [rad/s] each rollout holds at
            each control step (rollout r drives sequence r // M).
        draws: the standard normals, float32: ``model`` (5, R), ``noise`` (H, 3, R).
        dynamics: the model's arrays (float64; read in float32). cost_map, costs, robot, grid:
            as :func:`~skidnav.agents.mpc.rollouts.rollout_costs`.
        out: float64 (R,) receives the costs [control steps].
    """
    tables = (
        dynamics.mean.astype(np.float32), dynamics.factors.astype(np.float32),
        dynamics.offsets.astype(np.float32), dynamics.noise_std.astype(np.float32),
    )  # fmt: skip
    blocks = (out.shape[0] + BLOCK - 1) // BLOCK
    scratch = np.zeros((blocks, ROWS * BLOCK), np.float32)  # a block's rows, one block a row
    present = np.zeros(dynamics.mean.shape[0], np.bool_)  # the slip regions of a block
    poses = np.zeros((3, BLOCK))  # float64 poses for the double-precision code
    for block in range(blocks):
        first = block * BLOCK
        start_block(first, min(BLOCK, out.shape[0] - first), pose, draws, grid, scratch[block], out)
    for t in range(wheels.shape[0]):  # each step of every block: the inputs read in order
        for block in range(blocks):
            first = block * BLOCK
            size = min(BLOCK, out.shape[0] - first)
            advance(first, size, t, wheels, draws, (tables, present, poses), cost_map, costs,
                    robot, grid, scratch[block], out)  # fmt: skip
    for block in range(blocks):
        first = block * BLOCK
        size = min(BLOCK, out.shape[0] - first)
        widened(scratch[block], size, X, poses)
        for b in range(size):
            if scratch[block, RUNNING * BLOCK + b] > F32(0.0):
                out[first + b] += terminal_value(
                    poses[0, b], poses[1, b], poses[2, b], cost_map, costs, grid
                )  # fmt: skip


@vector_inline_jit
def start_block(
    first: int,
    size: int,
    pose: np.ndarray,
    draws: RolloutDraws,
    grid: GridShape,
    scratch: np.ndarray,
    out: np.ndarray,
) -> None:
    """Rollouts ``first`` to ``first + size − 1`` at the start ``pose`` and its cell, running,
    their model draws in their rows of ``scratch`` (the block's), their costs 0."""
    for b in range(size):
        scratch[X * BLOCK + b] = F32(pose[0])
        scratch[Y * BLOCK + b] = F32(pose[1])
        scratch[HEADING * BLOCK + b] = F32(pose[2])
        for row in range(5):
            scratch[(MODEL + row) * BLOCK + b] = draws.model[row, first + b]
        scratch[RUNNING * BLOCK + b] = F32(1.0)
        out[first + b] = 0.0
    levels(scratch, size, grid, X, CELL_I)


@vector_inline_jit
def widened(scratch: np.ndarray, size: int, source: int, poses: np.ndarray) -> None:
    """The poses of rows ``source`` to ``source + 2`` into ``poses`` float64 (3, BLOCK), for the
    double-precision code (terminal value, footprint) to read in another loop: a float32
    widened and passed straight to ``math.sin`` lets the compiler call the single-precision
    sine instead (``sinf``; also cosine, arctangent), other numbers than the interpreter's."""
    for row in range(3):
        for b in range(size):
            poses[row, b] = float(scratch[(source + row) * BLOCK + b])


@vector_inline_jit
def advance(
    first: int,
    size: int,
    t: int,
    wheels: np.ndarray,
    draws: RolloutDraws,
    work: tuple[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray, np.ndarray],
    cost_map: CostMap,
    costs: MapCosts,
    robot: KinematicConstants,
    grid: GridShape,
    scratch: np.ndarray,
    out: np.ndarray,
) -> None:
    """Control step ``t`` of rollouts ``first`` to ``first + size − 1`` (module doc): their
    rows of ``scratch`` and costs in ``out`` updated (other arguments as
    :func:`single_rollout_costs`; ``work``: the model's float32 tables, the regions present
    bool (n_regions,) and float64 (3, BLOCK) poses, scratch)."""
    tables, present, poses = work
    for b in range(size):
        scratch[LEFT * BLOCK + b] = wheels[t, 0, first + b]
        scratch[RIGHT * BLOCK + b] = wheels[t, 1, first + b]
        for row in range(3):
            scratch[(NOISE + row) * BLOCK + b] = draws.noise[t, row, first + b]
        scratch[MOVING * BLOCK + b] = scratch[RUNNING * BLOCK + b]
    for _ in range(robot.substeps):
        twists(scratch, size, tables, present, F32(draws.noise_scale), grid)
        move(scratch, size, robot, grid)
        stops(first, size, cost_map, costs, robot, grid, scratch, poses, out)
        commit(scratch, size)
    goal_i, goal_j = F32(costs.goal_i), F32(costs.goal_j)
    for b in range(size):  # vectorised
        running = scratch[RUNNING * BLOCK + b]
        out[first + b] += float(running)
        in_goal = (scratch[CELL_I * BLOCK + b] == goal_i) & (scratch[CELL_J * BLOCK + b] == goal_j)
        scratch[RUNNING * BLOCK + b] = running * (F32(1.0) - F32(in_goal))


@vector_inline_jit
def levels(scratch: np.ndarray, size: int, grid: GridShape, source: int, target: int) -> None:
    """The cells (i, j) of the positions in rows ``source`` and ``source + 1`` into rows
    ``target`` and ``target + 1``, as whole float32 numbers (module doc); vectorised."""
    scale_i, scale_j, top_i, top_j = level_scales(grid.n_x, grid.n_y, grid)
    for b in range(size):
        scratch[target * BLOCK + b] = level(scratch[source * BLOCK + b], scale_i, top_i)
        scratch[(target + 1) * BLOCK + b] = level(scratch[(source + 1) * BLOCK + b], scale_j, top_j)


@vector_inline_jit
def level_scales(
    levels_x: int, levels_y: int, grid: GridShape
) -> tuple[np.float32, np.float32, np.float32, np.float32]:
    """(n − 1)/W and (m − 1)/H [1/m] of ``levels_x`` n and ``levels_y`` m levels across the
    arena, and the top levels n − 1 and m − 1, float32."""
    return (
        F32((levels_x - 1) / grid.arena_width), F32((levels_y - 1) / grid.arena_height),
        F32(levels_x - 1), F32(levels_y - 1),
    )  # fmt: skip


@vector_inline_jit
def twists(
    scratch: np.ndarray,
    size: int,
    tables: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    present: np.ndarray,
    noise_scale: np.float32,
    grid: GridShape,
) -> None:
    """Each rollout's twist (rows V_X, V_Y, YAW) in the slip region of its pose: the regions
    first, then one vectorised pass per region present in the block, lowest first."""
    scale_i, scale_j, top_i, top_j = level_scales(grid.regions_x, grid.regions_y, grid)
    columns = F32(grid.regions_y)
    for b in range(size):
        i = level(scratch[X * BLOCK + b], scale_i, top_i)
        scratch[REGION * BLOCK + b] = i * columns + level(scratch[Y * BLOCK + b], scale_j, top_j)
    first, same = scratch[REGION * BLOCK], True
    for b in range(size):  # vectorised
        same &= scratch[REGION * BLOCK + b] == first
    if same:  # the usual block: one pass, nothing to choose
        region_twist(scratch, size, tables, int(first), noise_scale, F32(1.0))
        return
    for b in range(size):
        present[int(scratch[REGION * BLOCK + b])] = True
    for row in range(present.shape[0]):
        if present[row]:
            present[row] = False
            region_twist(scratch, size, tables, row, noise_scale, F32(-1.0))


@vector_inline_jit
def region_twist(
    scratch: np.ndarray,
    size: int,
    tables: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    row: int,
    noise_scale: np.float32,
    everyone: np.float32,
) -> None:
    """The twist in slip region ``row`` (rows V_X, V_Y, YAW) of the rollouts in it (of all
    when ``everyone`` is 1, else −1); vectorised."""
    region = F32(row)
    coefficients = (tables[0][row], tables[1][row], tables[2][row], tables[3][row])
    for b in range(size):
        chosen = (scratch[REGION * BLOCK + b] == region) | (everyone > F32(0.0))
        v_x, v_y, yaw_rate = sampled_twist(
            coefficients, (scratch[LEFT * BLOCK + b], scratch[RIGHT * BLOCK + b]),
            (scratch[MODEL * BLOCK + b], scratch[(MODEL + 1) * BLOCK + b],
             scratch[(MODEL + 2) * BLOCK + b], scratch[(MODEL + 3) * BLOCK + b],
             scratch[(MODEL + 4) * BLOCK + b]),
            (scratch[NOISE * BLOCK + b], scratch[(NOISE + 1) * BLOCK + b],
             scratch[(NOISE + 2) * BLOCK + b]),
            noise_scale,
        )  # fmt: skip
        scratch[V_X * BLOCK + b] = choose(chosen, v_x, scratch[V_X * BLOCK + b])
        scratch[V_Y * BLOCK + b] = choose(chosen, v_y, scratch[V_Y * BLOCK + b])
        scratch[YAW * BLOCK + b] = choose(chosen, yaw_rate, scratch[YAW * BLOCK + b])


@vector_inline_jit
def move(scratch: np.ndarray, size: int, robot: KinematicConstants, grid: GridShape) -> None:
    """Each rollout's new pose (rows NEW_X, NEW_Y, NEW_HEADING) after one sub-step of its
    twist from its pose, clipped to the arena, its cell (NEW_I, NEW_J) and whether it is moving
    into another cell (ENTERED); vectorised."""
    dt, exact = F32(robot.dt), robot.exact_integration
    arena = (F32(robot.arena_width), F32(robot.arena_height))
    scale_i, scale_j, top_i, top_j = level_scales(grid.n_x, grid.n_y, grid)
    for b in range(size):
        pose = (scratch[X * BLOCK + b], scratch[Y * BLOCK + b], scratch[HEADING * BLOCK + b])
        twist = (scratch[V_X * BLOCK + b], scratch[V_Y * BLOCK + b], scratch[YAW * BLOCK + b])
        new_x, new_y, new_heading = pose_step(pose, twist, dt, exact, arena)
        scratch[NEW_X * BLOCK + b] = new_x
        scratch[NEW_Y * BLOCK + b] = new_y
        scratch[NEW_HEADING * BLOCK + b] = new_heading
        i, j = level(new_x, scale_i, top_i), level(new_y, scale_j, top_j)
        scratch[NEW_I * BLOCK + b], scratch[NEW_J * BLOCK + b] = i, j
        other = (i != scratch[CELL_I * BLOCK + b]) | (j != scratch[CELL_J * BLOCK + b])
        scratch[ENTERED * BLOCK + b] = scratch[MOVING * BLOCK + b] * F32(other)


@vector_inline_jit
def stops(
    first: int,
    size: int,
    cost_map: CostMap,
    costs: MapCosts,
    robot: KinematicConstants,
    grid: GridShape,
    scratch: np.ndarray,
    poses: np.ndarray,
    out: np.ndarray,
) -> None:
    """The scalar pass of a sub-step, over the moving rollouts that entered another cell (or
    all moving ones, for a robot with a footprint): a footprint's contact costs C and stops the
    rollout (row STOP); entering a cell costs C · p, and a blocked one stops it."""
    if robot.footprint_length > 0.0:
        widened(scratch, size, NEW_X, poses)
        for b in range(size):
            if scratch[MOVING * BLOCK + b] > F32(0.0) and footprint_collides(
                cost_map.blocked, grid, poses[0, b], poses[1, b], poses[2, b],
                robot.footprint_length, robot.footprint_width,
            ):  # fmt: skip
                out[first + b] += costs.collision_cost
                scratch[STOP * BLOCK + b] = F32(1.0)
    for b in range(size):
        if scratch[ENTERED * BLOCK + b] == F32(0.0) or scratch[STOP * BLOCK + b] > F32(0.0):
            continue
        i, j = int(scratch[NEW_I * BLOCK + b]), int(scratch[NEW_J * BLOCK + b])
        out[first + b] += costs.collision_cost * cost_map.wall_probability[i, j]
        if cost_map.blocked[i, j]:
            scratch[STOP * BLOCK + b] = F32(1.0)


@vector_inline_jit
def commit(scratch: np.ndarray, size: int) -> None:
    """Each moving rollout takes its new heading, and unless stopped its new position and
    cell, and a stopped one stops moving for the rest of the control step; vectorised."""
    for b in range(size):
        moving = scratch[MOVING * BLOCK + b]
        keep = moving * (F32(1.0) - scratch[STOP * BLOCK + b])
        for new, old in ((NEW_HEADING, HEADING),):
            scratch[old * BLOCK + b] = choose(
                moving > F32(0.0), scratch[new * BLOCK + b], scratch[old * BLOCK + b]
            )
        for new, old in ((NEW_X, X), (NEW_Y, Y), (NEW_I, CELL_I), (NEW_J, CELL_J)):
            scratch[old * BLOCK + b] = choose(
                keep > F32(0.0), scratch[new * BLOCK + b], scratch[old * BLOCK + b]
            )
        scratch[MOVING * BLOCK + b] = keep
        scratch[STOP * BLOCK + b] = F32(0.0)
