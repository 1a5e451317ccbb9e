"""The ``observation="features"`` vector of ``SkidSteerNav-v0``: pose, goal and lidar ranges.

Unlike the flat discrete state, these features carry over between cells, maps and goals: a
function of them can generalise. Layout (float64, shape (7 + k,), k = ``lidar_rays``):

===== ====================== ======= ==========================================================
index name                   unit    bounds
===== ====================== ======= ==========================================================
0     ``x``                  m       [0, W]
1     ``y``                  m       [0, H]
2     ``cos_heading``        —       [−1, 1]: cos ψ
3     ``sin_heading``        —       [−1, 1]: sin ψ
4     ``goal_distance``      m       [0, √(W² + H²)]: to the goal (the goal cell's centre, or
                                             the map's goal point)
5     ``goal_cos_bearing``   —       [−1, 1]: cos β, β the goal direction minus the heading
6     ``goal_sin_bearing``   —       [−1, 1]: sin β (> 0: the goal lies to the left)
7 + r ``range_r``            m       [0, lidar_range]: lidar ray r, along ψ + 2π·r / k (a
                                             narrower field of view: see :class:`PoseFeatures`)
===== ====================== ======= ==========================================================

The bearing is taken as (cos β, sin β) = (1, 0) when the robot stands on the goal.
The ranges come from :func:`skidnav.sim.lidar.lidar_scan` (walls and the arena border).

>>> from skidnav.world.discretization import Discretization
>>> from skidnav.world.maps import build_map
>>> import numpy as np
>>> grid_map = build_map(np.random.default_rng(0), kind="free", shape=(25, 25))
>>> features = PoseFeatures(grid_map, Discretization(), lidar_rays=4, lidar_range=0.3)
>>> features.space().shape, features.names()[-1]
((11,), 'range_3')
"""

from __future__ import annotations

import math

import numpy as np
from gymnasium import spaces

from skidnav._jit import inline_jit, jit
from skidnav.checks import check_integer
from skidnav.sim.lidar import FULL_TURN, LaserSpec, lidar_scan
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap

POSE_GOAL_NAMES = (
    "x",
    "y",
    "cos_heading",
    "sin_heading",
    "goal_distance",
    "goal_cos_bearing",
    "goal_sin_bearing",
)
"""Names of the features before the lidar ranges, in order."""
MAX_LIDAR_RAYS = 1024
"""Most lidar rays an observation carries (the env's default is 8): the one cap, of the env, the
policy search and its policy files."""


def check_lidar(lidar_rays: int, lidar_range: float) -> None:
    """ValueError unless ``lidar_rays`` is an integer in [0, :data:`MAX_LIDAR_RAYS`] and
    ``lidar_range`` [m] is finite and > 0."""
    check_integer("lidar_rays", lidar_rays, 0, MAX_LIDAR_RAYS)
    if (
        isinstance(lidar_range, bool)
        or not isinstance(lidar_range, int | float)
        or not (math.isfinite(lidar_range) and lidar_range > 0)
    ):
        raise ValueError(f"expected lidar_range to be a finite number > 0 m, got {lidar_range!r}")


@inline_jit
def length(dx: float, dy: float) -> float:
    """√(dx² + dy²) [m] of a vector (dx, dy) [m]; of (W, H), the greatest goal distance. (A square
    root, not ``math.hypot``, whose CPython and compiled versions may differ in the last bit.)"""
    return math.sqrt(dx * dx + dy * dy)


@inline_jit
def goal_features(
    x: float, y: float, heading: float, goal_x: float, goal_y: float
) -> tuple[float, float, float]:
    """(distance [m], cos β, sin β) of the point (``goal_x``, ``goal_y``) [m] seen from the pose
    (x [m], y [m], heading [rad]); β is the goal direction minus the heading, (1, 0) at zero
    distance.

    >>> [round(v, 12) for v in goal_features(0.0, 0.0, math.pi / 2, 0.3, 0.4)]
    [0.5, 0.8, -0.6]
    """
    dx, dy = goal_x - x, goal_y - y
    distance = length(dx, dy)
    if distance == 0.0:
        return 0.0, 1.0, 0.0
    cos_heading, sin_heading = math.cos(heading), math.sin(heading)
    cos_bearing = (cos_heading * dx + sin_heading * dy) / distance
    sin_bearing = (cos_heading * dy - sin_heading * dx) / distance
    return distance, _unit_clip(cos_bearing), _unit_clip(sin_bearing)


@inline_jit
def _unit_clip(value: float) -> float:
    """``value`` clipped to [−1, 1] (a ratio that rounding may push a last bit past 1)."""
    return min(max(value, -1.0), 1.0)


@jit
def fill_features(
    occupancy: np.ndarray,
    arena: tuple[float, float],
    goal: tuple[float, float],
    pose: np.ndarray,
    max_range: float,
    out: np.ndarray,
    field_of_view: float = FULL_TURN,
) -> None:
    """Write the features (module doc) of ``pose`` float64 (3,) (x [m], y [m], heading [rad])
    into ``out`` float64 (7 + k,): walls ``occupancy`` uint8 (n_x, n_y), ``arena`` (W, H) [m],
    the goal ``goal`` (x, y) [m], k = len(out) − 7 rays of at most ``max_range`` [m] over
    ``field_of_view`` [rad] (:func:`skidnav.sim.lidar.lidar_scan`). Compiled, so that compiled
    loops can observe too."""
    x, y, heading = pose[0], pose[1], pose[2]
    distance, cos_bearing, sin_bearing = goal_features(x, y, heading, goal[0], goal[1])
    out[0], out[1] = x, y
    out[2], out[3] = math.cos(heading), math.sin(heading)
    out[4] = min(distance, length(arena[0], arena[1]))  # ≤ the diagonal but for rounding
    out[5], out[6] = cos_bearing, sin_bearing
    lidar_scan(occupancy, arena[0], arena[1], x, y, heading, max_range, field_of_view, out[7:])


def feature_bounds(
    arena: tuple[float, float], lidar_rays: int, lidar_range: float
) -> tuple[np.ndarray, np.ndarray]:
    """(low, high), float64 (7 + k,) each: the bounds of the feature observation (module doc) in
    an ``arena`` (W, H) [m] with k = ``lidar_rays`` readings of at most ``lidar_range`` [m].

    >>> [float(v) for v in feature_bounds((3.0, 4.0), 1, 0.3)[1]]
    [3.0, 4.0, 1.0, 1.0, 5.0, 1.0, 1.0, 0.3]
    """
    width, height = arena
    low = [0.0, 0.0, -1.0, -1.0, 0.0, -1.0, -1.0] + [0.0] * lidar_rays
    high = [width, height, 1.0, 1.0, length(width, height), 1.0, 1.0]
    high += [lidar_range] * lidar_rays
    return np.array(low, dtype=np.float64), np.array(high, dtype=np.float64)


class PoseFeatures:
    """The feature observation of one arena (its walls, goal and size), see the module doc.

    Args:
        grid_map: the walls and the goal cell. discretization: the cells and the arena extent.
        lidar_rays: k ≥ 0 rays (0: no range readings). lidar_range: the largest reading [m] > 0.
        field_of_view: the sector the rays sweep [rad], in (0, 2π] (2π, the default: a full
            turn, ray 0 ahead and the others counter-clockwise; narrower: ray 0 at the
            clockwise edge, both edges included, :class:`skidnav.sim.lidar.LaserSpec`).
        goal: the goal point (x, y) [m] the goal features measure to; None: the goal cell's
            centre.
    """

    def __init__(
        self,
        grid_map: GridMap,
        discretization: Discretization,
        lidar_rays: int = 8,
        lidar_range: float = 0.3,
        field_of_view: float = FULL_TURN,
        goal: tuple[float, float] | None = None,
    ) -> None:
        check_lidar(lidar_rays, lidar_range)
        LaserSpec(max(lidar_rays, 1), float(lidar_range), field_of_view)  # checks the sector
        self.lidar_rays, self.lidar_range = lidar_rays, float(lidar_range)
        self.field_of_view = float(field_of_view)
        self.arena = (float(discretization.arena_width), float(discretization.arena_height))
        self.goal = goal if goal is not None else discretization.cell_centre(*grid_map.goal)
        self.occupancy = np.ascontiguousarray(grid_map.as_uint8())

    def names(self) -> tuple[str, ...]:
        """The features' names in order (:data:`POSE_GOAL_NAMES`, then ``range_0`` …)."""
        return POSE_GOAL_NAMES + tuple(f"range_{r}" for r in range(self.lidar_rays))

    def steering_dimensions(self) -> tuple[int, ...]:
        """The features a tile coder takes when its config names none: the goal's distance and
        bearing (4, 5, 6) and the front ray, with at least 3 rays the front-left and front-right
        ones too (7, 8, 7 + k − 1). Tiling all 7 + k features jointly needs (tiles + 1)^(7 + k)
        tiles per tiling, beyond any memory for the default 8 rays.

        >>> from skidnav.world.maps import build_map
        >>> grid_map = build_map(np.random.default_rng(0), kind="free", shape=(25, 25))
        >>> PoseFeatures(grid_map, Discretization()).steering_dimensions()
        (4, 5, 6, 7, 8, 14)
        >>> PoseFeatures(grid_map, Discretization(), lidar_rays=0).steering_dimensions()
        (4, 5, 6)
        """
        rays = self.lidar_rays
        sides = (8, 7 + rays - 1) if rays >= 3 else ()
        return (4, 5, 6, *((7,) if rays else ()), *sides)

    def space(self) -> spaces.Box:
        """The ``Box`` float64 (7 + k,) of the observations, with the bounds of the module doc."""
        low, high = feature_bounds(self.arena, self.lidar_rays, self.lidar_range)
        return spaces.Box(low=low, high=high, dtype=np.float64)

    def __call__(self, pose: np.ndarray) -> np.ndarray:
        """The observation, float64 (7 + k,), of ``pose`` (x [m], y [m], heading [rad]) in the
        arena."""
        observation = np.empty(7 + self.lidar_rays)
        fill_features(
            self.occupancy, self.arena, self.goal, pose, self.lidar_range, observation,
            self.field_of_view,
        )  # fmt: skip
        return observation
