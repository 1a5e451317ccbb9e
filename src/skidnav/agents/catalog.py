"""Every agent by name: the families' descriptors, read in one place.

:data:`FAMILY_MODULES` lists the families; each module defines ``FAMILY``, a
:class:`~skidnav.agents.family.Family` (its agents, what they observe, how one is made, trained,
saved and loaded). :func:`entry` gives the :class:`AgentEntry` of a registered name — its family
and what the runner asks of it — and callers ask it once and use the entry. Every family returns
the same :class:`~skidnav.agents.training.TrainingLog`, and every agent answers
``greedy_action(observation)``, so the runner measures them alike.

Adding a family is one package under :mod:`skidnav.agents` with its ``family.py`` and one line
in :data:`FAMILY_MODULES`. The families are imported by name (:func:`families`), so this module
imports none of them and none imports it.
"""

from __future__ import annotations

import functools
import importlib
from dataclasses import dataclass
from typing import Any, Generic

from numpy.random import SeedSequence

from skidnav.agents.family import AgentT, Env, Family, Params, asks_for, constructor_context
from skidnav.agents.interface import Agent, AgentConfig
from skidnav.agents.training import NO_EVALUATION, Evaluation, TrainingLog
from skidnav.errors import UserError, shown, within
from skidnav.files.configtables import check_types

FAMILY_MODULES: tuple[str, ...] = (
    "skidnav.agents.tabular.family",
    "skidnav.agents.linear.family",
    "skidnav.agents.deep.family",
    "skidnav.agents.mpc.family",
    "skidnav.agents.policies.family",
    "skidnav.agents.classical.family",
)
"""The modules defining each family's ``FAMILY``, in the order agents are listed."""
BOX_OBSERVATIONS = ("pose", "features")
"""The skid-steer env's ``Box`` observations (``observation=``), for the non-tabular agents."""


@functools.cache
def families() -> tuple[Family[Any], ...]:
    """Every family's descriptor, in :data:`FAMILY_MODULES` order (their modules imported now;
    none imports an optional dependency before its agent is asked for)."""
    return tuple(importlib.import_module(module).FAMILY for module in FAMILY_MODULES)


def family(name: str) -> Family[Any]:
    """The family called ``name``; UserError naming the known families otherwise."""
    for described in families():
        if described.name == name:
            return described
    known = ", ".join(f.name for f in families())
    raise UserError(f"unknown agent family {shown(name)}; expected one of {known}")


def agent_names() -> list[str]:
    """Every registered name, family by family, each in its family's order."""
    return [name for described in families() for name in described.agents]


def family_of_format(save_format: object) -> Family[Any] | None:
    """The family whose saved files have the ``"format"`` ``save_format``, or None."""
    for described in families():
        if save_format in described.save_formats:
            return described
    return None


@dataclass(frozen=True)
class BuiltAgent(Generic[AgentT]):
    """A new agent with its family's training bound to it."""

    agent: AgentT
    family: Family[AgentT]

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
        its family trains (:class:`~skidnav.agents.family.Trainer`)."""
        return self.family.train(
            self.agent, env, episodes, max_steps=max_steps, evaluation=evaluation, seed=seed
        )


@dataclass(frozen=True)
class AgentEntry(Generic[AgentT]):
    """One registered agent: its name and its family's descriptor."""

    name: str
    family: Family[AgentT]

    @property
    def observation(self) -> str:
        """What it learns over: ``"discrete"`` or ``"box"``."""
        return self.family.observation

    @property
    def agent_class(self) -> type[AgentT]:
        """The agent's class (its module imported now)."""
        return self.family.agent_class(self.name)

    @property
    def config_class(self) -> type[AgentConfig]:
        """The agent's frozen config dataclass."""
        return self.family.config_class(self.name)

    def config(self, params: Params) -> AgentConfig:
        """The agent's config from ``params`` (e.g. an ``[[agents]]`` table's ``params``),
        validated as a new agent would: by its own checks first (their messages name the
        range), and each value's type (:func:`~skidnav.files.configtables.check_types`: a bool
        or a float its checks let through, a string they trip on); UserError naming the agent
        otherwise. A missing extra is its own UserError, unchanged."""
        config_class, where = self.config_class, f"agent {self.name!r}"
        try:
            config = config_class.from_mapping(dict(params))
        except TypeError as error:  # its checks compared a value of another type: name it
            check_types(config_class, dict(params), where)
            raise within(error, where) from None
        except (ValueError, UserError) as error:  # what is wrong first, then where
            raise within(error, where) from None
        check_types(config_class, dict(params), where)
        return config

    def env_observation(self, requested: object) -> str:
        """The skid-steer env's ``observation`` for this agent when a config asks for
        ``requested`` (its ``[env] observation`` as written, or None): a tabular agent always
        sees the discrete state; the others the requested ``Box`` observation, their family's
        ``box_observation`` by default. UserError when a ``Box`` agent is asked to learn over
        anything else."""
        if self.observation == "discrete":
            return "discrete"
        if requested is None:
            return self.family.box_observation
        if requested not in BOX_OBSERVATIONS:
            raise UserError(
                f"agent {self.name!r} learns over a Box observation: expected [env] observation "
                f"in {', '.join(BOX_OBSERVATIONS)}, got {shown(requested)}"
            )
        return str(requested)

    def asks_for(self, argument: str) -> bool:
        """True if the agent's constructor takes ``argument`` (e.g. ``"task"``: it plans on
        the navigation task's own cells)."""
        return asks_for(self.agent_class, argument)

    def context(self, env: Env, params: Params | None = None) -> dict[str, Any]:
        """Extra constructor arguments the agent asks for by name
        (:func:`~skidnav.agents.family.constructor_context`)."""
        return constructor_context(self.agent_class, env, params)

    def build(
        self, env: Env, params: Params, seed: SeedSequence, max_steps: int
    ) -> BuiltAgent[AgentT]:
        """A new agent for ``env`` (unwrapped) with ``params``, drawing from ``seed``, with its
        training; a deep agent drives ``env`` itself, cut at ``max_steps`` actions per
        episode. UserError when ``env``'s spaces are not the agent's or ``params`` are bad."""
        self.config(params)  # the one check of the params, whoever builds the agent
        return BuiltAgent(self.family.make(self.name, env, params, seed, max_steps), self.family)

    def bind(self, agent: Agent) -> BuiltAgent[AgentT]:
        """``agent`` (of this entry, e.g. loaded from a file) with its family's training;
        TypeError for an agent of another class."""
        cls = self.agent_class
        if not isinstance(agent, cls):
            raise TypeError(f"expected a {cls.__name__} agent, got {type(agent).__name__}")
        return BuiltAgent(agent, self.family)


CatalogEntry = AgentEntry[Any]
"""The entry of an agent of any family."""
CatalogAgent = BuiltAgent[Any]
"""A new agent of any family with its training (:meth:`AgentEntry.build`)."""


def entry(name: str) -> CatalogEntry:
    """The entry of agent ``name``; UserError naming the known agents otherwise."""
    for described in families():
        if name in described.agents:
            return AgentEntry(name, described)
    raise UserError(f"unknown agent {shown(name)}; expected one of {', '.join(agent_names())}")
