"""The policy family: wheel-speed policies that are not learned step by step.

``cmaes`` searches a tanh policy's parameters by CMA-ES on batches of real episodes
(:class:`~skidnav.agents.policies.search.agent.CMAESAgent`); ``goal-tracker`` is a fixed
proportional controller towards the goal, the reference every wheel-speed learner is compared
with (:class:`~skidnav.agents.policies.agent.GoalTrackerAgent`). Both drive the two wheel speeds
on the feature observation; a saved one runs on the robot as a frozen policy, and loads back as a
frozen agent (a loaded ``cmaes`` acts as the search left it).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from types import ModuleType
from typing import Any

from numpy.random import SeedSequence

from skidnav.agents.family import Env, Family, Params, require_wheel_speed_env, train_own_loop
from skidnav.agents.interface import Agent, AgentConfig, EpisodeTrainingAgent
from skidnav.agents.policies.agent import (
    GOAL_TRACKER_FORMAT,
    GoalTrackerAgent,
    PolicyAgent,
    TanhPolicyAgent,
    load_goal_tracker,
    load_tanh_agent,
)
from skidnav.agents.policies.goal_tracker import POLICY_NAME, GoalTracker, GoalTrackerConfig
from skidnav.agents.policies.search.config import SearchConfig
from skidnav.agents.policies.search.policy_file import SAVE_FORMAT as TANH_FORMAT
from skidnav.agents.training import NO_EVALUATION, Evaluation, TrainingLog, train_plain
from skidnav.agents.wheel_policy import WheelSpeedPolicy
from skidnav.errors import CorruptFileError, UserError, first_line
from skidnav.extras import import_with
from skidnav.seeding import seed_int

SEARCH_MODULE = "skidnav.agents.policies.search.agent"
"""The module of ``cmaes``'s agent, imported when it is asked for (it needs the ``search``
extra)."""
CONFIGS: dict[str, type[Any]] = {"cmaes": SearchConfig, POLICY_NAME: GoalTrackerConfig}
"""Registry name → its config class (a search's settings, a tracker's gains)."""


def _search_module() -> ModuleType:
    """The CMA-ES agent's module; UserError in one line without the ``search`` extra."""
    return import_with("search", "agent 'cmaes'", SEARCH_MODULE)


def _agent_class(name: str) -> type[Any]:
    return _search_module().CMAESAgent if name == "cmaes" else GoalTrackerAgent


def _config_class(name: str) -> type[AgentConfig]:
    return CONFIGS[name]


def _make(name: str, env: Env, params: Params, seed: SeedSequence, max_steps: int) -> Agent:
    require_wheel_speed_env(name, env)
    if name == "cmaes":
        agent: Agent = _search_module().make_cmaes_agent(env, params, seed_int(seed), max_steps)
        return agent
    try:
        config = GoalTrackerConfig.from_mapping(params)
    except (ValueError, TypeError, UserError) as error:
        raise UserError(f"agent {name!r}: {first_line(error)}") from None
    robot: Any = getattr(env.unwrapped, "robot", None)
    return GoalTrackerAgent(GoalTracker(config, robot))


def _train(
    agent: Agent,
    env: Env,
    episodes: int,
    /,
    *,
    max_steps: int | None = None,
    evaluation: Evaluation = NO_EVALUATION,
    seed: int | None = None,
) -> TrainingLog:
    """CMA-ES by generations (:meth:`~skidnav.agents.policies.search.agent.CMAESAgent.
    train_episodes`); a frozen policy's episodes in the plain loop, learning nothing."""
    if isinstance(agent, EpisodeTrainingAgent):  # the search, by generations
        return train_own_loop(
            agent, env, episodes, max_steps=max_steps, evaluation=evaluation, seed=seed
        )
    assert isinstance(agent, PolicyAgent)
    return train_plain(agent, env, episodes, max_steps=max_steps, evaluation=evaluation, seed=seed)


def _load(json_path: Path, meta: Mapping[str, Any], env: Env | None) -> PolicyAgent:
    if meta.get("format") == GOAL_TRACKER_FORMAT:
        return load_goal_tracker(json_path, meta)
    return load_tanh_agent(json_path, meta)


def _policy(json_path: Path, meta: Mapping[str, Any]) -> WheelSpeedPolicy:
    agent = _load(json_path, meta, None)
    if not isinstance(agent, (GoalTrackerAgent, TanhPolicyAgent)):
        raise CorruptFileError(f"{json_path}: not a saved policy")
    return agent.policy


FAMILY: Family[Any] = Family(
    name="policies",
    summary="wheel-speed policies not learned step by step: a tanh policy searched by CMA-ES, "
    "and the goal tracker, a fixed controller towards the goal",
    agents=("cmaes", POLICY_NAME),
    observation="box",
    actions="wheel-speeds",
    agent_class=_agent_class,
    config_class=_config_class,
    make=_make,
    train=_train,
    save_formats=(TANH_FORMAT, GOAL_TRACKER_FORMAT),
    load=_load,
    policy=_policy,
)
"""The policy family (:class:`~skidnav.agents.family.Family`)."""
