"""The shared core of the linear agents on continuous observations (docs/agents/linear-q.md).

An agent tile-codes a float64 observation (shape (k,), inside the bounds ``low``/``high`` of a
``Box``; all its dimensions, or those its config names) into ``n_tilings`` active features
(:mod:`skidnav.agents.linear.tile_coding`) and keeps action values linear in them: weights ``w``,
float64 (n_actions, n_features), ``q(s, a) = Σ w[a, active features of s]``. Every random draw
comes from its ``numpy.random.Generator``; the updates are compiled kernels
(:mod:`skidnav.agents.linear.updates`).

Contract (as the tabular agents', on observations): ``act(obs)`` ε-greedy with uniform tie-breaking
— except right after ``observe`` of a non-terminal step whose agent already chose the next action
(Sarsa(λ) needs a′ for its update): then ``act(next_obs)`` returns that action, so behaviour and
update agree; ``greedy_action(obs)`` the lowest-index greedy action (draws nothing);
``observe(obs, action, reward, next_obs, terminated, truncated, info)`` learns from one real step
(bootstraps unless terminated, so a time limit still bootstraps; the signature of
:class:`skidnav.agents.training.Learner`); ``end_episode()`` decays ε and forgets the episode (the
chosen next action, eligibility traces); ``save(path)`` writes ``path.npz`` and ``path.json``
(never pickle), read back by :func:`skidnav.agents.linear.registry.load_linear_agent`.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from skidnav.agents.linear.config import LinearConfig
from skidnav.agents.linear.tile_coding import active_tiles, check_coder
from skidnav.agents.linear.updates import choose_action, greedy_linear
from skidnav.agents.saving import generator_from_state, generator_state, new_save_paths
from skidnav.errors import CorruptFileError, shown
from skidnav.files.atomic import write_atomic, write_npz_atomic
from skidnav.sim.q_values import epsilon_at

logger = logging.getLogger(__name__)

SAVE_FORMAT = "skidnav-linear-agent"
SAVE_VERSION = 2
"""2: ``linear-dyna-kinematic`` keeps the wall and free evidence of every cell."""
MAX_ACTIONS = 1024
"""Most actions a linear agent may have."""
MAX_WEIGHT_BYTES = 256 * 2**20
"""Largest weight array [bytes]: n_actions · n_features · 8 ≤ 256 MiB, checked before it is
allocated (so a saved file cannot make the reader allocate more)."""
COUNTERS = ("steps", "episodes", "planning_updates")


class LinearAgent:
    """Base of the linear agents: tile coder, weights, ε-greedy behaviour, counters, save/load.

    Args:
        low: the observation's lower bounds (a ``Box``'s ``low``), float (k,), finite.
        high: its upper bounds (the ``Box``'s ``high``), float (k,), finite, ``high > low``.
        n_actions: size of the discrete action space.
        config: the agent's config (defaults if None).
        rng: the generator of every random draw (a fresh unseeded one if None).
    """

    name: ClassVar[str] = "linear"
    config_class: ClassVar[type[LinearConfig]] = LinearConfig

    def __init__(
        self,
        low: np.ndarray,
        high: np.ndarray,
        n_actions: int,
        config: LinearConfig | None = None,
        rng: np.random.Generator | None = None,
    ) -> None:
        config = self.config_class() if config is None else config
        if not isinstance(config, self.config_class):
            raise TypeError(f"expected a {self.config_class.__name__}, got {type(config).__name__}")
        if not (isinstance(n_actions, int | np.integer) and 1 <= n_actions <= MAX_ACTIONS):
            raise ValueError(f"expected n_actions in [1, {MAX_ACTIONS}], got {shown(n_actions)}")
        self.config, self.n_actions = config, int(n_actions)
        self.low = np.array(low, dtype=np.float64).ravel()
        self.high = np.array(high, dtype=np.float64).ravel()
        if self.low.shape != self.high.shape:
            raise ValueError(
                f"expected low and high of one shape, got {self.low.shape}, {self.high.shape}"
            )
        self.dimensions = config.dimensions_of(self.low.size)
        """Indices of the observation's dimensions that are tiled, int64 (m,)."""
        self._coded_low, self._coded_high = self.low[self.dimensions], self.high[self.dimensions]
        self.tiles = config.tiles_for(self.dimensions.size)
        self.n_features = check_coder(
            self._coded_low, self._coded_high, self.tiles, config.n_tilings
        )
        self._check_sizes()
        self.rng = np.random.default_rng() if rng is None else rng
        self.w = np.full((self.n_actions, self.n_features), config.initial_q / config.n_tilings)
        self.steps = self.episodes = self.planning_updates = 0
        self._tiles = np.zeros(config.n_tilings, dtype=np.int64)
        self._next_tiles = np.zeros(config.n_tilings, dtype=np.int64)
        self._values = np.zeros((1, self.n_actions))
        self._chosen: tuple[np.ndarray, int] | None = None
        """(next observation, action) chosen by the last update, returned by the next act."""
        self._allocate()

    def _allocate(self) -> None:
        """Allocate a subclass's own arrays (traces, models), once the base ones exist and
        :meth:`_check_sizes` has passed. Nothing here."""

    def _check_sizes(self) -> None:
        """ValueError if the agent's arrays would exceed their bounds; called before any is
        allocated (subclasses with more arrays extend it)."""
        weight_bytes = self.n_actions * self.n_features * 8
        if weight_bytes > MAX_WEIGHT_BYTES:
            raise ValueError(
                f"expected weights of at most {MAX_WEIGHT_BYTES:,} bytes, got {weight_bytes:,}"
            )

    @property
    def epsilon(self) -> float:
        """Current exploration rate ``max(ε_min, ε₀ · decay^episodes)``."""
        config = self.config
        return epsilon_at(self.episodes, config.epsilon, config.epsilon_decay, config.epsilon_min)

    @property
    def step_size(self) -> float:
        """α / n_tilings: the step of each active weight."""
        return float(self.config.alpha) / self.config.n_tilings

    def features(self, observation: Any, out: np.ndarray | None = None) -> np.ndarray:
        """The active features of ``observation`` (int64 (n_tilings,), into ``out`` if given);
        ValueError if it is not a finite vector of the bounds' length."""
        obs = np.asarray(observation, dtype=np.float64)
        if obs.shape != self.low.shape or not np.isfinite(obs).all():
            raise ValueError(
                f"expected a finite observation of shape {self.low.shape}, got {shown(obs)}"
            )
        out = np.zeros(self.config.n_tilings, dtype=np.int64) if out is None else out
        active_tiles(obs[self.dimensions], self._coded_low, self._coded_high, self.tiles, out)
        return out

    def act(self, observation: Any) -> int:
        """ε-greedy action (ties broken uniformly), or the action the last update chose for
        this observation (see the module's contract)."""
        chosen, self._chosen = self._chosen, None
        if chosen is not None and np.array_equal(chosen[0], observation):
            return chosen[1]
        tiles = self.features(observation, self._tiles)
        return int(choose_action(self.w, tiles, self._values, self.epsilon, self.rng))

    def greedy_action(self, observation: Any) -> int:
        """The lowest-index greedy action; draws no random number."""
        return int(greedy_linear(self.w, self.features(observation, self._tiles), self._values))

    def q_values(self, observation: Any) -> np.ndarray:
        """q(observation, ·), float64 (n_actions,)."""
        values: np.ndarray = self.w[:, self.features(observation)].sum(axis=1)
        return values

    def observe(
        self,
        observation: Any,
        action: int,
        reward: float,
        next_observation: Any,
        terminated: bool,
        truncated: bool = False,
        info: dict[str, Any] | None = None,
    ) -> None:
        """Learn from one real step (bootstraps on ``next_observation`` unless ``terminated``;
        a truncated step bootstraps too). The signature of the training loop's ``Learner``
        (:mod:`skidnav.agents.training`); ``info`` is not used."""
        action = int(action)
        if not 0 <= action < self.n_actions:
            raise ValueError(f"expected an action in [0, {self.n_actions}), got {action}")
        tiles = self.features(observation, self._tiles)
        next_tiles = self.features(next_observation, self._next_tiles)
        self.steps += 1
        self._chosen = None
        next_action = self._learn(tiles, action, float(reward), next_tiles, bool(terminated))
        if next_action is not None:
            self._chosen = (np.array(next_observation, dtype=np.float64), next_action)

    def _learn(
        self,
        tiles: np.ndarray,
        action: int,
        reward: float,
        next_tiles: np.ndarray,
        terminated: bool,
    ) -> int | None:
        """The agent's update; returns the next action if the update chose it. Subclasses."""
        raise NotImplementedError

    def end_episode(self) -> None:
        """Mark the end of an episode: decays ε, forgets the chosen next action."""
        self.episodes += 1
        self._chosen = None

    # --- saving -----------------------------------------------------------------------------

    def state_arrays(self) -> dict[str, np.ndarray]:
        """Every array the agent saves (``w`` and the subclass's), by name."""
        return {"w": self.w}

    def save(self, path: str | Path) -> tuple[Path, Path]:
        """Write ``path.npz`` (arrays) and ``path.json`` (name, bounds, config, counters,
        generator state), each atomically. Returns both paths."""
        npz_path, json_path = new_save_paths(path)
        write_npz_atomic(npz_path, self.state_arrays(), compress=True)
        meta = {
            "format": SAVE_FORMAT,
            "version": SAVE_VERSION,
            "agent": self.name,
            "low": self.low.tolist(),
            "high": self.high.tolist(),
            "n_actions": self.n_actions,
            "config": self.config.to_dict(),
            "counters": {name: getattr(self, name) for name in COUNTERS},
            "rng": generator_state(self.rng),
            **self._context_json(),
        }
        write_atomic(json_path, json.dumps(meta, indent=1).encode("utf-8"))
        logger.info("saved agent %s to %s", self.name, npz_path)
        return npz_path, json_path

    def _context_json(self) -> dict[str, Any]:
        """Extra JSON fields of a saved agent: what its constructor needs beyond the bounds,
        actions and config (read back by :meth:`context_from_json`). None here."""
        return {}

    @classmethod
    def context_from_json(cls, meta: Mapping[str, Any]) -> dict[str, Any]:
        """The constructor's keyword arguments from a saved JSON (:meth:`_context_json`);
        ValueError when they are malformed. None here."""
        return {}

    def restore(
        self, counters: Mapping[str, Any], rng_state: Mapping[str, Any], arrays: Any
    ) -> None:
        """Fill a freshly built agent from checked saved data (arrays of the shapes and dtypes
        of :meth:`state_arrays`); CorruptFileError when a value is out of range."""
        for name in COUNTERS:
            value = counters[name]
            if not (isinstance(value, int) and not isinstance(value, bool) and value >= 0):
                raise CorruptFileError(f"saved counter {name} is {shown(value)}, expected an int")
            setattr(self, name, value)
        for name, array in self.state_arrays().items():
            if array.dtype.kind == "f" and not np.isfinite(arrays[name]).all():
                raise CorruptFileError(f"saved array {name!r} holds NaN or infinite values")
            array[...] = arrays[name]
        self.rng = generator_from_state(rng_state)
