"""Compiled breadth-first search for the fewest actions from one exact pose to the goal cell,
under the simulator with no slip noise (the calibration of the convergence test,
:mod:`skidnav.experiments.reference.start_plan`).

Every pose reached after d actions is expanded by the four actions (the one MDP step,
:func:`skidnav.sim.navigation.transition`, noise draws all 0: no wheel-speed loss), level by
level, so the first level that ends an action in the goal cell is the fewest actions of any
action sequence from that pose. Poses closer than ``resolution`` [m] in x and y and within one
of ``n_heading_bins`` heading bins count as one (the first reached is kept), which bounds the
search to the arena's poses at that resolution; a finer resolution merges less.
"""

from __future__ import annotations

import math

import numpy as np

from skidnav._jit import jit
from skidnav.sim.navigation import NavigationTask, transition


@jit
def _pose_key(pose: np.ndarray, resolution: float, n_x: int, n_y: int, n_headings: int) -> int:
    """Flat index of the pose's bin: x and y in ``resolution`` steps, heading in n_headings."""
    i = min(max(int(pose[0] / resolution), 0), n_x - 1)
    j = min(max(int(pose[1] / resolution), 0), n_y - 1)
    turn = (pose[2] + math.pi) / (2.0 * math.pi)
    h = int((turn - math.floor(turn)) * n_headings) % n_headings
    return (i * n_y + j) * n_headings + h


@jit
def shortest_plan(
    task: NavigationTask,
    start: np.ndarray,
    max_actions: int,
    resolution: float,
    n_heading_bins: int,
    max_nodes: int,
) -> np.ndarray:
    """The fewest-actions action sequence from ``start`` (x [m], y [m], heading [rad]) to the
    goal cell without slip noise (module docs), int64 (length,); empty when the goal is not
    reached within ``max_actions`` actions or more than ``max_nodes`` poses were expanded."""
    n_x = int(task.grid.arena_width / resolution) + 1
    n_y = int(task.grid.arena_height / resolution) + 1
    seen = np.zeros(n_x * n_y * n_heading_bins, dtype=np.bool_)
    poses = np.empty((max_nodes, 3))
    parent = np.empty(max_nodes, dtype=np.int64)
    taken = np.empty(max_nodes, dtype=np.int64)
    noise = np.zeros(2 * task.robot.substeps)
    log = np.empty((task.robot.substeps, 6))
    pose = np.empty(3)
    poses[0] = start
    parent[0], taken[0] = -1, -1
    seen[_pose_key(start, resolution, n_x, n_y, n_heading_bins)] = True
    first, end = 0, 1
    for _ in range(max_actions):
        level_end = end
        for node in range(first, level_end):
            for action in range(4):
                pose[:] = poses[node]
                outcome = transition(task, pose, action, 0.0, noise, log)
                if outcome.terminated:
                    return _plan(parent, taken, node, action)
                key = _pose_key(pose, resolution, n_x, n_y, n_heading_bins)
                if seen[key]:
                    continue
                if end == max_nodes:
                    return np.zeros(0, dtype=np.int64)
                seen[key] = True
                poses[end] = pose
                parent[end], taken[end] = node, action
                end += 1
        first = level_end
        if first == end:
            break
    return np.zeros(0, dtype=np.int64)


@jit
def _plan(parent: np.ndarray, taken: np.ndarray, node: int, last: int) -> np.ndarray:
    """The actions from the root to ``node``, then ``last``."""
    length = 1
    walk = node
    while parent[walk] >= 0:
        length += 1
        walk = parent[walk]
    actions = np.empty(length, dtype=np.int64)
    actions[length - 1] = last
    walk, k = node, length - 2
    while parent[walk] >= 0:
        actions[k] = taken[walk]
        walk, k = parent[walk], k - 1
    return actions
