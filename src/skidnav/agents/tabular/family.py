"""The tabular family: a Q table over the env's ``Discrete`` state, learned step by step.

Q-learning, the Dyna agents with the multinomial model (Dyna-Q, Dyna-Q+, prioritized sweeping)
and the model-based agents with the kinematic model (``dyna-kinematic`` … ``dyna-sweep``),
trained by the compiled trainer (:func:`~skidnav.agents.tabular.fast_training.train_agent_fast`,
which
runs the plain loop itself for envs it cannot drive). On the robot they keep learning online
(``skidnav robot run --agent``).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
from numpy.random import SeedSequence

from skidnav.agents.family import (
    Env,
    Family,
    Params,
    constructor_context,
    discrete_actions,
    observation_space,
)
from skidnav.agents.interface import AgentConfig
from skidnav.agents.tabular.agent import SAVE_FORMAT, TabularAgent
from skidnav.agents.tabular.fast_training import train_agent_fast
from skidnav.agents.tabular.registry import AGENT_MODULES, agent_class, load_agent, make_agent


def _config_class(name: str) -> type[AgentConfig]:
    return agent_class(name).config_class


def _make(name: str, env: Env, params: Params, seed: SeedSequence, max_steps: int) -> TabularAgent:
    space = observation_space(name, env, gymnasium.spaces.Discrete)
    context = constructor_context(agent_class(name), env, params)
    rng = np.random.default_rng(seed)
    return make_agent(name, int(space.n), discrete_actions(name, env), dict(params), rng, **context)


def _load(json_path: Path, meta: Mapping[str, Any], env: Env | None) -> TabularAgent:
    """A saved tabular agent; one that plans on the navigation task takes ``env``'s task."""
    name = meta.get("agent")
    context: dict[str, Any] = {}
    if env is not None and isinstance(name, str) and name in AGENT_MODULES:
        context = constructor_context(agent_class(name), env.unwrapped)
    return load_agent(json_path, **context)


FAMILY: Family[TabularAgent] = Family(
    name="tabular",
    summary="a Q table over the discretized pose, learned step by step; the model-based agents "
    "plan with the multinomial and the kinematic model",
    agents=tuple(AGENT_MODULES),
    observation="discrete",
    actions="discrete",
    agent_class=agent_class,
    config_class=_config_class,
    make=_make,
    train=train_agent_fast,
    save_formats=(SAVE_FORMAT,),
    load=_load,
)
"""The tabular family (:class:`~skidnav.agents.family.Family`)."""
