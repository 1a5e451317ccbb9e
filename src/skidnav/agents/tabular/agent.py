"""The shared tabular core every agent builds on (one TD update, one ε-greedy, one save format).

An agent owns a Q table ``q`` (float64, shape (n_states, n_actions)), a ``numpy.random.Generator``
(every random draw of the agent comes from it), a frozen config and its int64 ``counters``
(:mod:`skidnav.agents.learning`). What one real transition teaches it is one compiled kernel,
registered for the class of its :meth:`TabularAgent.learning_arrays` and given the scalars of
:meth:`TabularAgent.learning_settings`; the step-by-step :meth:`TabularAgent.observe`
and the fused trainer (:mod:`skidnav.agents.tabular.fast_training`) both call it, so there is one
learning
step per agent. Subclasses keeping more state also implement :meth:`TabularAgent.reserve` (room
the kernel cannot allocate) and :meth:`TabularAgent._state_arrays` /
:meth:`TabularAgent._restore_state_arrays`.

Contract (docs/architecture.md): ``act(state)`` ε-greedy with random tie-breaking;
``greedy_action(state)`` the lowest-index greedy action (draws nothing, so evaluation never changes
training); ``observe(state, action, reward, next_state, terminated, truncated, info)`` learns from
one real step (bootstrap on truncation, never on termination); ``end_episode()`` decays ε;
``planning_updates`` counts model-based value updates; ``save(path)`` writes ``path.npz`` and
``path.json`` (never pickle), read back by :func:`skidnav.agents.tabular.registry.load_agent`.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar, Generic

import numpy as np
from typing_extensions import TypeVar

from skidnav.agents.config import QLearningConfig
from skidnav.agents.learning import (
    N_COUNTERS,
    PLANNING_UPDATES,
    STEPS,
    experience_from_info,
    learn,
)
from skidnav.agents.saving import generator_from_state, generator_state, new_save_paths
from skidnav.errors import CorruptFileError, shown
from skidnav.files.atomic import write_atomic, write_npz_atomic
from skidnav.sim.q_values import epsilon_at, epsilon_greedy, greedy_first

logger = logging.getLogger(__name__)

SAVE_FORMAT = "skidnav-agent"
SAVE_VERSION = 3
"""2: a model-based agent's geometry in the JSON (1 held it as 19 numbers in the archive);
3: a model-based agent's planner keeps the wall and free evidence of every cell."""


# The defaults (PEP 696) make a bare ``TabularAgent`` any tabular agent.
ArraysT = TypeVar("ArraysT", bound=tuple[Any, ...], default=tuple[Any, ...])
"""The NamedTuple of arrays an agent's learning step learns into
(:meth:`TabularAgent.learning_arrays`)."""
SettingsT = TypeVar("SettingsT", bound=tuple[Any, ...], default=tuple[Any, ...])
"""The NamedTuple of scalars an agent's learning step reads
(:meth:`TabularAgent.learning_settings`)."""


class TabularAgent(Generic[ArraysT, SettingsT]):
    """Base of every tabular agent: Q table, ε-greedy behaviour, counters, save/load.

    Generic in the NamedTuples its learning step takes: a concrete agent subclasses
    ``TabularAgent[ItsArrays, ItsSettings]`` (a bare ``TabularAgent`` is any agent)."""

    name: ClassVar[str] = "tabular"
    """Registry name of the agent (e.g. ``"dyna-q"``)."""
    config_class: ClassVar[type[QLearningConfig]] = QLearningConfig
    """The frozen config dataclass this agent takes."""

    def __init__(
        self,
        n_states: int,
        n_actions: int,
        config: QLearningConfig | None = None,
        rng: np.random.Generator | None = None,
    ) -> None:
        if n_states < 1 or n_actions < 1:
            raise ValueError(f"expected n_states, n_actions >= 1, got {n_states}, {n_actions}")
        config = self.config_class() if config is None else config
        if not isinstance(config, self.config_class):
            raise TypeError(f"expected a {self.config_class.__name__}, got {type(config).__name__}")
        self.config = config
        self.n_states = int(n_states)
        self.n_actions = int(n_actions)
        self.rng = np.random.default_rng() if rng is None else rng
        self.q = np.full((n_states, n_actions), config.initial_q, dtype=np.float64)
        shape = (n_states, n_actions) if config.alpha_visit_exponent > 0.0 else (1, 1)
        self.visits = np.zeros(shape, dtype=np.int64)
        """Real updates of each pair, int64 (n_states, n_actions), counted only when the step
        size decays with them (``alpha_visit_exponent`` > 0; a (1, 1) placeholder otherwise)."""
        self.counters = np.zeros(N_COUNTERS, dtype=np.int64)
        """Real steps and planning updates, int64 (N_COUNTERS,), as the learning kernel counts."""
        self.episodes = 0
        """Episodes completed (calls to :meth:`end_episode`)."""

    @property
    def steps(self) -> int:
        """Real transitions observed so far."""
        return int(self.counters[STEPS])

    @steps.setter
    def steps(self, value: int) -> None:
        self.counters[STEPS] = value

    @property
    def planning_updates(self) -> int:
        """Value updates made from a model (not from real experience) so far."""
        return int(self.counters[PLANNING_UPDATES])

    @planning_updates.setter
    def planning_updates(self, value: int) -> None:
        self.counters[PLANNING_UPDATES] = value

    @property
    def epsilon(self) -> float:
        """Current exploration rate ``max(ε_min, ε₀ · decay^episodes)``."""
        config = self.config
        return epsilon_at(self.episodes, config.epsilon, config.epsilon_decay, config.epsilon_min)

    def act(self, state: int) -> int:
        """ε-greedy action in ``state`` (ties among the greedy actions broken uniformly)."""
        return int(epsilon_greedy(self.q, int(state), self.epsilon, self.rng))

    def greedy_action(self, state: int) -> int:
        """Greedy action in ``state``: the lowest index among the maxima; draws no random number."""
        return int(greedy_first(self.q, int(state)))

    def observe(
        self,
        state: int,
        action: int,
        reward: float,
        next_state: int,
        terminated: bool,
        truncated: bool = False,
        info: Mapping[str, Any] | None = None,
    ) -> None:
        """Learn from one real step: one call of the learning kernel. ``terminated`` stops the
        bootstrap; ``truncated`` does not (the time limit is not part of the MDP). ``info`` is
        the env's info dict (may be None), read by
        :func:`~skidnav.agents.learning.experience_from_info`.

        Raises:
            ValueError: a state or action outside the Q table.
        """
        state, action, next_state = int(state), int(action), int(next_state)
        if not (0 <= state < self.n_states and 0 <= next_state < self.n_states) or not (
            0 <= action < self.n_actions
        ):
            raise ValueError(f"expected a valid transition, got ({state}, {action}, {next_state})")
        self.reserve(1)
        self.counters[STEPS] += 1
        experience = experience_from_info(state, action, reward, next_state, terminated, info)
        arrays, settings = self.learning_arrays(), self.learning_settings()
        learn(arrays, settings, self.counters, experience, self.rng)

    def learning_arrays(self) -> ArraysT:
        """The NamedTuple of arrays the agent's learning step learns into (its class chooses the
        kernel: :func:`~skidnav.agents.learning.learning_step`); views, never copies, to be
        asked again after :meth:`reserve`, which may reallocate. Subclasses override."""
        raise NotImplementedError

    def learning_settings(self) -> SettingsT:
        """The NamedTuple of scalars the agent's learning step reads. Subclasses override."""
        raise NotImplementedError

    def reserve(self, n_steps: int) -> None:
        """Make room for ``n_steps`` more real steps in every buffer the kernel fills (it cannot
        allocate); nothing for agents whose arrays have a fixed size."""

    def end_episode(self) -> None:
        """Mark the end of an episode (decays ε)."""
        self.episodes += 1

    # --- saving -----------------------------------------------------------------------------

    def _state_arrays(self) -> dict[str, np.ndarray]:
        """Arrays beyond ``q`` to save (names without ``/``); subclasses extend."""
        return {"visits": self.visits} if self.config.alpha_visit_exponent > 0.0 else {}

    def _restore_state_arrays(self, arrays: Mapping[str, np.ndarray]) -> None:
        """Inverse of :meth:`_state_arrays`; raise KeyError/ValueError if something is missing."""
        if self.config.alpha_visit_exponent > 0.0:
            visits = np.asarray(arrays["visits"])
            if visits.shape != self.visits.shape or (visits < 0).any():
                raise ValueError(f"saved visits must be >= 0 of shape {self.visits.shape}")
            self.visits[:] = visits

    def _state_json(self) -> dict[str, Any]:
        """Entries beyond the common ones for the saved JSON (subclasses extend)."""
        return {}

    def save(self, path: str | Path) -> tuple[Path, Path]:
        """Write ``path.npz`` (Q and model arrays) and ``path.json`` (name, config, counters,
        generator state), each atomically (:func:`~skidnav.files.atomic.write_npz_atomic`,
        :func:`~skidnav.files.atomic.write_atomic`): a failure or a kill leaves the old file, never
        a torn one. Returns both paths."""
        npz_path, json_path = new_save_paths(path)
        write_npz_atomic(npz_path, {"q": self.q, **self._state_arrays()}, compress=True)
        meta = {
            "format": SAVE_FORMAT,
            "version": SAVE_VERSION,
            "agent": self.name,
            "n_states": self.n_states,
            "n_actions": self.n_actions,
            "config": self.config.to_dict(),
            "counters": {
                "steps": self.steps,
                "episodes": self.episodes,
                "planning_updates": self.planning_updates,
            },
            "rng": generator_state(self.rng),
            **self._state_json(),
        }
        write_atomic(json_path, json.dumps(meta, indent=1).encode("utf-8"))
        logger.info("saved agent %s to %s", self.name, npz_path)
        return npz_path, json_path

    def _restore(self, meta: Mapping[str, Any], arrays: Mapping[str, np.ndarray]) -> None:
        """Fill a freshly built agent from saved data; CorruptFileError when inconsistent."""
        q = arrays["q"]
        if q.shape != self.q.shape or q.dtype != np.float64:
            raise CorruptFileError(
                f"saved Q table is {q.dtype} of shape {q.shape}, expected float64 of shape "
                f"{self.q.shape}"
            )
        self.q[:] = q
        counters, rng_state = meta["counters"], meta["rng"]
        if not isinstance(counters, Mapping) or not isinstance(rng_state, Mapping):
            raise CorruptFileError("saved counters and generator state must be JSON objects")
        for name in ("steps", "episodes", "planning_updates"):
            value = counters[name]
            if not isinstance(value, int) or value < 0:
                raise CorruptFileError(
                    f"saved counter {name} is {shown(value)}, expected an int >= 0"
                )
            setattr(self, name, value)
        self.rng = generator_from_state(rng_state)
        self._restore_state_arrays(arrays)
