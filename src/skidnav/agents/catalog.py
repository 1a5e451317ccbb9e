"""Every agent by name, described once: the one door of the experiment runner.

:func:`entry` gives the :class:`AgentEntry` of a registered name — its family, the observation
it learns over, its config class, how it is built and how it is trained — and callers ask it
once and use the entry. Four families, each with its own registry and protocol
(:mod:`skidnav.agents.interface`):

* **tabular** (:mod:`skidnav.agents.tabular.registry`): a Q table over the env's ``Discrete``
  observation, a :class:`~skidnav.agents.interface.StepLearningAgent` trained by the compiled
  trainer (:func:`~skidnav.agents.fast_training.train_agent_fast`, which runs the plain loop
  itself for envs it cannot drive);
* **linear** (:mod:`skidnav.agents.linear.registry`): tile-coded features of a ``Box``
  observation, a :class:`~skidnav.agents.interface.StepLearningAgent` trained by the plain loop
  (:func:`~skidnav.agents.training.train_agent`);
* **deep** (:data:`DEEP_AGENTS`, the ``deep`` extra, imported only when asked for):
  Stable-Baselines3 owns the loop, and the agent, an
  :class:`~skidnav.agents.interface.EpisodeTrainingAgent`, trains itself by episodes with the
  same greedy evaluations (:meth:`skidnav.agents.deep.common.DeepAgent.train_episodes`);
  ``ppo`` and ``sac`` need the env's ``action="continuous"`` and ``observation="features"``;
* **mpc** (:data:`MPC_AGENTS`): model predictive control of the two wheel speeds through a
  learned model (``mppi-kinematic``, :mod:`skidnav.agents.mpc`), on ``action="continuous"`` and
  a ``Box`` observation (the pose by default), a
  :class:`~skidnav.agents.interface.StepLearningAgent` trained by the plain loop
  (:func:`~skidnav.agents.mpc.training.train_mppi`); its greedy action is its frozen planner's.

Every family returns the same :class:`~skidnav.agents.training.TrainingLog`, and every agent
answers ``greedy_action(observation)``, so the runner measures them alike.
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from types import ModuleType
from typing import TYPE_CHECKING, Any, Generic, Literal, Protocol, TypeAlias, TypeVar

import gymnasium
import numpy as np
from gymnasium.wrappers import TimeLimit
from numpy.random import SeedSequence

from skidnav.agents.fast_training import train_agent_fast
from skidnav.agents.interface import Agent, AgentConfig, EpisodeTrainingAgent, StepLearningAgent
from skidnav.agents.linear.agent import LinearAgent
from skidnav.agents.linear.registry import (
    CONTINUOUS_AGENT_MODULES,
    linear_agent_class,
    make_linear_agent,
)
from skidnav.agents.mpc.agent import AGENT_NAME as MPPI_AGENT_NAME
from skidnav.agents.mpc.agent import MPPIKinematicAgent, make_mppi_agent
from skidnav.agents.mpc.config import MPPIConfig
from skidnav.agents.mpc.training import check_wheel_speed_env, train_mppi
from skidnav.agents.tabular.agent import TabularAgent
from skidnav.agents.tabular.registry import AGENT_MODULES, agent_class, make_agent
from skidnav.agents.training import NO_EVALUATION, Evaluation, TrainingLog, train_agent
from skidnav.errors import UserError, first_line, shown
from skidnav.extras import MissingExtraError, missing_message, require

if TYPE_CHECKING:  # each family's base class satisfies its protocol (checked by mypy)
    from skidnav.agents.deep.common import DeepAgent

    _TABULAR: type[StepLearningAgent] = TabularAgent
    _LINEAR: type[StepLearningAgent] = LinearAgent
    _DEEP: type[EpisodeTrainingAgent] = DeepAgent
    _MPC: type[StepLearningAgent] = MPPIKinematicAgent
    _MPC_CONFIG: type[AgentConfig] = MPPIConfig

DEEP_AGENTS: dict[str, str] = {
    "dqn": "skidnav.agents.deep.dqn",
    "ppo": "skidnav.agents.deep.ppo",
    "sac": "skidnav.agents.deep.sac",
}
"""Registry name → module defining ``AGENT_NAME``, ``AGENT_CLASS`` and ``CONFIG_CLASS``."""
MPC_AGENTS: tuple[str, ...] = (MPPI_AGENT_NAME,)
"""The model predictive controllers (:mod:`skidnav.agents.mpc`)."""

Family = Literal["tabular", "linear", "deep", "mpc"]
Observation = Literal["discrete", "box"]
"""What an agent learns over: the env's ``Discrete`` state, or a ``Box`` observation."""
BOX_OBSERVATIONS = ("pose", "features")
"""The skid-steer env's ``Box`` observations (``observation=``), for the non-tabular agents."""
DEFAULT_BOX_OBSERVATION = "features"
"""The ``Box`` observation of a non-tabular agent whose config names none."""

Env: TypeAlias = gymnasium.Env[Any, Any]
Params: TypeAlias = Mapping[str, Any]
Seeds: TypeAlias = Sequence[int] | None
AgentT = TypeVar("AgentT", bound=Agent)
AgentT_contra = TypeVar("AgentT_contra", bound=Agent, contravariant=True)


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


@dataclass(frozen=True)
class BuiltAgent(Generic[AgentT]):
    """A new agent with its family's training bound to it."""

    agent: AgentT
    trainer: Trainer[AgentT]

    def train(
        self,
        env: Env,
        episodes: int,
        *,
        max_steps: int | None = None,
        evaluation: Evaluation = NO_EVALUATION,
        seed: int | None = None,
    ) -> TrainingLog:
        """Train the agent for ``episodes`` episodes on ``env`` (the env it was built for), as
        its family trains (:class:`Trainer`)."""
        return self.trainer(
            self.agent, env, episodes, max_steps=max_steps, evaluation=evaluation, seed=seed
        )


@dataclass(frozen=True)
class AgentEntry(Generic[AgentT]):
    """One registered agent: its family, what it learns over, its config, how it is built and
    trained. The classes are imported only when asked for (:attr:`agent_class`)."""

    name: str
    family: Family
    observation: Observation
    load_class: Callable[[str], type[AgentT]]
    """The registry's class lookup (imports the agent's module)."""
    load_config_class: Callable[[str], type[AgentConfig]]
    make: Callable[[AgentEntry[AgentT], Env, Params, SeedSequence, int], AgentT]
    """How the family builds the agent of an entry for an unwrapped env with parameters, drawing
    from a seed sequence, its episodes cut at a number of actions."""
    trainer: Trainer[AgentT]
    box_observation: str = DEFAULT_BOX_OBSERVATION
    """The ``Box`` observation of this agent when a config names none (:meth:`env_observation`)."""

    @property
    def agent_class(self) -> type[AgentT]:
        """The agent's class (its module imported now)."""
        return self.load_class(self.name)

    @property
    def config_class(self) -> type[AgentConfig]:
        """The agent's frozen config dataclass."""
        return self.load_config_class(self.name)

    def config(self, params: Params) -> AgentConfig:
        """The agent's config from ``params`` (e.g. an ``[[agents]]`` table's ``params``),
        validated as a new agent would; UserError naming the agent otherwise."""
        try:
            return self.config_class.from_mapping(dict(params))
        except (ValueError, TypeError) as error:
            raise UserError(f"agent {self.name!r}: {first_line(error)}") from None

    def env_observation(self, requested: object) -> str:
        """The skid-steer env's ``observation`` for this agent when a config asks for
        ``requested`` (its ``[env] observation`` as written, or None): a tabular agent always
        sees the discrete state; the others the requested ``Box`` observation, their
        :attr:`box_observation` by default. UserError when a ``Box`` agent is asked to learn over
        anything else."""
        if self.observation == "discrete":
            return "discrete"
        if requested is None:
            return self.box_observation
        if requested not in BOX_OBSERVATIONS:
            raise UserError(
                f"agent {self.name!r} learns over a Box observation: expected [env] observation "
                f"in {', '.join(BOX_OBSERVATIONS)}, got {shown(requested)}"
            )
        return str(requested)

    def asks_for(self, argument: str) -> bool:
        """True if the agent's constructor takes ``argument`` (e.g. ``"task"``: it plans on
        the navigation task's own cells)."""
        return argument in inspect.signature(self.agent_class.__init__).parameters

    def context(self, env: Env, params: Params | None = None) -> dict[str, Any]:
        """Extra constructor arguments the agent asks for by name: the navigation ``task`` of
        ``env``, and for one whose ``params`` ask for ``kinematic_model = "true"`` the env's
        ``true_kinematics`` (None on an env without them: the agent refuses in one line). No
        other agent is handed the truth."""
        task = getattr(env, "task", None)
        context = {"task": task} if task is not None and self.asks_for("task") else {}
        if self.asks_for("true_kinematics") and (params or {}).get("kinematic_model") == "true":
            context["true_kinematics"] = getattr(env.unwrapped, "true_kinematics", None)
        return context

    def build(
        self, env: Env, params: Params, seed: SeedSequence, max_steps: int
    ) -> BuiltAgent[AgentT]:
        """A new agent for ``env`` (unwrapped) with ``params``, drawing from ``seed``, with its
        training; a deep agent drives ``env`` itself, cut at ``max_steps`` actions per
        episode. UserError when ``env``'s spaces are not the agent's or ``params`` are bad."""
        return BuiltAgent(self.make(self, env, params, seed, max_steps), self.trainer)

    def bind(self, agent: Agent) -> BuiltAgent[AgentT]:
        """``agent`` (of this entry, e.g. loaded from a file) with its family's training;
        TypeError for an agent of another class."""
        cls = self.agent_class
        if not isinstance(agent, cls):
            raise TypeError(f"expected a {cls.__name__} agent, got {type(agent).__name__}")
        return BuiltAgent(agent, self.trainer)


CatalogEntry: TypeAlias = (
    AgentEntry[TabularAgent]
    | AgentEntry[LinearAgent]
    | AgentEntry[EpisodeTrainingAgent]
    | AgentEntry[MPPIKinematicAgent]
)
"""The entry of an agent of any family."""
CatalogAgent: TypeAlias = (
    BuiltAgent[TabularAgent]
    | BuiltAgent[LinearAgent]
    | BuiltAgent[EpisodeTrainingAgent]
    | BuiltAgent[MPPIKinematicAgent]
)
"""A new agent of any family with its training (:meth:`AgentEntry.build`)."""


def agent_names() -> list[str]:
    """Every registered name: tabular, linear, deep, mpc, each in registry order."""
    return [*AGENT_MODULES, *CONTINUOUS_AGENT_MODULES, *DEEP_AGENTS, *MPC_AGENTS]


def entry(name: str) -> CatalogEntry:
    """The entry of agent ``name``; UserError naming the known agents otherwise."""
    if name in AGENT_MODULES:
        return _tabular_entry(name)
    if name in CONTINUOUS_AGENT_MODULES:
        return _linear_entry(name)
    if name in DEEP_AGENTS:
        return _deep_entry(name)
    if name in MPC_AGENTS:
        return _mpc_entry(name)
    raise UserError(f"unknown agent {shown(name)}; expected one of {', '.join(agent_names())}")


# --- the families ------------------------------------------------------------------------------

S = TypeVar("S", bound=gymnasium.Space[Any])


def _space(name: str, space: gymnasium.Space[Any], wanted: type[S]) -> S:
    """``space`` (the env's observation space) if it is a ``wanted``; UserError otherwise."""
    if not isinstance(space, wanted):
        raise UserError(
            f"agent {name!r} learns over a {wanted.__name__} observation, the env gives "
            f"{type(space).__name__} (set [env] observation)"
        )
    return space


def _n_actions(name: str, env: Env) -> int:
    """The number of ``env``'s discrete actions; UserError for another action space."""
    space = env.action_space
    if not isinstance(space, gymnasium.spaces.Discrete):
        raise UserError(f"agent {name!r} takes Discrete actions, the env gives {space}")
    return int(space.n)


def _tabular_entry(name: str) -> AgentEntry[TabularAgent]:
    return AgentEntry(
        name, "tabular", "discrete", agent_class, _tabular_config, _make_tabular, train_agent_fast
    )


def _tabular_config(name: str) -> type[AgentConfig]:
    return agent_class(name).config_class


def _make_tabular(
    described: AgentEntry[TabularAgent],
    env: Env,
    params: Params,
    seed: SeedSequence,
    max_steps: int,
) -> TabularAgent:
    name = described.name
    space = _space(name, env.observation_space, gymnasium.spaces.Discrete)
    context = described.context(env, params)
    rng = np.random.default_rng(seed)
    return make_agent(name, int(space.n), _n_actions(name, env), dict(params), rng, **context)


def _linear_entry(name: str) -> AgentEntry[LinearAgent]:
    return AgentEntry(
        name, "linear", "box", linear_agent_class, _linear_config, _make_linear, train_agent
    )


def _linear_config(name: str) -> type[AgentConfig]:
    return linear_agent_class(name).config_class


def _make_linear(
    described: AgentEntry[LinearAgent], env: Env, params: Params, seed: SeedSequence, max_steps: int
) -> LinearAgent:
    name = described.name
    space = _space(name, env.observation_space, gymnasium.spaces.Box)
    context = described.context(env, params)
    rng = np.random.default_rng(seed)
    chosen = _tiled_by_default(env, params)
    return make_linear_agent(name, space, _n_actions(name, env), chosen, rng, **context)


def _tiled_by_default(env: Env, params: Params) -> dict[str, Any]:
    """``params``, with the features a tile coder takes by default on the skid-steer env's
    feature observation when they name no ``dimensions``
    (:meth:`~skidnav.sim.features.PoseFeatures.steering_dimensions`: all 15 default features
    would need ~10^11 tiles); unchanged on any other observation."""
    nav = env.unwrapped
    features: Any = getattr(nav, "features", None)
    tiled = "dimensions" in params or getattr(nav, "observation_kind", None) != "features"
    if tiled or features is None:
        return dict(params)
    return {**params, "dimensions": list(features.steering_dimensions())}


def _deep_entry(name: str) -> AgentEntry[EpisodeTrainingAgent]:
    return AgentEntry(
        name, "deep", "box", _deep_class, _deep_config, _make_deep, _train_by_episodes
    )


def _deep_extra_missing(name: str, error: ModuleNotFoundError) -> UserError:
    return MissingExtraError(missing_message("deep", f"agent {name!r}", str(error.name)))


def _deep_module(name: str) -> ModuleType:
    """The module of deep agent ``name``; UserError when the ``deep`` extra is missing (checked
    before anything is imported, so a config naming the agent is refused up front)."""
    require("deep", f"agent {name!r}")
    try:
        return importlib.import_module(DEEP_AGENTS[name])
    except ModuleNotFoundError as error:
        raise _deep_extra_missing(name, error) from None


def _deep_class(name: str) -> type[EpisodeTrainingAgent]:
    cls: type[EpisodeTrainingAgent] = _deep_module(name).AGENT_CLASS
    return cls


def _deep_config(name: str) -> type[AgentConfig]:
    cls: type[AgentConfig] = _deep_module(name).CONFIG_CLASS
    return cls


def _make_deep(
    described: AgentEntry[EpisodeTrainingAgent],
    env: Env,
    params: Params,
    seed: SeedSequence,
    max_steps: int,
) -> EpisodeTrainingAgent:
    name = described.name
    _space(name, env.observation_space, gymnasium.spaces.Box)
    config = described.config(params)
    deep_seed = int(seed.generate_state(1)[0])  # 32 bits: Stable-Baselines3 seeds legacy NumPy
    try:  # PyTorch and Stable-Baselines3 are imported by the agent's constructor
        agent: EpisodeTrainingAgent = _deep_module(name).AGENT_CLASS(
            TimeLimit(env, max_steps), config, seed=deep_seed
        )
    except ModuleNotFoundError as error:
        raise _deep_extra_missing(name, error) from None
    return agent


def _train_by_episodes(
    agent: EpisodeTrainingAgent,
    env: Env,
    episodes: int,
    /,
    *,
    max_steps: int | None = None,
    evaluation: Evaluation = NO_EVALUATION,
    seed: int | None = None,
) -> TrainingLog:
    """The agent's own loop, on the env it was built with (``env`` is that env, its episodes
    already cut at ``max_steps``, which limits the rollouts as in every trainer)."""
    limited = evaluation._replace(max_steps=evaluation.limit(max_steps))
    return agent.train_episodes(episodes, evaluation=limited, seed=seed)


def _mpc_entry(name: str) -> AgentEntry[MPPIKinematicAgent]:
    return AgentEntry(
        name, "mpc", "box", _mpc_class, _mpc_config, _make_mpc, train_mppi, box_observation="pose"
    )


def _mpc_class(name: str) -> type[MPPIKinematicAgent]:
    return MPPIKinematicAgent


def _mpc_config(name: str) -> type[AgentConfig]:
    return MPPIConfig


def _make_mpc(
    described: AgentEntry[MPPIKinematicAgent],
    env: Env,
    params: Params,
    seed: SeedSequence,
    max_steps: int,
) -> MPPIKinematicAgent:
    """The controller for the navigation env ``env``: it reads the env's robot, discretization,
    goal cell and lidar layout (never its walls or floor), draws from ``seed``. UserError for an
    env of other spaces or bad ``params`` (``kinematic_model = "true"`` among them: the
    simulator offers no coefficients of the model to plan with)."""
    name = described.name
    try:
        check_wheel_speed_env(env)
    except ValueError as error:
        raise UserError(f"agent {name!r}: {error} (set [env] action and observation)") from None
    return make_mppi_agent(env, dict(params), np.random.default_rng(seed))
