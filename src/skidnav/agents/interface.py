"""What an agent answers, by family: the typed contract the catalog and the runner rely on.

* :class:`Agent` — every agent: its registry ``name``, ``greedy_action(observation)`` (the
  greedy evaluation, :func:`skidnav.agents.greedy.greedy_evaluation`) and ``save(path)``
  (``.npz`` + ``.json``, never pickle);
* :class:`StepLearningAgent` — the tabular, linear and model-predictive (``mppi-kinematic``)
  agents, which a loop drives one real step at a time: ``act``, ``observe``, ``end_episode``
  and the ``planning_updates`` counter, as :func:`skidnav.agents.training.train_agent` (and,
  for the tabular ones, the compiled :func:`skidnav.agents.tabular.fast_training.train_agent_fast`)
  calls them;
* :class:`EpisodeTrainingAgent` — the deep agents, which own their loop and train by episodes
  (``train_episodes``) with the same :class:`~skidnav.agents.training.Evaluation` and the same
  :class:`~skidnav.agents.training.TrainingLog`;
* :class:`AgentConfig` — an agent's frozen config dataclass, validated from a mapping (a TOML
  table, a saved agent's JSON).

The protocols are structural: the families' base classes
(:class:`~skidnav.agents.tabular.agent.TabularAgent`,
:class:`~skidnav.agents.linear.agent.LinearAgent`,
:class:`~skidnav.agents.deep.common.DeepAgent`,
:class:`~skidnav.agents.mpc.agent.MPPIKinematicAgent`) satisfy them without naming them, which mypy
checks in :mod:`skidnav.agents.catalog`; ``isinstance`` works too (runtime-checkable, by the
presence of the members only).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar, Protocol, Self, runtime_checkable

from skidnav.agents.greedy import Greedy
from skidnav.agents.training import NO_EVALUATION, Evaluation, Learner, TrainingLog


@runtime_checkable
class Agent(Greedy, Protocol):
    """What every agent answers: its registry name, its greedy action at an observation (an int
    for ``Discrete`` actions, wheel speeds for the ``Box`` actions of ``ppo`` and ``sac``) and
    how it saves itself (``path.npz`` and ``path.json``; both paths returned)."""

    name: ClassVar[str]

    def save(self, path: str | Path) -> tuple[Path, Path]: ...


@runtime_checkable
class StepLearningAgent(Learner, Agent, Protocol):
    """An agent a loop trains step by step (tabular and linear): ε-greedy ``act(state)``,
    ``observe(state, action, reward, next_state, terminated, truncated, info)`` after each real
    step, ``end_episode()`` after each episode, and the model-based updates made so far
    (``planning_updates``). A state is what :func:`skidnav.agents.greedy.as_state` makes of
    an observation."""


@runtime_checkable
class EpisodeTrainingAgent(Agent, Protocol):
    """An agent that trains itself by whole episodes on the env it was built for (deep)."""

    def train_episodes(
        self, episodes: int, *, evaluation: Evaluation = NO_EVALUATION, seed: int | None = None
    ) -> TrainingLog:
        """Learn for ``episodes`` more episodes (the first from a reset with ``seed``, if
        given), the greedy policy measured by ``evaluation`` after each; the per-episode log."""
        ...


class AgentConfig(Protocol):
    """An agent's config: a frozen dataclass whose fields are checked on construction."""

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any]) -> Self:
        """The config of a mapping of its fields; ValueError or TypeError (one line) for an
        unknown key or a bad value."""
        ...
