"""Every agent by name, whatever it learns over: the one door of the experiment runner.

Three families, each with its own registry:

* **tabular** (:mod:`skidnav.agents.tabular.registry`): a Q table over the env's ``Discrete``
  observation; trained by the compiled trainer
  (:func:`~skidnav.agents.fast_training.train_agent_fast`);
* **linear** (:mod:`skidnav.agents.linear.registry`): tile-coded features of a ``Box``
  observation; trained by the plain loop (:func:`~skidnav.agents.training.train_agent`, to
  which the compiled trainer falls back for them);
* **deep** (:data:`DEEP_AGENTS`, the ``deep`` extra): Stable-Baselines3 owns the loop, and the
  agent trains itself by episodes with the same greedy evaluations
  (:meth:`skidnav.agents.deep.common.DeepAgent.train_episodes`); ``ppo`` and ``sac`` need the
  env's ``action="continuous"`` and ``observation="features"``.

Every family returns the same :class:`~skidnav.agents.training.TrainingLog`, and every agent
answers ``greedy_action(observation)``, so the runner measures them alike.
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Mapping, Sequence
from typing import Any

import gymnasium
import numpy as np
from gymnasium.wrappers import TimeLimit

from skidnav.agents.fast_training import train_agent_fast
from skidnav.agents.linear.registry import (
    CONTINUOUS_AGENT_MODULES,
    linear_agent_class,
    make_linear_agent,
)
from skidnav.agents.tabular.registry import AGENT_MODULES, agent_class, make_agent, make_config
from skidnav.agents.training import TrainingLog
from skidnav.errors import UserError, first_line, shown

DEEP_AGENTS: dict[str, str] = {
    "dqn": "skidnav.agents.deep.dqn",
    "ppo": "skidnav.agents.deep.ppo",
    "sac": "skidnav.agents.deep.sac",
}
"""Registry name → module defining ``AGENT_NAME``, ``AGENT_CLASS`` and ``CONFIG_CLASS``."""


def family(name: str) -> str:
    """``"tabular"``, ``"linear"`` or ``"deep"``; UserError naming the known agents otherwise."""
    if name in AGENT_MODULES:
        return "tabular"
    if name in CONTINUOUS_AGENT_MODULES:
        return "linear"
    if name in DEEP_AGENTS:
        return "deep"
    known = [*AGENT_MODULES, *CONTINUOUS_AGENT_MODULES, *DEEP_AGENTS]
    raise UserError(f"unknown agent {shown(name)}; expected one of {', '.join(known)}")


def _deep_module(name: str) -> Any:
    """The module of deep agent ``name``; UserError when the ``deep`` extra is missing."""
    try:
        return importlib.import_module(DEEP_AGENTS[name])
    except ModuleNotFoundError as error:
        raise UserError(
            f"agent {name!r} needs the deep extra (pip install 'skidnav[deep]'): "
            f"no module {error.name!r}"
        ) from None


def check_params(name: str, params: Mapping[str, Any]) -> None:
    """Validate agent ``name``'s hyperparameters as a new agent would; UserError naming it."""
    kind = family(name)
    if kind == "tabular":
        make_config(name, params)
        return
    try:
        if kind == "linear":
            linear_agent_class(name).config_class.from_mapping(dict(params))
        else:
            _deep_module(name).CONFIG_CLASS.from_mapping(dict(params))
    except (ValueError, TypeError) as error:
        raise UserError(f"agent {name!r}: {first_line(error)}") from None


BOX_OBSERVATIONS = ("pose", "features")
"""The skid-steer env's ``Box`` observations (``observation=``), for the non-tabular agents."""


def observation_for(name: str, requested: str | None) -> str:
    """The skid-steer env's ``observation`` for agent ``name`` when a config asks for
    ``requested`` (its ``[env] observation``, or None): a tabular agent always sees the discrete
    state; the others the requested ``Box`` observation, ``"features"`` by default. UserError
    when a non-tabular agent is asked to learn over the discrete state."""
    if family(name) == "tabular":
        return "discrete"
    if requested is None:
        return "features"
    if requested not in BOX_OBSERVATIONS:
        raise UserError(
            f"agent {name!r} learns over a Box observation: expected [env] observation in "
            f"{', '.join(BOX_OBSERVATIONS)}, got {shown(requested)}"
        )
    return requested


def build_agent(
    name: str,
    env: gymnasium.Env[Any, Any],
    params: Mapping[str, Any],
    seed: np.random.SeedSequence,
    max_steps: int,
) -> Any:
    """A new agent ``name`` for ``env`` (unwrapped) with ``params``, drawing from ``seed``; a deep
    agent drives ``env`` itself, cut at ``max_steps`` actions per episode."""
    kind = family(name)
    space: Any = env.observation_space
    wanted = gymnasium.spaces.Discrete if kind == "tabular" else gymnasium.spaces.Box
    if not isinstance(space, wanted):
        raise UserError(
            f"agent {name!r} learns over a {wanted.__name__} observation, the env gives "
            f"{type(space).__name__} (set [env] observation)"
        )
    rng = np.random.default_rng(seed)
    if kind == "tabular":
        context = agent_context(name, env, params)
        n_actions = int(env.action_space.n)  # type: ignore[attr-defined]
        return make_agent(name, int(space.n), n_actions, dict(params), rng, **context)  # type: ignore[union-attr]
    if kind == "linear":
        context = agent_context(name, env, params)
        n_actions = int(env.action_space.n)  # type: ignore[attr-defined]
        return make_linear_agent(name, space, n_actions, dict(params), rng, **context)  # type: ignore[arg-type]
    module = _deep_module(name)
    config = module.CONFIG_CLASS.from_mapping(dict(params))
    deep_seed = int(seed.generate_state(1)[0])  # 32 bits: Stable-Baselines3 seeds legacy NumPy
    return module.AGENT_CLASS(TimeLimit(env, max_steps), config, seed=deep_seed)


def agent_context(
    name: str, env: gymnasium.Env[Any, Any], params: Mapping[str, Any] | None = None
) -> dict[str, Any]:
    """Extra constructor arguments a tabular or linear agent asks for by name: the navigation
    ``task``, and for one whose ``params`` ask for ``kinematic_model = "true"`` the env's
    ``true_kinematics`` (None on an env without them: the agent refuses in one line). No other
    agent is handed the truth."""
    cls = linear_agent_class(name) if family(name) == "linear" else agent_class(name)
    parameters = inspect.signature(cls.__init__).parameters
    context = {"task": env.task} if "task" in parameters and hasattr(env, "task") else {}
    if "true_kinematics" in parameters and (params or {}).get("kinematic_model") == "true":
        context["true_kinematics"] = getattr(env.unwrapped, "true_kinematics", None)
    return context


def train(
    agent: Any,
    env: gymnasium.Env[Any, Any],
    episodes: int,
    *,
    max_steps: int,
    greedy_eval_env: gymnasium.Env[Any, Any] | None,
    greedy_seeds: Sequence[int] | None,
) -> TrainingLog:
    """Train ``agent`` (from :func:`build_agent` on ``env``) for ``episodes`` episodes with a
    greedy evaluation after each, as its family trains."""
    if hasattr(agent, "train_episodes"):  # a deep agent: its own loop, on its own env
        log: TrainingLog = agent.train_episodes(
            episodes, greedy_eval_env=greedy_eval_env, greedy_seeds=greedy_seeds,
            greedy_max_steps=max_steps,
        )  # fmt: skip
        return log
    return train_agent_fast(
        agent, env, episodes, max_steps=max_steps, greedy_eval_env=greedy_eval_env,
        greedy_seeds=greedy_seeds,
    )  # fmt: skip
