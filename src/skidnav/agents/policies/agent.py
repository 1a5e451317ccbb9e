"""A wheel-speed policy as an agent: it acts, and learns nothing.

:class:`PolicyAgent` answers the agent contract for a frozen
:class:`~skidnav.agents.wheel_policy.WheelSpeedPolicy`: ``greedy_action`` and ``act`` are the
policy's wheel speeds, ``observe`` and ``end_episode`` change nothing. The goal tracker
(:class:`GoalTrackerAgent`) is one, and so is a policy found by CMA-ES once loaded from its file
(:class:`TanhPolicyAgent`): the search itself is :class:`~skidnav.agents.policies.search.agent.
CMAESAgent`.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import asdict
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from skidnav.agents.geometry import geometry_from_json, geometry_json
from skidnav.agents.policies.goal_tracker import POLICY_NAME, GoalTracker, GoalTrackerConfig
from skidnav.agents.policies.search.policy_file import policy_from_file, save_policy
from skidnav.agents.policies.search.tanh_policy import TanhPolicy
from skidnav.agents.saving import new_save_paths
from skidnav.agents.wheel_policy import WheelSpeedPolicy
from skidnav.errors import CorruptFileError, UserError, first_line, shown
from skidnav.files.atomic import write_atomic, write_npz_atomic

GOAL_TRACKER_FORMAT = "skidnav-goal-tracker"
"""The ``"format"`` of a saved goal tracker's ``.json``."""
GOAL_TRACKER_VERSION = 1


class PolicyAgent:
    """A frozen wheel-speed policy with the agent contract (module doc).

    Args:
        policy: the policy; its ``wheel_speeds(observation)`` gives (ω_L, ω_R) [rad/s].
    """

    name: ClassVar[str] = "policy"
    planning_updates: int = 0
    """It plans nothing."""

    def __init__(self, policy: WheelSpeedPolicy) -> None:
        self.policy = policy

    def greedy_action(self, state: Any) -> np.ndarray:
        """The policy's wheel speeds at the observation ``state``, float64 (2,) [rad/s]."""
        return np.array(self.policy.wheel_speeds(np.asarray(state, dtype=np.float64)))

    def act(self, state: Any) -> np.ndarray:
        """The same as :meth:`greedy_action`: a frozen policy does not explore."""
        return self.greedy_action(state)

    def observe(self, *transition: Any) -> None:
        """Nothing: a frozen policy learns nothing."""

    def end_episode(self) -> None:
        """Nothing."""

    def save(self, path: str | Path) -> tuple[Path, Path]:
        """Write ``path.npz`` and ``path.json``; both paths."""
        raise NotImplementedError


class GoalTrackerAgent(PolicyAgent):
    """The goal tracker (:class:`~skidnav.agents.policies.goal_tracker.GoalTracker`) as an agent,
    on the robot it was made for."""

    name: ClassVar[str] = POLICY_NAME
    config_class = GoalTrackerConfig

    def __init__(self, tracker: GoalTracker) -> None:
        super().__init__(tracker)
        self.tracker = tracker
        self.config = tracker.config

    def save(self, path: str | Path) -> tuple[Path, Path]:
        """Write ``path.json`` (its gains and robot) and an empty ``path.npz``; both paths."""
        npz_path, json_path = new_save_paths(path)
        meta = {
            "format": GOAL_TRACKER_FORMAT,
            "version": GOAL_TRACKER_VERSION,
            "agent": self.name,
            "config": asdict(self.config),
            "geometry": geometry_json(self.tracker.robot, None),
        }
        write_npz_atomic(npz_path, {})
        write_atomic(json_path, json.dumps(meta, indent=1).encode("utf-8"))
        return npz_path, json_path


def load_goal_tracker(json_path: Path, meta: Mapping[str, Any]) -> GoalTrackerAgent:
    """The goal tracker saved at ``json_path`` (``meta``: its parsed content); CorruptFileError
    in one line naming the file when it is not one."""
    if meta.get("format") != GOAL_TRACKER_FORMAT or meta.get("version") != GOAL_TRACKER_VERSION:
        raise CorruptFileError(
            f"{json_path}: not a goal tracker of version {GOAL_TRACKER_VERSION} (format "
            f"{shown(meta.get('format'))}, version {shown(meta.get('version'))})"
        )
    try:
        config = GoalTrackerConfig.from_mapping(meta.get("config") or {})
        robot, _ = geometry_from_json(meta.get("geometry"))
    except (ValueError, UserError) as error:
        raise CorruptFileError(
            f"{json_path}: cannot load goal tracker: {first_line(error)}"
        ) from None
    return GoalTrackerAgent(GoalTracker(config, robot))


class TanhPolicyAgent(PolicyAgent):
    """A policy found by CMA-ES, loaded from its file: it acts as the search left it."""

    name: ClassVar[str] = "cmaes"

    def __init__(self, policy: TanhPolicy, provenance: Mapping[str, Any] | None = None) -> None:
        super().__init__(policy)
        self.tanh_policy = policy
        self.provenance = dict(provenance or {})

    def save(self, path: str | Path) -> tuple[Path, Path]:
        """Write the policy's file again (:func:`~skidnav.agents.policies.search.policy_file.
        save_policy`); both paths."""
        return save_policy(self.tanh_policy, path, self.provenance)


def load_tanh_agent(json_path: Path, meta: Mapping[str, Any]) -> TanhPolicyAgent:
    """The CMA-ES policy saved at ``json_path`` as a frozen agent; CorruptFileError as
    :func:`~skidnav.agents.policies.search.policy_file.policy_from_file`."""
    provenance = meta.get("provenance")
    return TanhPolicyAgent(
        policy_from_file(json_path, meta), provenance if isinstance(provenance, Mapping) else None
    )
