"""``classical``: the navigator as an agent, which learns nothing (docs/agents/classical.md).

What it reads is the observation (the features: pose, goal distance and bearing, lidar
ranges) and, once, when it is made for an env (:meth:`ClassicalAgent.from_env`), the
datasheet robot (``env.unwrapped.robot``: r, c, Ω, x_ICR, the arena, the footprint), the cells
of its map (``env.unwrapped.discretization``: the arena cut as the simulator cuts it, so that
its footprint rule is the simulator's) and the lidar's layout (``env.unwrapped.features``: rays,
range, field of view). Never the walls, the goal's cell, the floor or the task.

:meth:`ClassicalAgent.act` and :meth:`ClassicalAgent.greedy_action` are the same navigator
(:class:`~skidnav.agents.classical.navigator.ClassicalNavigator`), each with a map of its own:
the training episodes' map is forgotten at every episode's end (:meth:`ClassicalAgent.
end_episode`), the greedy rollouts' at every rollout's start (:meth:`ClassicalAgent.
start_greedy_rollout`). So every episode is zero-shot, as the BARN benchmark scores it, and
training changes nothing. Saved, it is its settings, robot, cells and laser layout (a
``.json`` and an empty ``.npz``); loaded, the same navigator.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from skidnav.agents.classical.config import ClassicalConfig
from skidnav.agents.classical.navigator import ClassicalNavigator, Laser
from skidnav.agents.geometry import geometry_from_json, geometry_json
from skidnav.agents.saving import new_save_paths
from skidnav.errors import CorruptFileError, UserError, first_line, shown
from skidnav.files.atomic import write_atomic, write_npz_atomic
from skidnav.robot.params import RobotParams
from skidnav.sim.features import check_lidar
from skidnav.world.discretization import Discretization

AGENT_NAME = "classical"
SAVE_FORMAT = "skidnav-classical"
"""The ``"format"`` of a saved navigator's ``.json``."""
SAVE_VERSION = 1


class ClassicalAgent:
    """The classical navigator (global Dijkstra route on an inflated laser map, local DWA), as
    an agent that learns nothing (module doc).

    Args:
        config: its settings. robot: the datasheet robot. grid: the cells of its map.
        laser: the layout of the observations' lidar readings.
    """

    name: ClassVar[str] = AGENT_NAME
    config_class = ClassicalConfig

    def __init__(
        self, config: ClassicalConfig, robot: RobotParams, grid: Discretization, laser: Laser
    ) -> None:
        self.config, self.robot, self.discretization, self.laser = config, robot, grid, laser
        self.navigator = ClassicalNavigator(config, robot, grid, laser)
        """The training episodes' navigator."""
        self.greedy = ClassicalNavigator(config, robot, grid, laser)
        """The greedy rollouts' navigator."""
        self.replans = 0
        """Routes planned in training episodes so far."""

    @classmethod
    def from_env(cls, env: Any, config: ClassicalConfig | None = None) -> ClassicalAgent:
        """The navigator for the navigation env ``env`` (wrapped or not): its robot, cells and
        lidar layout (module doc); nothing of its walls, goal cell or floor."""
        nav = env.unwrapped
        return cls(config or ClassicalConfig(), nav.robot, nav.discretization, laser_of(nav))

    @property
    def planning_updates(self) -> int:
        """Routes planned in the training episodes (the family's planning work)."""
        return self.replans + self.navigator.replans

    def act(self, observation: Any) -> np.ndarray:
        """The wheel speeds (ω_L, ω_R) [rad/s], float64 (2,), for a feature observation of the
        current training episode."""
        return np.array(self.navigator.wheel_speeds(observation))

    def greedy_action(self, observation: Any) -> np.ndarray:
        """The same navigator's wheel speeds on the greedy rollout's own map."""
        return np.array(self.greedy.wheel_speeds(observation))

    def observe(self, *transition: Any) -> None:
        """Nothing: the map is built from the observations as the navigator acts on them."""

    def end_episode(self) -> None:
        """Forget the episode's map."""
        self.replans += self.navigator.replans
        self.navigator.reset()

    def start_greedy_rollout(self) -> None:
        """Forget the previous rollout's map (:class:`~skidnav.agents.greedy.RolloutState`)."""
        self.greedy.reset()

    def policy(self) -> ClassicalNavigator:
        """A navigator of its own, a :class:`~skidnav.agents.wheel_policy.WheelSpeedPolicy`."""
        return ClassicalNavigator(self.config, self.robot, self.discretization, self.laser)

    def save(self, path: str | Path) -> tuple[Path, Path]:
        """Write ``path.json`` (settings, robot, cells, laser) and an empty ``path.npz``."""
        npz_path, json_path = new_save_paths(path)
        meta = {
            "format": SAVE_FORMAT,
            "version": SAVE_VERSION,
            "agent": self.name,
            "config": self.config.to_dict(),
            "geometry": geometry_json(self.robot, self.discretization),
            "laser": self.laser._asdict(),
        }
        write_npz_atomic(npz_path, {})
        write_atomic(json_path, json.dumps(meta, indent=1).encode("utf-8"))
        return npz_path, json_path


def laser_of(nav: Any) -> Laser:
    """The lidar layout of the navigation env ``nav`` (unwrapped): its features' rays, range
    and field of view."""
    features = nav.features
    return Laser(
        int(features.lidar_rays), float(features.lidar_range), float(features.field_of_view)
    )


def make_classical_agent(env: Any, params: Mapping[str, Any]) -> ClassicalAgent:
    """:meth:`ClassicalAgent.from_env` with the settings ``params`` (an ``[[agents]]`` table's);
    UserError in one line naming the agent for a bad setting or an env it cannot read."""
    try:
        config = ClassicalConfig.from_mapping(params)
        return ClassicalAgent.from_env(env, config)
    except (ValueError, TypeError, UserError) as error:
        raise UserError(f"agent {AGENT_NAME!r}: {first_line(error)}") from None


def load_classical_agent(json_path: Path, meta: Mapping[str, Any]) -> ClassicalAgent:
    """The navigator saved at ``json_path`` (``meta``: its parsed content); CorruptFileError
    in one line naming the file when it is not one."""
    if meta.get("format") != SAVE_FORMAT or meta.get("version") != SAVE_VERSION:
        raise CorruptFileError(
            f"{json_path}: not a classical navigator of version {SAVE_VERSION} (format "
            f"{shown(meta.get('format'))}, version {shown(meta.get('version'))})"
        )
    try:
        config = ClassicalConfig.from_mapping(meta.get("config") or {})
        robot, grid = geometry_from_json(meta.get("geometry"))
        laser = _laser_from_json(meta.get("laser"))
        if grid is None:
            raise ValueError("expected the navigator's discretization")
        return ClassicalAgent(config, robot, grid, laser)
    except (ValueError, TypeError, UserError) as error:
        raise CorruptFileError(
            f"{json_path}: cannot load the classical navigator: {first_line(error)}"
        ) from None


def _laser_from_json(value: Any) -> Laser:
    """The :class:`Laser` of a saved navigator; ValueError unless exactly its three fields."""
    if not isinstance(value, Mapping) or set(value) != set(Laser._fields):
        raise ValueError(f"expected a laser with {', '.join(Laser._fields)}")
    rays, max_range, fov = value["rays"], value["range"], value["field_of_view"]
    check_lidar(rays, max_range)
    if isinstance(fov, bool) or not isinstance(fov, int | float) or not 0 < fov <= 2 * math.pi:
        raise ValueError(f"expected a field of view in (0, 2π] rad, got {shown(fov)}")
    return Laser(rays, float(max_range), float(fov))
