"""The deep family: Stable-Baselines3's DQN, PPO and SAC (the ``deep`` extra).

Stable-Baselines3 owns the loop: an agent trains itself by episodes on the env it was built with
(:meth:`~skidnav.agents.deep.common.DeepAgent.train_episodes`) with the same greedy evaluations
and log as every family. ``ppo`` and ``sac`` drive wheel speeds (the env's
``action="continuous"``); their saved files also run as frozen policies on the robot, as do a
saved ``dqn``'s, by the wheel speeds of its greedy actions. Nothing
here imports PyTorch: an agent's module is imported when it is asked for, after the ``deep``
extra is checked.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from types import ModuleType
from typing import Any

import gymnasium
from gymnasium.wrappers import TimeLimit
from numpy.random import SeedSequence

from skidnav.agents.family import (
    Env,
    Family,
    Params,
    action_space,
    observation_space,
    train_own_loop,
)
from skidnav.agents.interface import AgentConfig, EpisodeTrainingAgent
from skidnav.agents.wheel_policy import WheelSpeedPolicy
from skidnav.errors import CorruptFileError, UserError
from skidnav.extras import MissingExtraError, import_with, missing_message

DEEP_AGENTS: dict[str, str] = {
    "dqn": "skidnav.agents.deep.dqn",
    "ppo": "skidnav.agents.deep.ppo",
    "sac": "skidnav.agents.deep.sac",
}
"""Registry name → module defining ``AGENT_NAME``, ``AGENT_CLASS``, ``CONFIG_CLASS`` and
``policy_from_file`` (a saved agent as a frozen wheel-speed policy)."""
FORMATS = {f"skidnav-{name}": name for name in DEEP_AGENTS}
"""The ``format`` of a saved deep agent's ``.json`` → its registry name."""


def _module(name: str) -> ModuleType:
    """The module of agent ``name``; UserError when the ``deep`` extra is missing (checked
    before anything is imported, so a config naming the agent is refused up front)."""
    return import_with("deep", f"agent {name!r}", DEEP_AGENTS[name])


def _agent_class(name: str) -> type[EpisodeTrainingAgent]:
    cls: type[EpisodeTrainingAgent] = _module(name).AGENT_CLASS
    return cls


def _config_class(name: str) -> type[AgentConfig]:
    cls: type[AgentConfig] = _module(name).CONFIG_CLASS
    return cls


def _make(
    name: str, env: Env, params: Params, seed: SeedSequence, max_steps: int
) -> EpisodeTrainingAgent:
    observation_space(name, env, gymnasium.spaces.Box)
    module = _module(name)
    action_space(name, env, module.AGENT_CLASS.action_space_class)
    try:
        config = module.CONFIG_CLASS.from_mapping(dict(params))
    except (ValueError, TypeError) as error:
        raise UserError(f"agent {name!r}: {error}") from None
    deep_seed = int(seed.generate_state(1)[0])  # 32 bits: Stable-Baselines3 seeds legacy NumPy
    try:  # PyTorch and Stable-Baselines3 are imported by the agent's constructor
        agent: EpisodeTrainingAgent = module.AGENT_CLASS(
            TimeLimit(env, max_steps), config, seed=deep_seed
        )
    except ModuleNotFoundError as error:
        raise MissingExtraError(
            missing_message("deep", f"agent {name!r}", str(error.name))
        ) from None
    return agent


def _saved_name(json_path: Path, meta: Mapping[str, Any]) -> str:
    name = FORMATS.get(str(meta.get("format")))
    if name is None:  # the door hands a family only its own formats
        raise CorruptFileError(f"{json_path}: not a saved deep agent")
    return name


def _load(json_path: Path, meta: Mapping[str, Any], env: Env | None) -> EpisodeTrainingAgent:
    """A saved deep agent on ``env`` (its networks are built on the env's spaces)."""
    name = _saved_name(json_path, meta)
    if env is None:
        raise UserError(f"{json_path}: a saved {name} agent loads onto its env (pass env)")
    from skidnav.agents.deep.common import load_agent

    return load_agent(_agent_class(name), json_path, env)  # type: ignore[type-var]


def _policy(json_path: Path, meta: Mapping[str, Any]) -> WheelSpeedPolicy:
    """The frozen wheel-speed policy of a saved deep agent: that of a ``ppo`` or ``sac``, or a
    ``dqn`` driving by the wheel speeds of its greedy actions."""
    name = _saved_name(json_path, meta)
    policy: WheelSpeedPolicy = _module(name).policy_from_file(json_path, dict(meta))
    return policy


FAMILY: Family[EpisodeTrainingAgent] = Family(
    name="deep",
    summary="neural networks trained by Stable-Baselines3 (DQN on discrete actions, PPO and SAC "
    "on wheel speeds)",
    agents=tuple(DEEP_AGENTS),
    observation="box",
    actions="discrete",
    agent_class=_agent_class,
    config_class=_config_class,
    make=_make,
    train=train_own_loop,
    save_formats=tuple(FORMATS),
    load=_load,
    policy=_policy,
    extra="deep",
)
"""The deep family (:class:`~skidnav.agents.family.Family`). Its ``actions`` are those of
``dqn``; ``ppo`` and ``sac`` drive wheel speeds."""
