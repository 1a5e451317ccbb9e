"""What an agent family is, written once: :class:`Family`, the descriptor every door reads.

A family is a package under :mod:`skidnav.agents` (``tabular/``, ``linear/``, ``deep/``,
``mpc/``, ``policies/``) whose ``family.py`` defines ``FAMILY``, a :class:`Family`: the names of
its agents and their classes and configs, what they observe, how one is made for an env and
trained, the ``format`` of its saved files, how a saved file is loaded back as an agent, and how
one becomes a wheel-speed policy on the robot. The catalog (:mod:`skidnav.agents.catalog`), the
saved-file door (:mod:`skidnav.agents.saved`), the real-time run and the studies read
:data:`skidnav.agents.catalog.FAMILY_MODULES` and nothing else: adding a family is one package
and one line there.

The helpers below (:func:`observation_space`, :func:`discrete_actions`,
:func:`constructor_context`) are what several families' ``make`` share.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Generic, Literal, Protocol, TypeAlias, TypeVar

import gymnasium
from numpy.random import SeedSequence

from skidnav.agents.interface import Agent, AgentConfig, EpisodeTrainingAgent
from skidnav.agents.training import NO_EVALUATION, Evaluation, TrainingLog
from skidnav.agents.wheel_policy import WheelSpeedPolicy
from skidnav.errors import UserError

Env: TypeAlias = gymnasium.Env[Any, Any]
Params: TypeAlias = Mapping[str, Any]
Observation = Literal["discrete", "box"]
"""What an agent learns over: the env's ``Discrete`` state, or a ``Box`` observation."""
Actions = Literal["discrete", "wheel-speeds"]
"""What an agent answers: one of the env's ``Discrete`` actions, or two wheel speeds [rad/s]
(the env's ``action="continuous"``)."""

AgentT = TypeVar("AgentT", bound=Agent)
AgentT_contra = TypeVar("AgentT_contra", bound=Agent, contravariant=True)
AgentT_co = TypeVar("AgentT_co", bound=Agent, covariant=True)


class Maker(Protocol[AgentT_co]):
    """How a family makes agent ``name`` for the unwrapped env ``env`` with ``params`` (an
    ``[[agents]]`` table's), drawing every random number from ``seed``, its episodes cut at
    ``max_steps`` actions. UserError (one line naming the agent) for an env of other spaces or
    bad ``params``."""

    def __call__(
        self, name: str, env: Env, params: Params, seed: SeedSequence, max_steps: int, /
    ) -> AgentT_co: ...


class Trainer(Protocol[AgentT_contra]):
    """How a family trains: ``episodes`` episodes of ``agent`` on ``env`` (the env it was built
    for), each cut at ``max_steps`` actions, the first from a reset with ``seed`` (if given),
    the greedy policy measured by ``evaluation`` after each
    (:func:`skidnav.agents.training.train_episodes`)."""

    def __call__(
        self,
        agent: AgentT_contra,
        env: Env,
        episodes: int,
        /,
        *,
        max_steps: int | None = None,
        evaluation: Evaluation = NO_EVALUATION,
        seed: int | None = None,
    ) -> TrainingLog: ...


Loader: TypeAlias = Callable[[Path, Mapping[str, Any], Env | None], Agent]
"""How a family loads a saved agent: (the ``.json`` path, its parsed content, the env the agent
will act in or None) → the agent; CorruptFileError or UserError in one line naming the file."""
PolicyLoader: TypeAlias = Callable[[Path, Mapping[str, Any]], WheelSpeedPolicy]
"""How a family's saved file becomes a frozen wheel-speed policy on the robot: (the ``.json``
path, its parsed content) → the policy; UserError in one line naming the file."""


@dataclass(frozen=True)
class Family(Generic[AgentT]):
    """One agent family, described once (module doc).

    Attributes:
        name: the family's name (``"tabular"``, ``"linear"``, ``"deep"``, ``"mpc"``,
            ``"policies"``).
        summary: one sentence on what its agents are (the documentation's agent index).
        agents: its agents' registry names, in order; known without importing their modules.
        observation: what they learn over (:data:`Observation`).
        actions: what they answer (:data:`Actions`).
        agent_class: registry name → the agent's class (its module imported now).
        config_class: registry name → the agent's frozen config dataclass.
        make: how one is made for an env (:class:`Maker`).
        train: how one is trained (:class:`Trainer`).
        save_formats: the ``"format"`` values of its saved ``.json`` files.
        load: how a saved file becomes an agent again (:data:`Loader`).
        policy: how a saved file becomes a frozen wheel-speed policy on the robot
            (:data:`PolicyLoader`): by its own wheel speeds, or by those of its greedy discrete
            actions (:mod:`skidnav.agents.discrete_policy`); None when its agents do not act
            frozen on the robot (the tabular family's learn there).
        box_observation: the env's ``Box`` observation for its agents when a config names none.
        extra: the optional dependency its agents need (:mod:`skidnav.extras`), or None.
    """

    name: str
    summary: str
    agents: tuple[str, ...]
    observation: Observation
    actions: Actions
    agent_class: Callable[[str], type[AgentT]]
    config_class: Callable[[str], type[AgentConfig]]
    make: Maker[AgentT]
    train: Trainer[AgentT]
    save_formats: tuple[str, ...]
    load: Loader
    policy: PolicyLoader | None = None
    box_observation: str = "features"
    extra: str | None = None
    documentation: Mapping[str, str] = field(default_factory=dict)
    """Registry name → its page under docs/agents/ (without ``.md``) where it has one of its
    own (the default: the registry name)."""

    def page(self, name: str) -> str:
        """The docs/agents/ page of agent ``name`` (without ``.md``)."""
        return self.documentation.get(name, name)


S = TypeVar("S", bound=gymnasium.Space[Any])


def observation_space(name: str, env: Env, wanted: type[S]) -> S:
    """``env``'s observation space if it is a ``wanted``; UserError naming agent ``name``
    otherwise."""
    space = env.observation_space
    if not isinstance(space, wanted):
        raise UserError(
            f"agent {name!r} learns over a {wanted.__name__} observation, the env gives "
            f"{type(space).__name__} (set [env] observation)"
        )
    return space


def action_space(name: str, env: Env, wanted: type[S]) -> S:
    """``env``'s action space if it is a ``wanted``; UserError naming agent ``name`` otherwise."""
    space = env.action_space
    if not isinstance(space, wanted):
        raise UserError(
            f"agent {name!r} takes {wanted.__name__} actions, the env gives {space} "
            "(set [env] action)"
        )
    return space


def discrete_actions(name: str, env: Env) -> int:
    """The number of ``env``'s discrete actions; UserError for another action space."""
    return int(action_space(name, env, gymnasium.spaces.Discrete).n)


def asks_for(cls: type, argument: str) -> bool:
    """True if the constructor of ``cls`` takes ``argument`` (e.g. ``"task"``: the agent plans
    on the navigation task's own cells)."""
    return argument in inspect.signature(cls).parameters


def constructor_context(cls: type, env: Env | None, params: Params | None = None) -> dict[str, Any]:
    """Extra constructor arguments an agent class asks for by name: the navigation ``task`` of
    ``env``, and for one whose ``params`` ask for ``kinematic_model = "true"`` the env's
    ``true_kinematics`` (None on an env without them: the agent refuses in one line). No other
    agent is handed the truth; nothing without an env."""
    if env is None:
        return {}
    task = getattr(env, "task", None)
    context = {"task": task} if task is not None and asks_for(cls, "task") else {}
    if asks_for(cls, "true_kinematics") and (params or {}).get("kinematic_model") == "true":
        context["true_kinematics"] = getattr(env.unwrapped, "true_kinematics", None)
    return context


def check_wheel_speed_env(env: Env) -> None:
    """ValueError unless ``env`` takes two wheel speeds and observes a ``Box``."""
    space = env.action_space
    if not isinstance(space, gymnasium.spaces.Box) or space.shape != (2,):
        raise ValueError(
            f"expected an env of two wheel speeds (action='continuous'), got actions {space}"
        )
    if not isinstance(env.observation_space, gymnasium.spaces.Box):
        raise ValueError(
            "expected an env observing the pose or the features (observation='pose' or "
            f"'features'), got {env.observation_space}"
        )


def require_wheel_speed_env(name: str, env: Env) -> None:
    """:func:`check_wheel_speed_env` for making agent ``name``: UserError in one line naming
    the agent and the config keys to set."""
    try:
        check_wheel_speed_env(env)
    except ValueError as error:
        raise UserError(f"agent {name!r}: {error} (set [env] action and observation)") from None


def train_own_loop(
    agent: EpisodeTrainingAgent,
    env: Env,
    episodes: int,
    /,
    *,
    max_steps: int | None = None,
    evaluation: Evaluation = NO_EVALUATION,
    seed: int | None = None,
) -> TrainingLog:
    """The :class:`Trainer` of an agent that owns its loop (the deep agents through
    Stable-Baselines3, CMA-ES by generations): its ``train_episodes`` on the env it was built
    with (``env`` is that env, its episodes already cut at ``max_steps``, which also limits the
    greedy rollouts, as in every trainer)."""
    limited = evaluation._replace(max_steps=evaluation.limit(max_steps))
    return agent.train_episodes(episodes, evaluation=limited, seed=seed)
