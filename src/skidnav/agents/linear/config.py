"""Hyperparameters of the linear agents: frozen dataclasses validated on construction.

They extend the tabular :class:`~skidnav.agents.config.QLearningConfig` (α, γ, ε and its
decay, the initial value, the same checks and ``from_mapping``) with the tile coder:
:class:`LinearConfig` ⊂ :class:`LinearSarsaConfig` and :class:`LinearDynaConfig`.

>>> LinearConfig(tiles=[4, 4, 8]).tiles
(4, 4, 8)
>>> LinearSarsaConfig(lam=1.5)
Traceback (most recent call last):
...
ValueError: expected lam in [0, 1], got 1.5
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from skidnav.agents.config import QLearningConfig, check

MAX_TILINGS = 1024
"""Most tilings of a tile coder."""
MAX_PLANNING_MEMORY = 1_000_000
"""Most visited states Linear Dyna remembers for planning."""
MAX_LINEAR_PLANNING_STEPS = 100_000
"""Most planning updates per real step of Linear Dyna (each costs O(n_features · n_actions))."""


@dataclass(frozen=True)
class LinearConfig(QLearningConfig):
    """Semi-gradient Q-learning on tile-coded features (Sutton & Barto (2018) §10.1, §9.5.4).

    ``alpha`` is the step size per update of q(s, a): each of the ``n_tilings`` active weights
    moves by α / n_tilings times the TD error. ``initial_q`` is the initial q(s, a) of every
    state (each weight starts at ``initial_q / n_tilings``)."""

    n_tilings: int = 8
    """Tilings of the tile coder, in [1, 1024] (the book: a power of 2, at least 4 × dims)."""
    tiles: tuple[int, ...] = (4,)
    """Tiles per dimension across the observation's bounds: one count for every dimension, or
    one per tiled dimension, each ≥ 1 (a list is stored as a tuple)."""
    dimensions: tuple[int, ...] = ()
    """Indices of the observation's dimensions to tile jointly (empty: all). A coder's size
    grows as Π(tiles + 1): a 15-dimensional observation is better tiled on a few of its
    dimensions (e.g. the goal's distance and bearing)."""

    def __post_init__(self) -> None:
        super().__post_init__()
        check(
            self.alpha_visit_exponent == 0.0,
            "alpha_visit_exponent 0 (visit counts are tabular)",
            self.alpha_visit_exponent,
        )
        check(
            isinstance(self.n_tilings, int) and 1 <= self.n_tilings <= MAX_TILINGS,
            f"an integer n_tilings in [1, {MAX_TILINGS}]",
            self.n_tilings,
        )
        tiles = tuple(self.tiles) if isinstance(self.tiles, list | tuple) else ()
        check(
            bool(tiles) and all(isinstance(n, int) and n >= 1 for n in tiles),
            "tiles as a non-empty list of integers >= 1",
            self.tiles,
        )
        object.__setattr__(self, "tiles", tiles)
        dimensions = tuple(self.dimensions) if isinstance(self.dimensions, list | tuple) else None
        check(
            dimensions is not None
            and all(isinstance(i, int) and i >= 0 for i in dimensions)
            and len(set(dimensions)) == len(dimensions),
            "dimensions as a list of distinct integers >= 0",
            self.dimensions,
        )
        object.__setattr__(self, "dimensions", dimensions)

    def dimensions_of(self, n_dims: int) -> np.ndarray:
        """The tiled dimensions of an observation of ``n_dims`` dimensions, int64 (m,): all of
        them if :attr:`dimensions` is empty; ValueError if one is out of range."""
        if not self.dimensions:
            return np.arange(n_dims, dtype=np.int64)
        if max(self.dimensions) >= n_dims:
            raise ValueError(
                f"expected dimensions below {n_dims} for a {n_dims}-dimensional observation, "
                f"got {max(self.dimensions)}"
            )
        return np.array(self.dimensions, dtype=np.int64)

    def tiles_for(self, n_dims: int) -> np.ndarray:
        """The tiles per dimension for ``n_dims`` tiled dimensions, int64 (n_dims,);
        ValueError if :attr:`tiles` has neither 1 nor ``n_dims`` entries."""
        if len(self.tiles) not in (1, n_dims):
            raise ValueError(
                f"expected 1 or {n_dims} tile counts for {n_dims} tiled dimensions, "
                f"got {len(self.tiles)}"
            )
        return np.broadcast_to(np.array(self.tiles, dtype=np.int64), (n_dims,)).copy()


@dataclass(frozen=True)
class LinearSarsaConfig(LinearConfig):
    """Sarsa(λ) with replacing traces on tile-coded features (Sutton & Barto (2018) §12.7)."""

    lam: float = 0.9
    """Trace-decay parameter λ in [0, 1] (0: one-step Sarsa)."""

    def __post_init__(self) -> None:
        super().__post_init__()
        check(0.0 <= self.lam <= 1.0, "lam in [0, 1]", self.lam)


@dataclass(frozen=True)
class LinearDynaConfig(LinearConfig):
    """Linear Dyna (Sutton, Szepesvári, Geramifard & Bowling 2008) with action values."""

    planning_steps: int = 5
    """Planning updates after each real step (0 = linear Q-learning, bit for bit)."""
    model_alpha: float = 0.5
    """Step size of the model's LMS updates, in (0, 1] (divided by n_tilings like alpha)."""
    planning_memory: int = 1000
    """Most recently visited states whose features planning draws from, ≥ 1."""

    def __post_init__(self) -> None:
        super().__post_init__()
        check(
            isinstance(self.planning_steps, int)
            and 0 <= self.planning_steps <= MAX_LINEAR_PLANNING_STEPS,
            f"an integer planning_steps in [0, {MAX_LINEAR_PLANNING_STEPS:,}]",
            self.planning_steps,
        )
        check(0.0 < self.model_alpha <= 1.0, "model_alpha in (0, 1]", self.model_alpha)
        check(
            isinstance(self.planning_memory, int)
            and 1 <= self.planning_memory <= MAX_PLANNING_MEMORY,
            f"an integer planning_memory in [1, {MAX_PLANNING_MEMORY:,}]",
            self.planning_memory,
        )
